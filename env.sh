# Source this for interactive work:  source env.sh
# Puts the workspace's devel space and the virtual environment (first on PATH) into this shell, so that
# roslaunch, rosrun, rostopic, rosbag and rostest find closed_loop and run its nodes with the right Python.
# Unless you have set ROS_IP, ROS_HOSTNAME or ROS_MASTER_URI yourself, it also sets ROS_IP=127.0.0.1 and
# ROS_MASTER_URI=http://127.0.0.1:11311, so the graph listens on loopback only (README: "Network").
_closed_loop_root=$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")" && pwd)
if [ ! -f "$_closed_loop_root/.ws/devel/setup.bash" ]; then
  echo "closed_loop: not provisioned yet; run 'make provision' (as root) in $_closed_loop_root" >&2
  return 1 2>/dev/null || exit 1
fi
# The rule lives in closed_loop.netenv; it prints fixed export lines (ROS_IP, ROS_MASTER_URI) or none.
# It looks at the variables before the workspace's setup.bash, which sets a default ROS_MASTER_URI.
_closed_loop_net=$(PYTHONPATH="$_closed_loop_root/src" "$_closed_loop_root/.venv/bin/python3" -m closed_loop.netenv)
source "$_closed_loop_root/.ws/devel/setup.bash"
export PATH="$_closed_loop_root/.venv/bin:$PATH"
eval "$_closed_loop_net"
unset _closed_loop_net
unset _closed_loop_root
