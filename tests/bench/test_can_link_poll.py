"""HilLink.poll's drain of queued frames is bounded by the caller's time budget
(max(timeout, 0.05) s): on a bus that always has another frame (an emulated VM in real time
faster than this process decodes) it still returns. The link waits on its bus's clock, so a fake
bus whose every recv() takes a fixed time makes the bound exact."""
from __future__ import annotations

import pytest

can = pytest.importorskip("can")
pytest.importorskip("cantools")

from legsim_bench.hil.can_link import HilLink  # noqa: E402

STEP = 2.0 ** -6   # s per recv(): exact in binary, so the counts below are exact


class EndlessBus:
    """recv() always returns a HEARTBEAT and advances the bus's clock by STEP."""
    channel_info = "endless stand-in"

    def __init__(self):
        self.frame, self.now, self.reads = None, 0.0, 0

    def clock(self) -> float:
        return self.now

    def recv(self, timeout=None):
        self.now += STEP
        self.reads += 1
        if self.reads > 100_000:   # an unbounded drain fails here instead of hanging
            raise AssertionError("poll() keeps draining past its budget")
        return self.frame

    def send(self, msg, timeout=None):
        raise AssertionError("poll sends nothing")


@pytest.mark.parametrize("timeout, budget", [(0.0, 0.05), (0.01, 0.05), (0.2, 0.2)])
def test_poll_returns_once_its_budget_has_passed(timeout, budget):
    bus = EndlessBus()
    link = HilLink(bus=bus, timeout=1.0)   # waits on bus.clock
    bus.frame = link.encode("HEARTBEAT", {"Hb_Counter": 7, "Hb_ProtocolVersion": 1})
    assert link.poll(timeout) is True
    # the first frame, then queued ones while the clock is short of (first read) + budget
    end = STEP + budget
    assert bus.now >= end and bus.now - STEP < end
    assert bus.reads == 1 + sum(1 for k in range(1, 10_000) if k * STEP < end)
    assert len(link._heartbeats) == bus.reads and link.last_heartbeat.counter == 7
