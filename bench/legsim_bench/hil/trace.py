"""Raw CAN traces of the bench's sessions with hil_sim, in python-can's standard log formats,
and their replay into a recording.

Writing: :meth:`HilLink.trace` logs every frame the link sends (direction Tx, stamped when
sent) and every frame it reads (Rx, the interface's time stamp) through python-can's own
writers, the format chosen by the file's suffix: ``.log`` candump (can-utils), ``.asc``
Vector ASCII, ``.blf`` Vector binary. Frames are written in the order the link handled them,
with time stamps made non-decreasing, so the file is the session as the bench saw it
(HEARTBEATs already queued when :meth:`HilLink.heartbeat` is called, which it discards, are
left out: they came before the session).

Replay: :class:`TraceBus` is a python-can bus that plays such a file back to a HilLink. The
bench runs the scene again on it (legsim_bench.hil.runner.record, the same code as live):
every frame the bench sends must be the trace's next Tx frame (else :class:`TraceError`:
another scene, or another bench), and the trace's Rx frames come back in their order, each
once the bench's clock has reached its time stamp. The bus keeps that clock (``TraceBus.clock``,
seconds of the trace) and the link waits on it, so waits and timeouts run as they did live,
in no real time: a session that timed out live times out the same way in the replay.
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import can

__all__ = ["TRACE_SUFFIXES", "TraceError", "TraceWriter", "TraceBus", "read_trace", "trace_path"]

# python-can writes and reads these with CAN FD and the frame's direction
TRACE_SUFFIXES = {".log": "candump log", ".asc": "Vector ASC", ".blf": "Vector BLF"}


class TraceError(RuntimeError):
    """A trace that cannot be read, or that does not match the scene replayed on it."""


def trace_path(path: str | os.PathLike) -> Path:
    """The path if its suffix names a format the bench writes and replays, else TraceError."""
    p = Path(path)
    if p.suffix.lower() not in TRACE_SUFFIXES:
        kinds = ", ".join(f"{s} ({k})" for s, k in TRACE_SUFFIXES.items())
        raise TraceError(f"{p}: a CAN trace is named by its format: {kinds}")
    return p


def _copy(msg: can.Message, timestamp: float, is_rx: bool, channel) -> can.Message:
    return can.Message(timestamp=timestamp, arbitration_id=msg.arbitration_id,
                       is_extended_id=msg.is_extended_id, is_remote_frame=msg.is_remote_frame,
                       is_error_frame=msg.is_error_frame, channel=channel, dlc=msg.dlc,
                       data=bytes(msg.data), is_fd=msg.is_fd, is_rx=is_rx,
                       bitrate_switch=msg.bitrate_switch,
                       error_state_indicator=msg.error_state_indicator)


class TraceWriter:
    """One session's frames into a python-can log file (can.Logger picks the writer)."""

    def __init__(self, path: str | os.PathLike, channel: str | int | None = None):
        self.path = trace_path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # a channel name with blanks would break candump's line format
        ok = isinstance(channel, int) or (isinstance(channel, str) and channel.split() == [channel])
        self.channel = channel if ok else None   # None: the writer's default (vcan0, 1)
        self.logger = can.Logger(str(self.path))
        self.frames = 0
        self._last = float("-inf")

    def write(self, msg: can.Message, *, rx: bool, timestamp: float | None = None) -> None:
        """One frame: rx, read from the bus (its own time stamp); else sent at `timestamp`."""
        ts = (msg.timestamp if rx else timestamp) or time.time()
        self._last = max(self._last, ts)   # handling order; the formats want no step back
        self.logger(_copy(msg, self._last, rx, self.channel))
        self.frames += 1

    def close(self) -> None:
        self.logger.stop()


