#!/usr/bin/env bash
# The main job: Floquet modal analysis of the default turbine (`hawt modes`).
# Sets up .venv first if needed (scripts/bootstrap.sh; fast when nothing changed).
# Extra arguments go to `hawt modes`, e.g.  bash scripts/run.sh --json
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="${HAWT_VENV:-$root/.venv}"
bash "$root/scripts/bootstrap.sh"
# Let the ROS wheels' start-up hook set LD_LIBRARY_PATH for THIS venv.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE
export MPLBACKEND="${MPLBACKEND:-Agg}"
exec "$venv/bin/hawt" modes "$@"
