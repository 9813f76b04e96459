#!/usr/bin/env bash
# The one install path for the README, CI and the Docker image.
# Idempotent: every step checks whether its work is done and skips it if so.
#   ./setup.sh                 install what is missing and build the workspace
#   ./setup.sh --opt-ros[=DIR] also make the course's `source /opt/ros/noetic/setup.bash`
#                              (or DIR/setup.bash) enter this environment
# Enter the environment afterwards with:  source env.sh
set -euo pipefail

TOP=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
VENV="$TOP/.venv"
WS="$TOP/catkin_ws"
OPT_ROS=""
for arg in "$@"; do
  case "$arg" in
    --opt-ros) OPT_ROS=/opt/ros/noetic ;;
    --opt-ros=*) OPT_ROS=${arg#--opt-ros=} ;;
    *) echo "usage: ./setup.sh [--opt-ros[=DIR]]" >&2; exit 2 ;;
  esac
done

# Debian's own ROS 1 (Noetic) packages; Gazebo is not among them, flatsim stands in.
APT_PACKAGES=(
  ros-core-dev python3-rostest rosbash ros-robot-state-publisher liburdfdom-tools
  joint-state-publisher python3-tf2-ros python3-nav-msgs python3-std-srvs
  python3-visualization-msgs catkin-lint rviz ros-image-view xvfb
  python3-venv cmake g++ iproute2 procps
  # What students' own packages build and run against, with every Debian
  # package that rosdep's rule for each key names (so `rosdep check` agrees):
  # cv_bridge, image_transport, tf, tf2_ros, nodelet, image_view, and catkin's
  # and robot_state_publisher's development halves.
  libcv-bridge-dev python3-cv-bridge libimage-transport-dev image-transport-tools
  libtf-dev python3-tf tf-tools libtf2-ros-dev
  libnodelet-dev libnodeletlib-dev libnodeletlib-tools python3-nodelet
  libimage-view-dev python3-image-view libgtest-dev libgmock-dev librobot-state-publisher-dev
  # gazebo_msgs' SetJointTrajectory carries a trajectory_msgs message.
  python3-trajectory-msgs
  # The rest of what rosdep's rules name for this workspace's package.xmls
  # (pip's numpy, OpenCV and pytest still win inside .venv).
  librviz-dev python3-topic-tools ros-tf2-msgs python3-opencv python3-pytest python3-rosdep2
  # turtlesim: actionlib for its RotateAbsolute action, Tk for its window
  libactionlib-msgs-dev python3-actionlib python3-actionlib-msgs python3-tk
  # The grader runs untrusted submissions in a sandbox.
  bubblewrap
  # Tests check the worlds and models flatsim writes against the SDF specification
  # files and libsdformat's own checks (no PyPI package validates SDF).
  sdformat-sdf libsdformat12-12
  # grade --slurm submits to Slurm; its test runs a one-node cluster of this machine.
  slurm-wlm munge
  # The studio's page: three.js from npm (npm below), and the browser its tests drive.
  nodejs chromium
)

step=""
hint=""
say() { printf '[setup] %s\n' "$*"; }
begin() { step=$1; hint=$2; say "$step"; }
on_error() {
  printf '\n[setup] FAILED at step: %s\n[setup] what to do: %s\n' "$step" "$hint" >&2
}
trap on_error ERR

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

missing_apt_packages() {
  local pkg
  for pkg in "${APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}\n' "$pkg" 2>/dev/null | grep -q '^install ok installed$' || echo "$pkg"
  done
}

begin "1/7 Debian packages (ROS 1, rviz, Xvfb)" \
  "check that this is Debian 12 (bookworm) with network access to its package mirror, and that you are root or may use sudo; then run ./setup.sh again"
mapfile -t missing < <(missing_apt_packages)
# Debian's npm, unless the nodejs installed brings its own (NodeSource's conflicts with it).
command -v npm > /dev/null || missing+=(npm)
if [ "${#missing[@]}" -eq 0 ]; then
  say "    all ${#APT_PACKAGES[@]} packages installed, skipping"
else
  say "    installing: ${missing[*]}"
  as_root apt-get update -q
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

begin "2/7 Python virtual environment in .venv" \
  "remove .venv (rm -rf .venv) and run ./setup.sh again; the venv must be made from /usr/bin/python3 so Debian's rospy stays importable"
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c 'import rospy' 2>/dev/null; then
  say "    .venv exists and sees Debian's rospy, skipping"
else
  rm -rf "$VENV"
  /usr/bin/python3 -m venv --system-site-packages "$VENV"
fi

begin "3/7 pinned Python packages (requirements.txt)" \
  "read pip's message above; if a download failed, check access to PyPI and run ./setup.sh again"
req_hash=$(sha256sum "$TOP/requirements.txt" | cut -d' ' -f1)
if [ "$(cat "$VENV/.requirements.sha256" 2>/dev/null)" = "$req_hash" ]; then
  say "    requirements unchanged since last install, skipping"