def read_trace(path: str | os.PathLike) -> list[can.Message]:
    """Every frame of a trace, in file order (python-can's LogReader); TraceError if the file
    is missing, not of its suffix's format, cut inside a frame, or holds no frame sent by a
    bench."""
    p = trace_path(path)
    if not p.is_file():
        raise TraceError(f"{p}: no such trace")
    try:
        with can.LogReader(str(p)) as reader:
            # a BLF file says its size in its header; python-can reads a cut one up to the cut
            size = getattr(reader, "file_size", 0)
            if isinstance(reader, can.BLFReader) and size and p.stat().st_size < size:
                raise TraceError(f"{p}: a BLF trace cut short ({p.stat().st_size} of the "
                                 f"{size} bytes its header gives)")
            frames = list(reader)
    except TraceError:
        raise
    except Exception as e:  # noqa: BLE001 - each reader fails its own way (struct, zlib, ValueError)
        raise TraceError(f"{p}: not a readable {TRACE_SUFFIXES[p.suffix.lower()]} trace "
                         f"({type(e).__name__}: {e})") from None
    frames = [m for m in frames if not m.is_error_frame]
    if not any(not m.is_rx for m in frames):
        raise TraceError(f"{p}: {len(frames)} frames, none sent by the bench (Tx): not a "
                         "legsim-bench session trace, or cut before its first request")
    return frames


def _describe(msg: can.Message) -> str:
    return f"0x{msg.arbitration_id:03x} [{len(msg.data)}] {bytes(msg.data[:8]).hex()}..."


class TraceBus(can.BusABC):
    """A recorded session played back to the bench (see the module's text)."""

    def __init__(self, path: str | os.PathLike, frames: list[can.Message] | None = None):
        self.path = Path(path)
        frames = read_trace(self.path) if frames is None else frames
        self._tx = [(i, m) for i, m in enumerate(frames) if not m.is_rx]
        self._rx = [(i, m) for i, m in enumerate(frames) if m.is_rx]
        self._next_tx = self._next_rx = 0
        self.now = (frames[0].timestamp if frames else 0.0) - 1e-6
        self.channel_info = f"replay of {self.path}"
        #: the bench asked for a frame after the trace's last one
        self.ran_out = False
        super().__init__(channel=self.channel_info)

    def clock(self) -> float:
        """The bench's clock during the replay: the trace's time (s)."""
        return self.now

    @property
    def unsent(self) -> int:
        """Tx frames of the trace the bench has not sent (yet)."""
        return len(self._tx) - self._next_tx

    def _available(self) -> can.Message | None:
        if self._next_rx >= len(self._rx):
            return None
        i, m = self._rx[self._next_rx]
        # an Rx frame after a Tx frame came once the bench had sent that one
        if self._next_tx < len(self._tx) and self._tx[self._next_tx][0] < i:
            return None
        return m

    def recv(self, timeout: float | None = None) -> can.Message | None:
        wait = 0.0 if timeout is None else float(timeout)
        m = self._available()
        if m is not None and m.timestamp <= self.now + wait:
            self._next_rx += 1
            self.now = max(self.now, m.timestamp)
            return m
        if self._next_rx >= len(self._rx):
            self.ran_out = True
        self.now += wait
        return None

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if self._next_tx >= len(self._tx):
            raise TraceError(f"{self.path}: the bench sends {_describe(msg)} after the trace's last "
                             f"sent frame ({len(self._tx)} sent frames): a trace of another scene, "
                             "or cut short")
        i, want = self._tx[self._next_tx]
        if (want.arbitration_id, want.is_extended_id, bytes(want.data)) != \
                (msg.arbitration_id, msg.is_extended_id, bytes(msg.data)):
            raise TraceError(f"{self.path}: sent frame {self._next_tx + 1} of the trace (frame "
                             f"{i + 1} of the file) is {_describe(want)}, the bench sends {_describe(msg)}: the "
                             "trace is of another scene or another version of the bench")
        self._next_tx += 1
        self.now = max(self.now, want.timestamp)

    def _recv_internal(self, timeout):   # recv() is overridden: the trace's clock, not real time
        raise NotImplementedError

    def shutdown(self) -> None:
        super().shutdown()
