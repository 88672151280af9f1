#!/bin/bash
# Stage 2 of the vcan VM, run by init.c in the guest as root with the host's /
# as root file system. $1 is the per-run directory that tools/vcan-vm/run made
# on the host; it holds vm.conf, argv and env (both NUL-separated).
# Setup messages go to the serial console (shown by the host if the VM fails);
# the command's stdout/stderr go to the virtio-serial ports "stdout"/"stderr".
# The command's exit status goes to $1/status; no status file = VM failure.
set -u
R=$1
fail() { echo "legsim-stage2: FATAL: $*" >&2; exit 1; }

# shellcheck source=/dev/null
. "$R/vm.conf" || fail "cannot read $R/vm.conf"   # KVER MODROOT CWD TIMEOUT RUN_UID RUN_GID
: > "$R/booted"                                    # tells the host's KVM fallback that we are alive

# CAN core, raw sockets (CAN_RAW_FD_FRAMES), the CAN device layer and vcan.
modprobe -d "$MODROOT" -S "$KVER" -a can can-raw can-dev vcan || fail "modprobe CAN modules"
# One ip process: every fork+exec costs ~0.2 s under TCG.
ip -batch - <<'EOF' || fail "ip: cannot set up lo and vcan0 (mtu 72 for CAN FD)"
link set lo up
link add dev vcan0 type vcan
link set vcan0 mtu 72 up
EOF

# virtio-serial ports show up as /dev/vportNpM; udev is absent, so map names by hand.
out='' err=''
for p in /sys/class/virtio-ports/vport*; do
	name=
	read -r name <"$p/name"
	case $name in
	stdout) out=/dev/${p##*/} ;;
	stderr) err=/dev/${p##*/} ;;
	esac
done
[[ -n $out && -n $err ]] || fail "virtio-serial ports stdout/stderr not found"

mapfile -d '' -t argv < "$R/argv" || fail "cannot read argv"
mapfile -d '' -t envv < "$R/env" || fail "cannot read env"
cd "$CWD" || fail "cannot cd to $CWD in the guest"

# Run as the caller's uid when that is not root.
drop=()
if [[ $RUN_UID != 0 ]]; then
	drop=(setpriv --reuid="$RUN_UID" --regid="$RUN_GID" --clear-groups --)
fi

start=$SECONDS
# env -i: the command sees only the environment the host passed along.
"${drop[@]}" /usr/bin/env -i "${envv[@]}" \
	/usr/bin/timeout -k 10 "$TIMEOUT" "${argv[@]}" </dev/null >"$out" 2>"$err"
rc=$?
# timeout(1) says 124, or 137 when it had to SIGKILL a command that ignored
# SIGTERM; the elapsed time tells those apart from the command's own 124/137.
if ((rc == 124 || rc == 137)) && ((SECONDS - start >= TIMEOUT)); then
	rc=124
	: >"$R/timedout"
fi

# The host reads it only after QEMU exits, and init syncs before that.
echo "$rc" >"$R/status" || fail "cannot write $R/status"