else
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -r "$TOP/requirements.txt"
  echo "$req_hash" > "$VENV/.requirements.sha256"
fi

begin "4/7 catkin_make in catkin_ws" \
  "read the CMake error above (usually a package.xml/CMakeLists.txt mistake); then run ./setup.sh again"
# Python sources are used in place from src/, so only the build files and
# message definitions decide whether catkin_make has work to do.
# So do env/catkin_make.py and the CMake file it adds to every package.
build_hash=$( (cd "$WS/src" && find . \( -name package.xml -o -name CMakeLists.txt -o -name setup.py \
  -o -name '*.srv' -o -name '*.msg' -o -name '*.action' \) -type f | LC_ALL=C sort | xargs sha256sum;
  cd "$TOP/env" && sha256sum catkin_make.py cmake/*.cmake) | sha256sum | cut -d' ' -f1)
if [ -f "$WS/devel/setup.bash" ] && [ "$(cat "$WS/build/.inputs.sha256" 2>/dev/null)" = "$build_hash" ]; then
  say "    workspace built and its build files unchanged, skipping"
else
  # catkin writes the interpreter it finds into the devel space; it must be the venv's.
  (
    # shellcheck disable=SC1091
    source "$VENV/bin/activate"
    # This workspace sits on Debian's ROS alone, whatever the calling shell has sourced.
    unset CMAKE_PREFIX_PATH ROS_PACKAGE_PATH
    cd "$WS"
    # Through env/bin/catkin_make, as a student's terminal and the tests build.
    "$TOP/env/bin/catkin_make" -DPYTHON_EXECUTABLE="$VENV/bin/python" -DCATKIN_ENABLE_TESTING=ON
  )
  echo "$build_hash" > "$WS/build/.inputs.sha256"
fi
# `source env.sh --student` sources catkin_ws/devel_platform, devel without the project's
# solutions (my_robot, ball_chaser, simple_arm); it follows devel's changes.
/usr/bin/python3 -S "$TOP/env/platform_devel.py" --if-stale > /dev/null

begin "5/7 compile flatsim's sensor kernels (numba caches them beside their sources)" \
  "read the numba error above; ./setup.sh again retries, and the simulator would compile them at its first frame"
# numba checks its own cache, so this takes about a second when nothing changed.
outcome=$(PYTHONPATH="$WS/src/flatsim/src" "$VENV/bin/python" -m flatsim.sensors.precompile)
say "$outcome"

begin "6/7 rosdep rules for this machine (offline: Debian's ROS packages, the stand-ins, system libraries)" \
  "read rosdep's message above; env/rosdep_rules.py writes the rules into .rosdep, which you may delete and rebuild"
outcome=$(/usr/bin/python3 "$TOP/env/rosdep_rules.py")
say "    $outcome"

begin "7/7 three.js for the studio (npm ci in catkin_ws/src/flatsim/studio_web)" \
  "read npm's message above; if a download failed, check access to the npm registry and run ./setup.sh again"
web="$WS/src/flatsim/studio_web"
lock_hash=$(sha256sum "$web/package-lock.json" | cut -d' ' -f1)
if [ -d "$web/node_modules/three" ] && [ "$(cat "$web/node_modules/.lock.sha256" 2>/dev/null)" = "$lock_hash" ]; then
  say "    node_modules matches package-lock.json, skipping"
else
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
  echo "$lock_hash" > "$web/node_modules/.lock.sha256"
  say "    installed three $(sed -n 's/.*"version": "\(.*\)".*/\1/p' "$web/node_modules/three/package.json" | head -n 1)"
fi

if [ -n "$OPT_ROS" ]; then
  begin "extra: $OPT_ROS/setup.bash enters this environment (--opt-ros)" \
    "$OPT_ROS/setup.bash belongs to another ROS install; remove it yourself if you want this one there"
  marker="# Written by $TOP/setup.sh --opt-ros"
  if [ -f "$OPT_ROS/setup.bash" ] && [ "$(head -n 1 "$OPT_ROS/setup.bash")" = "$marker" ]; then
    say "    $OPT_ROS/setup.bash already enters $TOP, skipping"
  elif [ -e "$OPT_ROS/setup.bash" ]; then
    false
  else
    as_root mkdir -p "$OPT_ROS"
    printf '%s\n%s\n%s\n%s\n' "$marker" \
      "# The course starts each terminal with \`source $OPT_ROS/setup.bash\`; here that enters" \
      "# the Go Chase It environment (Debian's ROS 1 with flatsim). Delete this file to undo." \
      "source '$TOP/env.sh'" | as_root tee "$OPT_ROS/setup.bash" > /dev/null
    say "    wrote $OPT_ROS/setup.bash (it sources $TOP/env.sh)"
  fi
fi

trap - ERR
say "done. Enter the environment with:  source env.sh"
