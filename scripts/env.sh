# Source this file to use the swim workspace in a shell: the virtual environment, the ROS 2
# prefix it holds (the ros-jazzy-* wheels install a ROS prefix into the venv), and our install/.
# Discovery stays on this host; ROS_DOMAIN_ID is left to the caller (tests set their own).
_swim_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
_swim_venv=${SWIM_VENV:-$_swim_root/.venv}
export VIRTUAL_ENV="$_swim_venv"
case ":$PATH:" in *":$_swim_venv/bin:"*) ;; *) export PATH="$_swim_venv/bin:$PATH" ;; esac
export AMENT_PREFIX_PATH="$_swim_venv${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
export CMAKE_PREFIX_PATH="$_swim_venv${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
export RMW_IMPLEMENTATION=${RMW_IMPLEMENTATION:-rmw_fastrtps_cpp}
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
mkdir -p "$_swim_root/log"
if [ -f "$_swim_root/install/local_setup.bash" ]; then
  # colcon's script reads unset variables; relax nounset while it runs.
  _swim_nounset=$([[ $- == *u* ]] && echo 1 || true)
  set +u
  # shellcheck disable=SC1091
  source "$_swim_root/install/local_setup.bash"
  [ -n "$_swim_nounset" ] && set -u
fi
# `ros2 run` for our executables where ros2cli is not installed (see scripts/bin/ros2)
if ! command -v ros2 >/dev/null 2>&1; then export PATH="$PATH:$_swim_root/scripts/bin"; fi
unset _swim_root _swim_venv _swim_nounset
