#!/usr/bin/env bash
# Create or reuse the project's virtual environment and install everything into it:
# hawt (editable) with its test and ROS extras, the ROS 2 wheels from PyPI, the MCAP
# libraries, and the hawt_msgs interface package built from msg_defs/.
#
#   bash scripts/bootstrap.sh      # install / update .venv
#   source scripts/bootstrap.sh    # the same, then activate .venv in this shell
#
# Idempotent and fast when nothing changed: a stamp file in the venv records a hash of
# pyproject.toml, msg_defs/** and this script; the install runs again only when it changes
# (or when the venv lacks what it installs). scripts/run.sh and scripts/test.sh call this.
#
# Environment:
#   HAWT_VENV    venv location (default: <repo>/.venv)
#   HAWT_PYTHON  interpreter to create the venv with (must be CPython 3.11: the ROS 2
#                wheels on PyPI exist for 3.11 only)
#   HAWT_BOOTSTRAP_FORCE=1  reinstall even if the stamp matches
# Needs: python3.11 with venv and its headers, cmake >= 3.20 (else taken from PyPI), a C and
# C++ compiler (g++), network access to PyPI.

_hawt_bootstrap_main() {
  set -euo pipefail
  local root venv vpy py stamp_file lock t0
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  venv="${HAWT_VENV:-$root/.venv}"
  stamp_file="$venv/.hawt-stamp"
  vpy="$venv/bin/python"
  t0=$(date +%s)
  export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_PROGRESS_BAR=off

  say() { echo "bootstrap: $*" >&2; }

  # --- hash of everything the install depends on -------------------------------------
  calc_want() {
    (
      cd "$root"
      sha256sum pyproject.toml scripts/bootstrap.sh
      find msg_defs -type f ! -path '*/build/*' ! -name '*.pyc' -print0 | LC_ALL=C sort -z \
        | xargs -0 -r sha256sum
      if [ -f "$venv/pyvenv.cfg" ]; then grep -E '^(version|home)' "$venv/pyvenv.cfg" || true; fi
    ) | sha256sum | cut -d' ' -f1
  }
  # quiet pip, minus the noise of unreachable local index folders in some pip configs
  pip_q() {
    "$vpy" -m pip "$@" 2>&1 | { grep -v "^WARNING: Location 'file:" || true; } >&2
    return "${PIPESTATUS[0]}"
  }

  is_ready() {
    [ -z "${HAWT_BOOTSTRAP_FORCE:-}" ] &&
      [ -x "$venv/bin/python" ] && [ -f "$stamp_file" ] &&
      [ "$(cat "$stamp_file")" = "$(calc_want)" ] &&
      [ -f "$venv/share/hawt_msgs/package.xml" ] && [ -x "$venv/bin/hawt" ]
  }
  if is_ready; then
    say "$venv is up to date"
    return 0
  fi

  # --- interpreter and venv -------------------------------------------------------------
  is311() { "$1" -c 'import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)' 2>/dev/null; }
  if [ -x "$venv/bin/python" ]; then
    if ! is311 "$venv/bin/python"; then
      say "ERROR: $venv exists but is not a working Python 3.11 venv (the ROS 2 wheels need 3.11)."
      say "       Remove it (rm -rf $venv) or set HAWT_VENV, then run again."
      return 1
    fi
  else
    py="${HAWT_PYTHON:-}"
    if [ -z "$py" ]; then
      for cand in python3.11 python3 python; do
        if command -v "$cand" >/dev/null && is311 "$cand"; then py="$cand"; break; fi
      done
    fi
    if [ -z "$py" ] || ! is311 "$py"; then
      say "ERROR: no CPython 3.11 found (python3.11/python3); the ROS 2 wheels on PyPI exist"
      say "       for 3.11 only. Install one, or point HAWT_PYTHON at it."
      return 1
    fi
    say "creating $venv with $(command -v "$py")"
    if ! "$py" -m venv "$venv"; then
      say "ERROR: '$py -m venv' failed (Debian: apt-get install python3.11-venv)."
      return 1
    fi
  fi
  mkdir -p "$venv"
  lock="$venv/.hawt-bootstrap.lock"
  if command -v flock >/dev/null; then
    exec 9>"$lock"
    flock 9
    if is_ready; then say "$venv was brought up to date meanwhile"; return 0; fi
  fi
  # The ROS wheels' .pth re-executes the interpreter with its LD_LIBRARY_PATH unless this
  # guard is set; an inherited guard (from another venv's process) would skip that.
  unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

  # --- build tools for the interface package -------------------------------------------
  need_cxx=1
  for cxx in "${CXX:-}" c++ g++ clang++; do
    if [ -n "$cxx" ] && command -v "$cxx" >/dev/null; then need_cxx=0; break; fi
  done
  local py_include
  py_include="$("$vpy" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
  local missing=()
  [ "$need_cxx" = 1 ] && missing+=(g++)
  [ -f "$py_include/Python.h" ] || missing+=(python3-dev)
  if [ ${#missing[@]} -gt 0 ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
      say "installing ${missing[*]} with apt-get (needed to build msg_defs/hawt_msgs)"
      apt-get update -qq >&2 && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
        --no-install-recommends "${missing[@]}" >&2
    else
      say "ERROR: building msg_defs/hawt_msgs needs: ${missing[*]} (Debian package names)."
      return 1
    fi
  fi
  local extra_tools=()
  if ! command -v cmake >/dev/null ||
     ! cmake --version | awk 'NR==1{split($3,v,"."); exit !(v[1]>3 || (v[1]==3 && v[2]>=20))}'; then
    extra_tools+=("cmake>=3.20")
  fi
  if ! command -v ninja >/dev/null && ! command -v make >/dev/null; then
    extra_tools+=(ninja)
  fi

  # --- install ----------------------------------------------------------------------------
  say "installing hawt[test,ros,turbines,cluster] (editable) and the ROS 2 wheels into $venv"
  pip_q install -q -e "$root[test,ros,turbines,cluster]"
  # the OpenFAST decks (NREL 5-MW, IEA 15-MW, ...) and the ROSCO controller library ship in
  # the rosco wheel; hawt reads its data only, so its heavy dependencies are not installed
  say "installing the rosco wheel (OpenFAST decks and libdiscon) without its dependencies"
  pip_q install -q --no-deps "rosco==2.10.6"
  say "installing the build requirements of msg_defs/hawt_msgs"
  local reqs
  reqs="$("$vpy" -c '
import sys, tomllib
with open(sys.argv[1], "rb") as f:
    print("\n".join(tomllib.load(f)["build-system"]["requires"]))
' "$root/msg_defs/hawt_msgs/pyproject.toml")"
  # shellcheck disable=SC2086
  pip_q install -q $reqs "${extra_tools[@]}"
  say "building and installing msg_defs/hawt_msgs (takes ~20 s)"
  pip_q install -q --no-build-isolation --no-deps --force-reinstall \
    "$root/msg_defs/hawt_msgs"

  # --- check --------------------------------------------------------------------------------
  if ! "$vpy" -c '
import rclpy, rclpy.action, rclpy.serialization, mcap, mcap_ros2, Examples
from hawt_msgs.msg import BladeDeflection, Mode
from hawt_msgs.srv import ModalAnalysis
from hawt_msgs.action import ModalAnalysis as ModalAnalysisAction
rclpy.serialization.serialize_message(BladeDeflection())
'; then
    say "ERROR: the installed environment does not import rclpy/hawt_msgs (see above)."
    return 1
  fi
  calc_want >"$stamp_file"
  say "done in $(( $(date +%s) - t0 )) s: $venv"
}

if [[ "${BASH_SOURCE[0]}" != "$0" ]]; then
  # Sourced: run in a subshell (set -e must not leak into the caller), then activate.
  if ( _hawt_bootstrap_main "$@" ); then
    # shellcheck disable=SC1091
    source "${HAWT_VENV:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/.venv}/bin/activate"
    unset -f _hawt_bootstrap_main
  else
    unset -f _hawt_bootstrap_main
    return 1
  fi
else
  _hawt_bootstrap_main "$@"
fi
