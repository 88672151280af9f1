#!/usr/bin/env bash
# Installs what legsim needs on a Debian machine, idempotently: the Debian
# packages that are missing, and a Python virtual environment (.venv) with the
# public Python API (python/, package legsim) and the bench (bench/, with its
# test and peer-engine extras), both editable. Safe to run again.
#
# Run by tools/demo.sh and tools/test.sh (they source it for its functions:
# legsim_setup, legsim_build). One short line per stage on stderr; the output of
# apt, pip and CMake goes to out/logs/<stage>.log, and a failing stage prints
# the last 40 lines of its log and the log's path.
#
# Environment: LEGSIM_LOG_DIR (default out/logs), LEGSIM_SETUP_PYTHON (the
# python3 that makes .venv; default: the first python3 on PATH, 3.11+).

legsim_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
legsim_logs=${LEGSIM_LOG_DIR:-$legsim_root/out/logs}

# What a fresh Debian 12 root lacks and the project needs (build, tests, the MCU
# images under QEMU, the vcan VM). libgl1: exudyn's wheel (a peer engine of the
# bench) links libGL.so.1. pkgconf: the installed package's pkg-config file is tested.
# python3-siconos, python3-scipy: the two-leg robot's Siconos peer runs in the system
# Python (Siconos is not on PyPI; bench/legsim_bench/benchmarks/peers/siconos_robot.py).
# valgrind: instruction counts (callgrind) of the work-precision benchmark.
legsim_debs=(build-essential cmake ninja-build pkgconf python3 python3-venv valgrind
             libeigen3-dev libtomlplusplus-dev libgl1 python3-siconos python3-scipy
             gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
             qemu-system-arm qemu-system-x86 qemu-system-data iproute2 kmod cpio xz-utils)

legsim_say() { echo "setup: $*" >&2; }

# legsim_logged LOGNAME CMD...: runs CMD with stdout and stderr appended to
# $legsim_logs/LOGNAME.log; on failure prints the log's tail and path, returns 1.
legsim_logged() {
  local log=$legsim_logs/$1.log rc=0
  shift
  mkdir -p "$legsim_logs"
  echo "### $(date '+%F %T') $*" >>"$log"
  # A line every 30 s while it runs (apt and pip take minutes on a fresh machine).
  local t0=$SECONDS ticker
  (while sleep 30; do
     echo "setup:   ... $((SECONDS - t0)) s: $(tail -n 1 "$log" | tr -d '\r' | cut -c1-110)" >&2
   done) &
  ticker=$!
  "$@" >>"$log" 2>&1 </dev/null || rc=$?
  kill "$ticker" 2>/dev/null
  wait "$ticker" 2>/dev/null
  if ((rc)); then
    echo "setup: FAILED (exit status $rc): $*" >&2
    echo "----- last 40 lines of $log -----" >&2
    tail -n 40 "$log" >&2
    echo "----- full log: $log -----" >&2
    return 1
  fi
}

