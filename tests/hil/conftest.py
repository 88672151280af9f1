"""Fixtures of the hil_sim tests.

The SocketCAN tests need a kernel with CAN and a CAN FD vcan0; this machine kind has none,
so run them inside tools/with-vcan:

    tools/with-vcan python3 -m pytest tests/hil

Nothing is built here: hil_sim comes from $LEGSIM_HIL_SIM or build/host/hil_sim/hil_sim
(and hil_sim_expect beside it). Without vcan0 (or without the binaries) those tests are
skipped with the reason, unless LEGSIM_HIL_REQUIRE=1, which turns the skips into failures
(for runs that must exercise the bus). The pure-Python tests run anywhere.
"""
from __future__ import annotations

import importlib.util
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
if importlib.util.find_spec("legsim_bench") is None:
    sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.hil.vcan import vcan_problem as _vcan_problem  # noqa: E402

CHANNEL = os.environ.get("LEGSIM_HIL_CHANNEL", "vcan0")
REQUIRE = os.environ.get("LEGSIM_HIL_REQUIRE") == "1"


def hil_sim_path() -> Path:
    return Path(os.environ.get("LEGSIM_HIL_SIM", ROOT / "build" / "host" / "hil_sim" / "hil_sim"))


def expect_path() -> Path:
    return hil_sim_path().with_name("hil_sim_expect")


def vcan_problem(channel: str = CHANNEL) -> str | None:
    return _vcan_problem(channel)


def _skip_or_fail(reason: str):
    if REQUIRE:
        pytest.fail(reason + " (LEGSIM_HIL_REQUIRE=1)")
    pytest.skip(reason)


@pytest.fixture(scope="session")
def vcan() -> str:
    problem = vcan_problem()
    if problem:
        _skip_or_fail(problem)
    return CHANNEL


@pytest.fixture(scope="session")
def hil_binary() -> Path:
    p = hil_sim_path()
    if not p.exists():
        _skip_or_fail(f"{p} not built (cmake --build build/host --target hil_sim hil_sim_expect)")
    return p


@pytest.fixture(scope="session")
def expect_binary(hil_binary) -> Path:
    p = expect_path()
    if not p.exists():
        _skip_or_fail(f"{p} not built")
    return p


class HilProcess:
    """hil_sim running on the bus, and a HilLink to it."""

    def __init__(self, binary: Path, channel: str, args: list[str]):
        from legsim_bench.hil.can_link import HilLink

        self.stderr_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"hil_sim_{os.getpid()}_{id(self)}.log"
        self._stderr = open(self.stderr_path, "w+b")
        self.proc = subprocess.Popen([str(binary), "--channel", channel, *args],
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=self._stderr)
        self.link = HilLink(interface="socketcan", channel=channel)
        try:
            self.link.heartbeat(timeout=10.0)  # it is up and on the bus
        except Exception:
            self.stop()
            raise RuntimeError(f"hil_sim did not come up: {self.log()}")

    def log(self) -> str:
        self._stderr.flush()
        return self.stderr_path.read_text(errors="replace")

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 10.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.link.close()
        return self.proc.returncode

    def close(self):
        rc = self.stop()
        self._stderr.close()
        try:
            self.stderr_path.unlink()
        except OSError:
            pass
        return rc


@pytest.fixture
def start_hil(vcan, hil_binary):
    """start_hil(*args) -> HilProcess; every one is stopped (SIGTERM) at teardown."""
    started: list[HilProcess] = []

    def start(*args: str) -> HilProcess:
        for h in started:  # one hil_sim on the bus at a time
            h.stop()
        h = HilProcess(hil_binary, vcan, list(args))
        started.append(h)
        return h

    yield start
    for h in started:
        h.close()


@pytest.fixture
def hil(start_hil):
    """A hil_sim with the default options, and its HilLink."""
    return start_hil().link


def wait_until(cond, timeout: float, step: float = 0.01) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(step)
    return cond()
