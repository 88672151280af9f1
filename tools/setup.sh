#!/usr/bin/env bash
# Installs what legsim needs on a Debian machine, idempotently: the Debian
# packages that are missing, and a Python virtual environment (.venv) with the
# bench and its test and peer-engine extras. Sourced or run by tools/demo.sh and
# tools/test.sh; safe to run again.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

debs=(build-essential cmake ninja-build python3 python3-venv
      libeigen3-dev libtomlplusplus-dev
      gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
      qemu-system-arm qemu-system-x86 iproute2 kmod cpio xz-utils)
missing=()
for p in "${debs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing Debian packages: ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

# Python: the first python3 on PATH (3.11+ for tomllib), in a venv of its own.
venv="$root/.venv"
if [ ! -x "$venv/bin/python" ]; then
  echo "setup: creating $venv" >&2
  python3 -m venv "$venv"
fi
stamp="$venv/.legsim-bench-installed"
if [ ! -f "$stamp" ] || [ "$root/bench/pyproject.toml" -nt "$stamp" ]; then
  echo "setup: installing the bench into $venv" >&2
  "$venv/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip
  "$venv/bin/python" -m pip install -q --disable-pip-version-check -e "$root/bench[test,peers]"
  touch "$stamp"
fi
