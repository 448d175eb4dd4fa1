#!/usr/bin/env bash
# Provision what is missing, and nothing else: Debian's ROS 1 packages, the virtual environment with the
# pinned PyPI packages, and the catkin workspace in .ws/. A second run installs nothing.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

# Debian bookworm's own ROS 1 (in /usr) and every program the tests run, each named here even where a minimal
# Debian (debootstrap's minbase, the usual container image) already has it: chromium opens a sweep's report.html;
# util-linux gives unshare (the browser and a graph kept off the network, a full disk in a mount namespace),
# nsenter and setpriv; iproute2 gives ip and ss; procps gives pgrep; x11-apps gives xwd; openssl checks a cluster's
# certificates. package.xml declares each by its rosdep key (test/unit/test_packaging.py keeps the lists together).
APT_PACKAGES=(
  catkin python3-catkin-pkg python3-setuptools python3-venv python3-pip python3-pytest python3-yaml
  python3-rospy python3-rosgraph python3-rospkg python3-rostest python3-rosbag python3-roslaunch python3-rosmaster
  python3-rosnode python3-rostopic python3-rosservice python3-rosparam python3-rosmsg python3-rosgraph-msgs
  python3-tf2-ros python3-tf2-msgs python3-cryptography
  python3-std-msgs python3-std-srvs python3-geometry-msgs python3-sensor-msgs python3-nav-msgs
  python3-visualization-msgs python3-dynamic-reconfigure libdynamic-reconfigure-config-init-mutex-dev
  ros-std-msgs ros-std-srvs ros-geometry-msgs ros-sensor-msgs ros-nav-msgs ros-visualization-msgs ros-tf2-msgs
  librostest-dev rosout rosbash rospack-tools ros-robot-state-publisher rviz xvfb x11-apps cmake g++ make
  libroscpp-dev libgeometry-msgs-dev libsensor-msgs-dev libnav-msgs-dev
  chromium util-linux mount hostname coreutils iproute2 procps git openssl
)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "provision: installing Debian packages: ${missing[*]}"
  if [ "$(id -u)" != 0 ]; then
    echo "provision: need root for apt-get (run as root, or install the packages above)" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Virtual environment from Debian's interpreter (the one its ROS is built for), seeing Debian's packages.
venv="$root/.venv"
req_stamp="$venv/.requirements.sha256"
if [ ! -x "$venv/bin/python3" ] || [ "$("$venv/bin/python3" -c 'import sys; print(sys.base_prefix)')" != /usr ]; then
  echo "provision: creating $venv from /usr/bin/python3"
  rm -rf "$venv"
  /usr/bin/python3 -m venv --system-site-packages "$venv"
fi
want=$(sha256sum requirements.txt | cut -d' ' -f1)
if [ "$(cat "$req_stamp" 2>/dev/null)" != "$want" ]; then
  echo "provision: installing requirements.txt into $venv"
  # pip compiles each package's modules one after another; compileall does the same on every core (39 s -> 29 s
  # for the whole install on 2 cores).
  "$venv/bin/python3" -m pip install -q --no-compile --disable-pip-version-check -r requirements.txt
  "$venv/bin/python3" -m compileall -q -j 0 "$venv/lib" >/dev/null
  echo "$want" > "$req_stamp"
fi
export PATH="$venv/bin:$PATH"

# The catkin workspace. .ws/src/closed_loop is a folder of links to this repository's top-level entries
# (not one link to the repository itself): the workspace lives inside the package, and a link to the
# whole repository would put .ws/ inside the package path, where rosrun's `find -L` would loop into
# it and find every executable twice.
ws="$root/.ws"
pkg="$ws/src/closed_loop"
mkdir -p "$ws/src"
[ -L "$pkg" ] && rm "$pkg"
mkdir -p "$pkg"
for entry in "$root"/*; do
  name=$(basename "$entry")
  case "$name" in test_output|bags) continue ;; esac
  [ -e "$pkg/$name" ] || ln -sfn "$entry" "$pkg/$name"
done
for link in "$pkg"/*; do
  [ -L "$link" ] && [ ! -e "$link" ] && rm "$link"
done
build_stamp="$ws/.build.sha256"
want=$( (cat CMakeLists.txt package.xml setup.py; ls scripts launch test/rostest 2>/dev/null; command -v python3) \
        | sha256sum | cut -d' ' -f1)
if [ ! -f "$ws/devel/setup.bash" ] || [ "$(cat "$build_stamp" 2>/dev/null)" != "$want" ]; then
  echo "provision: catkin_make in $ws"
  (cd "$ws" && catkin_make -DPYTHON_EXECUTABLE="$venv/bin/python3" -DCATKIN_ENABLE_TESTING=ON > "$ws/catkin_make.log" 2>&1) \
    || { tail -n 40 "$ws/catkin_make.log"; echo "provision: catkin_make failed (log: $ws/catkin_make.log)" >&2; exit 1; }
  echo "$want" > "$build_stamp"
fi

# The compiled loops (numba: the LIDAR's planar caster and its grid, the navigator's wave and arcs, a mesh's
# footprint), compiled into the source tree's __pycache__ once here, not by the first processes of a test run,
# all at once. Loading them when they are there takes a fraction of a second.
# The three sets at once, each in a process of its own (on 2 cores, 6 s where one after another took 12 s).
warm=()
for module in closed_loop.control.navigation.window closed_loop.sim.planar_rays closed_loop.sim.mesh_footprint; do
  PYTHONPATH="$root/src" "$venv/bin/python3" -c "import $module as m; m.prepare()" &
  warm+=($!)
done
for pid in "${warm[@]}"; do
  wait "$pid" || { echo "provision: compiling the loops failed" >&2; exit 1; }
done
