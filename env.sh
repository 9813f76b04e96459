# Enter the project's environment:  source env.sh
# It activates .venv (pinned Python packages over Debian's ROS 1) and the
# catkin devel space, adds rosbash (roscd, rosls, rosed and tab completion),
# puts env/bin (catkin_make and rosdep for this machine) first on PATH, and
# keeps ROS on this machine unless you say otherwise.
#
#   source env.sh --student   the same platform without the project's own my_robot,
#                             ball_chaser and simple_arm (catkin_ws/devel_platform, made
#                             by env/platform_devel.py): only yours are found
_flatsim_top=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# A script that sources this without arguments passes its own on: only --student counts.
_flatsim_devel="$_flatsim_top/catkin_ws/devel"
case "${1:-}" in
  --student) _flatsim_devel="$_flatsim_top/catkin_ws/devel_platform" ;;
  -*) echo "env.sh: unknown option ${1} (the one option is --student); entering the default environment" >&2 ;;
esac
if [ ! -f "$_flatsim_top/catkin_ws/devel/setup.bash" ]; then
  echo "env.sh: the workspace is not built yet; run $_flatsim_top/setup.sh first" >&2
  unset _flatsim_top _flatsim_devel
  return 1 2>/dev/null || exit 1
fi
# The view follows the devel space: made again after a catkin_make changed what devel holds.
# -S: it needs only the standard library, and site's start-up would double its time.
if [ "$_flatsim_devel" != "$_flatsim_top/catkin_ws/devel" ] \
   && ! /usr/bin/python3 -S "$_flatsim_top/env/platform_devel.py" --if-stale > /dev/null \
   && [ ! -f "$_flatsim_devel/.catkin" ]; then
  unset _flatsim_top _flatsim_devel
  return 1 2>/dev/null || exit 1
fi
# shellcheck disable=SC1091
source "$_flatsim_top/.venv/bin/activate"
# shellcheck disable=SC1091
source "$_flatsim_devel/setup.bash"
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
if [ "$_flatsim_devel" != "$_flatsim_top/catkin_ws/devel" ]; then
  echo "env.sh: student mode: the project's my_robot, ball_chaser and simple_arm are hidden;" \
       "yours run once you 'source devel/setup.bash' in your workspace" >&2
fi
unset _flatsim_top _flatsim_devel
