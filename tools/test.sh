#!/usr/bin/env bash
# Every test of the project, from a fresh Debian machine: installs what is
# missing (tools/setup.sh), builds the host preset, runs the C tests (Unity,
# the model and CLI tests, the Cortex-M builds under QEMU) through CTest, the
# Python tests through pytest, and the SocketCAN tests through pytest inside
# tools/with-vcan (on vcan0 here, or in a throwaway VM when the kernel has no CAN).
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
"$root/tools/setup.sh" || exit 1
py="$root/.venv/bin/python"
export LEGSIM_ROOT="$root"

cmake --preset host && cmake --build --preset host || exit 1

status=0
# SocketCAN: the hil_sim tests need vcan0, so they run where it exists.
# (pytest's temporary files go to /dev/shm: the VM's /tmp is the host's, over 9p,
# where a deleted-then-truncated file fails.)
LEGSIM_HIL_REQUIRE=1 "$root/tools/with-vcan" env TMPDIR=/dev/shm "$py" -m pytest -q -p no:cacheprovider \
  tests/hil/test_hil_sim.py tests/hil_scenes || status=1
ctest --preset host || status=1
# Everything else in Python (tests that need vcan0 skip here: they ran above).
"$py" -m pytest -q -p no:cacheprovider tests || status=1
exit $status
