#!/usr/bin/env bash
# The main job, from a fresh Debian machine: installs what is missing
# (tools/setup.sh), builds the host preset, then the bench brings up vcan0 (here,
# or in a throwaway VM when the kernel has no CAN), starts hil_sim, drives the
# leg's demo scene and the robot's Fig. 7 over SocketCAN, checks them against the
# bench's own models and prints the check tables and where the plots (and the
# robot's GIF) are. Extra arguments go to `legsim-bench demo` (e.g. --all for every
# shipped scene).
# Logs of the set-up and the build: out/logs/ (a failing stage prints its tail).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
# shellcheck source=tools/setup.sh
. "$root/tools/setup.sh"
legsim_setup || exit 1
legsim_build host || exit 1
export LEGSIM_ROOT="$root" PYTHONUNBUFFERED=1
echo "demo: legsim-bench demo $*" >&2
exec "$root/.venv/bin/legsim-bench" demo "$@"
