# Enter the project's environment:  source env.sh
# It activates .venv (pinned Python packages over Debian's ROS 1) and the
# catkin devel space, adds rosbash (roscd, rosls, rosed and tab completion),
# puts env/bin (catkin_make and rosdep for this machine) first on PATH, and
# keeps ROS on this machine unless you say otherwise.
_flatsim_top=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
if [ ! -f "$_flatsim_top/catkin_ws/devel/setup.bash" ]; then
  echo "env.sh: the workspace is not built yet; run $_flatsim_top/setup.sh first" >&2
  unset _flatsim_top
  return 1 2>/dev/null || exit 1
fi
# shellcheck disable=SC1091
source "$_flatsim_top/.venv/bin/activate"
# shellcheck disable=SC1091
source "$_flatsim_top/catkin_ws/devel/setup.bash"
# Debian installs rosbash's shell functions as a completion file rather than as
# a catkin environment hook, so nothing sources it unless we do.
if [ -n "${BASH_VERSION:-}" ] && [ -f /usr/share/bash-completion/completions/rosbash ]; then
  # shellcheck disable=SC1091
  source /usr/share/bash-completion/completions/rosbash
fi
case ":$PATH:" in
  *":$_flatsim_top/env/bin:"*) ;;
  *) export PATH="$_flatsim_top/env/bin:$PATH" ;;
esac
# ROS 1 has no authentication: by default every node and the master listen on
# loopback only. Set ROS_IP (or ROS_HOSTNAME) yourself to open up to other machines.
if [ -z "${ROS_IP:-}" ] && [ -z "${ROS_HOSTNAME:-}" ]; then
  export ROS_HOSTNAME=localhost
fi
export ROS_MASTER_URI=${ROS_MASTER_URI:-http://localhost:11311}
echo "env.sh: ROS_HOSTNAME=${ROS_HOSTNAME:-} ROS_IP=${ROS_IP:-} ROS_MASTER_URI=$ROS_MASTER_URI" \
     "(loopback only unless you set ROS_IP; see docs/course.md, 'Two machines')" >&2
unset _flatsim_top
