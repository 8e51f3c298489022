#!/usr/bin/env bash
# Run the whole pytest suite in the project's venv (set up first by scripts/bootstrap.sh).
# Extra arguments go to pytest, e.g.  bash scripts/test.sh -k mcap -x
# Exits with pytest's status (non-zero when tests fail).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="${HAWT_VENV:-$root/.venv}"
bash "$root/scripts/bootstrap.sh"

# ROS 2 isolation: discovery stays on this machine, a domain of our own per run (parallel
# runs do not see each other), rcl logs in a temporary folder instead of ~/.ros.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID="${HAWT_ROS_DOMAIN_ID:-$(( (RANDOM + $$) % 100 + 1 ))}"
ROS_LOG_DIR="$(mktemp -d "${TMPDIR:-/tmp}/hawt-roslog.XXXXXX")"
export ROS_LOG_DIR
trap 'rm -rf "$ROS_LOG_DIR"' EXIT
# The venv has ROS: the ROS tests must run, not skip (tests/test_*: HAWT_REQUIRE_ROS).
export HAWT_REQUIRE_ROS="${HAWT_REQUIRE_ROS:-1}"
export MPLBACKEND=Agg
# One BLAS thread per process: on 2 cores, threaded BLAS in several test processes thrashes.
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
# Let the ROS wheels' start-up hook set LD_LIBRARY_PATH for THIS venv, and drop library
# folders of other venvs an outer process may have left in it.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE
if [ -n "${LD_LIBRARY_PATH:-}" ]; then
  keep=()
  IFS=: read -r -a parts <<<"$LD_LIBRARY_PATH"
  for d in "${parts[@]}"; do
    [ -z "$d" ] && continue
    if [ -f "$d/../pyvenv.cfg" ] && [ "$(cd "$d/.." && pwd)" != "$(cd "$venv" && pwd)" ]; then
      continue
    fi
    keep+=("$d")
  done
  LD_LIBRARY_PATH="$(IFS=:; echo "${keep[*]:-}")"
  export LD_LIBRARY_PATH
fi

# Parallel test processes (pytest-xdist), one per core by default (HAWT_TEST_WORKERS=N to
# choose, 0 for one process; an explicit -n/--numprocesses/-p no:xdist in the arguments wins).
# Whole files go to one worker (--dist loadfile): module fixtures are computed once, and the
# ROS tests of a file run one after another. Each worker draws ROS domains from its own share
# (tests/ros_support.py).
workers=(-n "${HAWT_TEST_WORKERS:-auto}" --dist loadfile)
for a in "$@"; do
  case "$a" in -n|-n*|--numprocesses*|no:xdist) workers=() ;; esac
done
echo "test.sh: ROS_DOMAIN_ID=$ROS_DOMAIN_ID ROS_LOG_DIR=$ROS_LOG_DIR workers=${HAWT_TEST_WORKERS:-auto}" >&2
cd "$root"
set +e
"$venv/bin/python" -m pytest "${workers[@]}" "$@"
rc=$?
exit $rc
