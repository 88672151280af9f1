#!/bin/bash
# Self-test of tools/with-vcan (called by the project's pytest suite).
# One run (so one VM boot where the host has no vcan) checks that a 64-byte
# CAN FD frame goes between two python-can buses on vcan0, that the command's
# exit status comes back, and that its stdout and stderr stay apart.
# Needs python-can for $PYTHON (default python3). Exit 0 = pass.
set -u
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
PY=${PYTHON:-python3}

out=$(mktemp) err=$(mktemp)
trap 'rm -f "$out" "$err"' EXIT

"$ROOT/tools/with-vcan" "$PY" -c "
import sys, can
a = can.Bus(interface='socketcan', channel='vcan0', fd=True)
b = can.Bus(interface='socketcan', channel='vcan0', fd=True)
a.send(can.Message(arbitration_id=0x123, data=bytes(range(64)), is_fd=True, is_extended_id=False))
m = b.recv(2)
print(m)
assert m and len(m.data) == 64, m
assert m.is_fd and bytes(m.data) == bytes(range(64)), m
a.shutdown(); b.shutdown()
print('selftest-stdout', hex(m.arbitration_id))
print('selftest-stderr', file=sys.stderr)
sys.exit(42)
" >"$out" 2>"$err"
rc=$?

fail() {
	echo "vcan selftest: FAIL: $*" >&2
	echo "--- stdout:" >&2; cat "$out" >&2
	echo "--- stderr:" >&2; cat "$err" >&2
	exit 1
}
((rc == 42)) || fail "exit status $rc, expected 42 (the python-can check failed or did not run)"
grep -qx 'selftest-stdout 0x123' "$out" || fail "CAN FD frame report missing from stdout"
grep -q 'selftest-stderr' "$out" && fail "stderr text found on stdout"
grep -qx 'selftest-stderr' "$err" || fail "stderr text missing"
grep -q 'selftest-stdout' "$err" && fail "stdout text found on stderr"
echo "vcan selftest: OK ($(grep -o 'mode=[a-z]*' "$err" | head -n 1): CAN FD frame over vcan0, exit status, stdout/stderr)"