legsim_apt() {
  local p missing=() sudo_cmd=()
  for p in "${legsim_debs[@]}"; do
    [[ $(dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null) == ii* ]] || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  if ! command -v apt-get >/dev/null; then
    legsim_say "missing Debian packages (${missing[*]}) and no apt-get: install them by hand"
    return 1
  fi
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  local log=$legsim_logs/setup-apt.log
  mkdir -p "$legsim_logs" && : >"$log"
  legsim_say "installing ${#missing[@]} Debian packages (log: $log): ${missing[*]}"
  local apt=("${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600)
  local t0=$SECONDS
  legsim_logged setup-apt "${apt[@]}" update &&
    legsim_logged setup-apt "${apt[@]}" install -y --no-install-recommends "${missing[@]}" &&
    legsim_say "Debian packages installed ($((SECONDS - t0)) s)"
}

legsim_venv() {
  local venv=$legsim_root/.venv py=${LEGSIM_SETUP_PYTHON:-python3}
  if [ ! -x "$venv/bin/python" ]; then
    if ! "$py" -c 'import sys, tomllib, venv; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
      legsim_say "$(command -v "$py" || echo "$py") is not a Python >= 3.11 with tomllib and venv" \
        "(Debian 12: apt-get install python3 python3-venv; or set LEGSIM_SETUP_PYTHON)"
      return 1
    fi
    local log=$legsim_logs/setup-venv.log
    mkdir -p "$legsim_logs" && : >"$log"
    legsim_say "creating $venv with $(command -v "$py") (log: $log)"
    legsim_logged setup-venv "$py" -m venv --clear "$venv" || return 1
  fi
  # Reinstall when a pyproject changed (new pins, extras, entry points).
  local stamp=$venv/.legsim-installed f stale=0
  for f in "$legsim_root/python/pyproject.toml" "$legsim_root/bench/pyproject.toml"; do
    [ -f "$stamp" ] && [ ! "$f" -nt "$stamp" ] || stale=1
  done
  ((stale)) || return 0
  local log=$legsim_logs/setup-pip.log
  mkdir -p "$legsim_logs" && : >"$log"
  legsim_say "installing the Python API (python/) and the bench (bench/) into $venv (log: $log)"
  local pip=(env PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 "$venv/bin/python" -m pip) t0=$SECONDS
  legsim_logged setup-pip "${pip[@]}" install --upgrade pip &&
    legsim_logged setup-pip "${pip[@]}" install -e "$legsim_root/python" -e "$legsim_root/bench[test,peers]" &&
    legsim_logged setup-pip "${pip[@]}" install "fmpy==0.3.32" &&  # the FMUs' client (tests/fmu)
    touch "$stamp" && legsim_say "Python packages installed ($((SECONDS - t0)) s)"
}

legsim_setup() {
  legsim_apt && legsim_venv
}

# legsim_build PRESET: configures and builds a CMake preset with the .venv's
# python; the output goes to out/logs/build-PRESET.log, with a progress line
# every 10 % of the build (and any warning or error) on stderr, and a line at
# least every 20 s while one step (a large generated file) compiles.
legsim_build() {
  local preset=$1 log=$legsim_logs/build-$1.log
  mkdir -p "$legsim_logs" && : >"$log"
  legsim_say "configuring the $preset preset (log: $log)"
  local t0=$SECONDS
  legsim_logged "build-$preset" cmake --preset "$preset" \
    -DPython3_EXECUTABLE="$legsim_root/.venv/bin/python" || return 1
  legsim_say "building the $preset preset"
  local rc ticker awk_cmd=(awk)
  # mawk (Debian's awk) buffers a pipe's input unless told it is interactive.
  awk -W version 2>/dev/null | grep -qi mawk && awk_cmd=(awk -W interactive)
  (while sleep 20; do
     echo "build:   ... $((SECONDS - t0)) s: $(tail -n 1 "$log" | tr -d '\r' | cut -c1-100)" >&2
   done) &
  ticker=$!
  cmake --build --preset "$preset" 2>&1 | tee -a "$log" | "${awk_cmd[@]}" '
    /^\[[0-9]+\/[0-9]+\] / {
      split(substr($1, 2), f, "/"); n = f[1] + 0; t = f[2] + 0
      p = int(10 * n / t)
      if (p > last) { printf "build: %d%% (%d/%d)\n", 10 * p, n, t; fflush(); last = p }
      next
    }
    /^ninja: no work to do/ { print "build: up to date"; fflush(); next }
    { print; fflush() }' >&2
  rc=${PIPESTATUS[0]}
  kill "$ticker" 2>/dev/null
  wait "$ticker" 2>/dev/null
  if ((rc)); then
    echo "setup: FAILED: cmake --build --preset $preset (exit status $rc); full log: $log" >&2
    return 1
  fi
  legsim_say "built the $preset preset ($((SECONDS - t0)) s)"
}

if [[ ${BASH_SOURCE[0]} == "$0" ]]; then
  set -euo pipefail
  legsim_setup
fi
