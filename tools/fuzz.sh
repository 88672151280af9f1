#!/usr/bin/env bash
# Builds the preset "fuzz" (clang, libFuzzer, ASan + UBSan) and runs each fuzz target for
# a while with its corpus (fuzz/README.md).
#
#   tools/fuzz.sh [-t SECONDS] [-j JOBS] [--no-build] [TARGET...]
#
#   -t SECONDS  per target (default 60; the long run: fuzz/README.md)
#   -j JOBS     libFuzzer processes per target (default 1); with JOBS > 1 (-fork) a target
#               keeps going after a failure (each failing input is still written out)
#   --no-build  use the binaries already in build/fuzz
#   TARGET      model, scene, can (default: all three, one after the other)
#
# Corpora: the seeds (shipped files, fuzz/README.md) are read only; what a run learns goes
# to build/fuzz/fuzz/corpus-work/TARGET and is kept for the next run. An input that fails
# (crash, sanitizer report, violated invariant, leak, timeout, out of memory) is written to
# fuzz/regressions/TARGET/ for a human to commit (CTest then runs it in every build); the
# script fails if any target failed. A summary line per target closes the run, with how many
# of the inputs run reached the two-leg robot (fuzz/reach.h).
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

seconds=60 jobs=1 build=1 targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    -t) seconds=$2; shift 2 ;;
    -j) jobs=$2; shift 2 ;;
    --no-build) build=0; shift ;;
    -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    model|scene|can) targets+=("$1"); shift ;;
    *) echo "tools/fuzz.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=(model scene can)

bin=build/fuzz/fuzz
if [ "$build" = 1 ]; then
  cmake --preset fuzz >/dev/null || { echo "tools/fuzz.sh: configure failed (cmake --preset fuzz)" >&2; exit 1; }
  cmake --build --preset fuzz || { echo "tools/fuzz.sh: build failed (cmake --build --preset fuzz)" >&2; exit 1; }
fi

# Seeds per target (read only); the first folder given to libFuzzer is the one it writes.
seeds() {
  case "$1" in
    model) echo "models tests/model/fixtures" ;;
    scene) echo "scenes tests/model/fixtures/scenes" ;;
    can) echo "$bin/corpus/can" ;;
  esac
  [ -d "fuzz/corpus/$1" ] && echo "fuzz/corpus/$1"  # a merged corpus, if one was committed
}
options() {
  case "$1" in
    model|scene) echo "-dict=$bin/toml.dict -max_len=16384 -timeout=20" ;;
    can) echo "-max_len=4096 -timeout=20" ;;
  esac
}

export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0 summary=()
for t in "${targets[@]}"; do
  exe=$bin/fuzz_$t
  [ -x "$exe" ] || { echo "tools/fuzz.sh: no $exe (build the preset fuzz)" >&2; exit 1; }
  work=$bin/corpus-work/$t
  out=fuzz/regressions/$t
  log=$bin/fuzz_$t.log
  mkdir -p "$work" "$out"
  before=$(ls "$out" | sort)
  fork=()
  [ "$jobs" -gt 1 ] && fork=(-fork="$jobs" -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
  echo "== fuzz_$t: ${seconds} s, seeds $(seeds "$t" | tr '\n' ' ')log $log"
  # shellcheck disable=SC2046
  "$exe" -max_total_time="$seconds" -print_final_stats=1 -artifact_prefix="$out/" \
    $(options "$t") "${fork[@]}" "$work" $(seeds "$t") >"$log" 2>&1
  rc=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | awk '{s+=$2} END {print s+0}')
  if [ "$execs" = 0 ]; then  # -fork: the last status line counts
    execs=$(grep -o '#[0-9]*' "$log" | tail -1 | tr -d '#')
  fi
  corpus=$(find "$work" -type f | wc -l)
  reach=$(grep -o '[0-9]* of [0-9]* inputs reached the robot' "$log" | tail -1)
  new=$(comm -13 <(echo "$before") <(ls "$out" | sort) | sed "s|^|$out/|" | tr '\n' ' ')
  if [ $rc -ne 0 ] || [ -n "$new" ]; then
    status=1
    echo "fuzz_$t FAILED (exit $rc): ${new:-no input saved}; the report:"
    grep -m1 -A12 -E '^==[0-9]+==ERROR|runtime error|invariant violated|ERROR: libFuzzer' "$log" | head -20
    summary+=("fuzz_$t: FAILED after ${execs:-?} executions: ${new:-see $log}")
  else
    summary+=("fuzz_$t: ok, ${execs:-?} executions in ${seconds} s, work corpus $corpus inputs; ${reach:-no reach count}")
  fi
done
echo "== summary"
printf '%s\n' "${summary[@]}"
exit $status
