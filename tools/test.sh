#!/usr/bin/env bash
# Every test of the project, from a fresh Debian machine: installs what is
# missing (tools/setup.sh), builds the host preset, then runs
#   1. the SocketCAN tests (hil_sim on vcan0) through pytest inside tools/with-vcan
#      (on vcan0 here, or in a throwaway QEMU VM when the kernel has no CAN),
#   2. the C tests through CTest (Unity, the model and CLI tests, the Cortex-M
#      images under QEMU),
#   3. every other Python test through pytest, one worker per core (pytest-xdist;
#      the SocketCAN ones are deselected there: they ran in 1).
# One line per test as it finishes. A test that skips fails the run
# (LEGSIM_NO_SKIP=1, tests/conftest.py; for CTest: a test that did not run):
# set-up installs every dependency, so a skip here means something is missing.
# Logs: out/logs/ (setup-*, build-host, test-*.log); a summary closes the run.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
# shellcheck source=tools/setup.sh
. "$root/tools/setup.sh"
legsim_setup || exit 1
legsim_build host || exit 1

py="$root/.venv/bin/python"
export LEGSIM_ROOT="$root" LEGSIM_NO_SKIP=1 PYTHONUNBUFFERED=1
logs=$legsim_logs
# The SocketCAN tests (tests/hil, tests/hil_scenes: hil_sim and the bench on vcan0, and
# the bench's CAN decoding on python-can's virtual bus) run where vcan0 is; the rest on the host,
# among them tests/hil_verdicts, which checks the scenes' recordings against the reference at
# native speed (the VM emulates its one vCPU). The scenes record
# into an emptied out/hil_scenes/ so that no verdict reads an older run. The VM's limit is
# 50 min (LEGSIM_VM_TIMEOUT).
socketcan_tests=(tests/hil tests/hil_scenes)
pytest_args=(-v -p no:cacheprovider -rfEs --color=no --continue-on-collection-errors)

status=0 summary=()
# stage NAME LOG CMD...: runs CMD with its output on stdout and in LOG; adds
# NAME, its last summary line, its result and wall time to the closing summary.
stage() {
  local name=$1 log=$logs/$2 t0=$SECONDS rc line
  shift 2
  echo "== test: $name (log: $log)"
  "$@" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  # pytest's "== N passed in Xs ==" or CTest's "N% tests passed, ..." line.
  line=$(grep -E '^=+ .*(passed|failed|error|skipped|no tests ran).* in [0-9.]+s|tests passed, .* tests failed out of' \
         "$log" | tail -n 1 | tr -d '=' | sed 's/^ *//; s/ *$//')
  if ((rc == 0)) && [[ $name == ctest ]] && grep -q 'The following tests did not run' "$log"; then
    echo "test: ctest: tests that did not run (skipped) count as failures here:"
    sed -n '/The following tests did not run/,/^$/p' "$log"
    rc=1 line+="; some did not run"
  fi
  ((rc)) && status=1
  summary+=("$(printf '%-20s %-4s %5d s  %s' "$name" "$( ((rc)) && echo FAIL || echo ok)" \
               $((SECONDS - t0)) "${line:-(no summary line; exit status $rc)}")")
}

mkdir -p "$logs"
export LEGSIM_SCENES_OUT="$root/out/hil_scenes"
rm -rf "$LEGSIM_SCENES_OUT"
# pytest's temporary files go to /dev/shm: the VM's /tmp is the host's, over 9p,
# where a deleted-then-truncated file fails.
stage "socketcan (vcan0)" test-socketcan.log \
  env LEGSIM_HIL_REQUIRE=1 LEGSIM_VM_TIMEOUT="${LEGSIM_VM_TIMEOUT:-3000}" \
  "$root/tools/with-vcan" env TMPDIR=/dev/shm \
  "$py" -m pytest "${pytest_args[@]}" "${socketcan_tests[@]}"
stage ctest test-ctest.log ctest --preset host
ignore=()
for t in "${socketcan_tests[@]}"; do ignore+=(--ignore="$t"); done
# on the host's cores (pytest-xdist, one worker per core): the tests share no files but
# their own tmp_path and out/hil_scenes/, which they only read
stage pytest test-pytest.log "$py" -m pytest "${pytest_args[@]}" -n auto tests "${ignore[@]}"

echo "== test: summary"
printf '  %s\n' "${summary[@]}"
if ((status)); then echo "test: FAILED (logs: $logs)"; else echo "test: all passed"; fi
exit $status
