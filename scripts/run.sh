#!/usr/bin/env bash
# The main job: start the hawt ROS 2 node (hawt-node) on the default turbine, the NREL 5-MW
# operating in 15 m/s wind under ROSCO (its DISCON library from the rosco wheel), recording
# everything it publishes into runs/hawt-<date>-<time>.mcap, with a live status line (wind,
# rotor speed, power, pitch, tip deflection); the Floquet modal analysis is served on request.
# Ctrl-C stops the node, which finalizes the recording; this script then prints `hawt info`.
# The paper's turbine in a vacuum: bash scripts/run.sh --ros-args -p turbine:=paper
# Sets up .venv first if needed (scripts/bootstrap.sh; fast when nothing changed).
#
#   bash scripts/run.sh                                  # defaults
#   bash scripts/run.sh --ros-args -p wind:=8.0          # extra arguments go to hawt-node
#   bash scripts/run.sh modes [--json ...]               # just the Table 2 table (`hawt modes`)
#
# Environment: HAWT_RUNS_DIR (recording folder, default <repo>/runs), ROS_DOMAIN_ID (kept),
# ROS_AUTOMATIC_DISCOVERY_RANGE (default LOCALHOST), ROS_LOG_DIR (default: a temporary folder,
# removed at the end), HAWT_VENV.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="${HAWT_VENV:-$root/.venv}"
bash "$root/scripts/bootstrap.sh"
# Let the ROS wheels' start-up hook set LD_LIBRARY_PATH for THIS venv.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE
export MPLBACKEND="${MPLBACKEND:-Agg}"

if [ "${1:-}" = "modes" ]; then          # the offline table: `hawt modes`
  shift
  exec "$venv/bin/hawt" modes "$@"
fi
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then
  sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d' | sed 's/^# \{0,1\}//'
  echo
  exec "$venv/bin/hawt-node" --help
fi

# ROS 2: discovery on this machine only unless the user chose otherwise; rcl logs in a
# temporary folder instead of ~/.ros.
export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
own_log_dir=""
if [ -z "${ROS_LOG_DIR:-}" ]; then
  ROS_LOG_DIR="$(mktemp -d "${TMPDIR:-/tmp}/hawt-roslog.XXXXXX")"
  own_log_dir="$ROS_LOG_DIR"
fi
export ROS_LOG_DIR
cleanup() { if [ -n "$own_log_dir" ]; then rm -rf "$own_log_dir"; fi; }
trap cleanup EXIT

runs="${HAWT_RUNS_DIR:-$root/runs}"
mkdir -p "$runs"
runs="$(cd "$runs" && pwd)"
stamp="$(date +%Y%m%d-%H%M%S)"
file="$runs/hawt-$stamp.mcap"
k=1
while [ -e "$file" ]; do file="$runs/hawt-$stamp-$k.mcap"; k=$((k + 1)); done
shown="$file"
case "$file" in "$PWD"/*) shown="${file#"$PWD"/}" ;; esac
hawt_cmd="$venv/bin/hawt"
case "$hawt_cmd" in "$PWD"/*) hawt_cmd="${hawt_cmd#"$PWD"/}" ;; esac

cat <<MSG
hawt: starting the node (default: the NREL 5-MW in 15 m/s wind under ROSCO); recording to
  $shown
  publishes /joint_states (yaw, teeter, rotor azimuth, blade pitch, generator),
  /blade_deflections, /blade_markers; subscribes /pitch_command, /torque_command, /wind
  ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-0}  ROS_AUTOMATIC_DISCOVERY_RANGE=$ROS_AUTOMATIC_DISCOVERY_RANGE
Modal analysis on request, from another terminal in this folder:
  $hawt_cmd call modes                 # --json, --elements 8, --action (progress)
With a full ROS 2 install (hawt_msgs built and sourced, same ROS_DOMAIN_ID):
  ros2 service call /modal_analysis hawt_msgs/srv/ModalAnalysis "{}"
  ros2 topic echo /joint_states
Ctrl-C stops the node and finalizes the recording.

MSG

# The node runs in the background so that this script can pass on a SIGINT/SIGTERM sent to it
# alone (a Ctrl-C in a terminal reaches both) and then report on the recording.
"$venv/bin/hawt-node" --ros-args -p record:="$file" "$@" &
pid=$!
forward() { kill -s "$1" "$pid" 2>/dev/null || true; }
trap 'forward INT' INT
trap 'forward TERM' TERM
rc=0
while :; do
  if wait "$pid"; then rc=0; else rc=$?; fi
  kill -0 "$pid" 2>/dev/null || break       # wait was interrupted by a signal: wait again
done
trap - INT TERM

if [ -e "$file" ]; then
  echo
  echo "hawt: node stopped (exit status $rc); the recording:"
  "$venv/bin/hawt" info "$file" || true
else
  echo "hawt: node stopped (exit status $rc); no recording was written" >&2
fi
exit "$rc"
