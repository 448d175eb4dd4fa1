# Source this for interactive work:  source env.sh
# Puts the workspace's devel space and the virtual environment (first on PATH) into this shell, so that
# roslaunch, rosrun, rostopic, rosbag and rostest find closed_loop and run its nodes with the right Python.
_closed_loop_root=$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")" && pwd)
if [ ! -f "$_closed_loop_root/.ws/devel/setup.bash" ]; then
  echo "closed_loop: not provisioned yet; run 'make provision' (as root) in $_closed_loop_root" >&2
  return 1 2>/dev/null || exit 1
fi
source "$_closed_loop_root/.ws/devel/setup.bash"
export PATH="$_closed_loop_root/.venv/bin:$PATH"
unset _closed_loop_root
