"""The bench's CAN link to hil_sim: python-can for the bus, cantools with can/legsim.dbc for
the frames (the same file hil_sim's C code is generated from). Nothing here packs bits.

    from legsim_bench.hil.can_link import HilLink

    with HilLink() as hil:                      # socketcan/vcan0 unless configured otherwise
        s0 = hil.reset(variant="revolute", integrator="rk4", step_s=1e-3)
        hil.command_length(0, 0.70)             # upper actuator holds 0.70 m
        s = hil.step(100)                       # lockstep: exactly 100 steps, then the state
        print(s.t, s.q[:3], s.reactions[7], s.status_names)

Bus configuration, first found wins: the interface/channel arguments, python-can's own
configuration (``can.rc``, the environment CAN_INTERFACE / CAN_CHANNEL, ``~/.canrc``), then
the default ``socketcan`` on ``vcan0``. CAN FD is always on. A ready python-can bus can be
passed instead (``bus=``), e.g. ``can.Bus(interface="virtual", ...)`` in tests, or a
recorded session to replay (hil/trace.py's TraceBus).

Raw trace: ``with hil.trace("session.blf"): ...`` writes every frame sent and read in the
block through python-can's log writers (.log candump, .asc, .blf by the suffix).

Protocol (details in can/README.md):
- every CONTROL frame (reset, step, start_realtime, stop_realtime) is answered by one state
  sample (six frames, ST_STATUS last) or, when refused, by a FAULT naming its sequence
  counter: the methods wait for that answer and raise :class:`HilFault` on a refusal. A
  solver failure inside a STEP (or a real-time tick) is no refusal: the sample comes, in
  state HALTED, with the SOLVER fault in ``State.faults``;
- actuator and load commands are not answered; their faults, and the faults hil_sim raises
  on its own (command timeout, solver failure in real time), are collected in
  ``State.faults`` of the next sample and in :meth:`HilLink.faults`;
- sequence counters are kept per frame id by the link (strictly increasing).

A :class:`State` holds numpy arrays: ``q`` (18,) = (x, y, phi) of bodies 1-6 of
models/leg.toml, ``qd`` (18,), ``lengths``/``rates``/``forces`` (2,) for the upper and lower
actuator, ``reactions`` (8, 3) = (fx, fy, moment) of joints 1-8 in the model's order, as
float32 values (the DBC's resolution: ~6e-8 relative); ``t`` and ``step_count`` are exact.

The two-leg robot (``hil_sim --robot``): each leg is its own node, leg 1's frames at leg 0's
ids + 0x20 (ACT_CMD_L1, ST_POS_L1 ...), plus per foot ST_CONTACT and the box's ST_BOX. The
link tells a robot sample by its ST_BOX and completes it when every leg's ST_STATUS of the
tick is in. Its State has the robot's arrays in the core's order: ``q``/``qd`` (39,) = the
box, then leg 0's bodies 1-6, then leg 1's; ``lengths``/``rates``/``forces`` (4,);
``reactions`` (16, 3); ``contacts`` (one :class:`Contact` per foot, leg order); ``legs`` 2.
Actuator a of the robot is leg a // 2's slot a % 2: ``command_force(2, F)`` goes out in
ACT_CMD_L1, ``set_load(0, fx, fy, leg=1)`` in LOAD_CMD_L1.
"""
from __future__ import annotations

import collections
import configparser
import contextlib
import enum
import os
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Deque, Iterator

import can
import cantools
import numpy as np

# $LEGSIM_DBC, else can/legsim.dbc under $LEGSIM_ROOT, else in this checkout
DBC_PATH = Path(os.environ.get("LEGSIM_DBC") or
                Path(os.environ.get("LEGSIM_ROOT") or Path(__file__).resolve().parents[3])
                / "can" / "legsim.dbc")

BODIES = ("upper_cylinder", "upper_rod", "thigh", "lower_cylinder", "lower_rod", "shank")
JOINTS = ("A", "upper_actuator", "B_thigh", "B_lower", "C_rod_thigh", "C_rod_shank",
          "lower_actuator", "D")


def _dbc_legs_and_actuators(path: Path) -> tuple[int, tuple[str, ...]]:
    """The robot's legs (hil_sim's nodes HIL, HIL_L1, ...: can/gen_dbc.py writes one per leg)
    and a leg's actuators (ACT_CMD's Act_Mode_NAME signals), read from the DBC's text: the
    DBC is made for a number of legs, the link follows it."""
    text = path.read_text()
    nodes = re.search(r"^BU_:(.*)$", text, re.M)
    act = re.search(r"^BO_ \d+ ACT_CMD: .*?\n\n", text, re.M | re.S)
    if not nodes or not act:
        raise ValueError(f"{path}: no BU_ line or no ACT_CMD frame")
    legs = sum(1 for n in nodes.group(1).split() if re.fullmatch(r"HIL(_L\d+)?", n))
    return legs, tuple(re.findall(r"^ SG_ Act_Mode_(\w+) :", act.group(0), re.M))


# the robot's legs, a leg's actuators (as the DBC's signals name them)
ROBOT_LEGS, ACTUATORS = _dbc_legs_and_actuators(DBC_PATH)


def leg_frame(name: str, leg: int) -> str:
    """Leg k's copy of a leg frame (ACT_CMD, ST_POS, ...): NAME for leg 0, NAME_Lk else."""
    return f"{name}_L{leg}" if leg else name

CONTROL, ACT_CMD, LOAD_CMD = 0x080, 0x100, 0x110
START_CMD = 0x081    # a robot's start off the stance, for the next RESET
FAULT, HEARTBEAT = 0x020, 0x700
ST_POS, ST_VEL, ST_ACT, ST_REACT_A, ST_REACT_B, ST_STATUS = range(0x200, 0x206)
STATE_IDS = (ST_POS, ST_VEL, ST_ACT, ST_REACT_A, ST_REACT_B, ST_STATUS)
# the robot: leg k's frames at leg 0's ids + LEG_OFFSET * k; per foot ST_CONTACT; the box
LEG_OFFSET = 0x20
ACT_CMD_L1, LOAD_CMD_L1 = ACT_CMD + LEG_OFFSET, LOAD_CMD + LEG_OFFSET
ST_CONTACT, ST_BOX = 0x206, 0x240
ST_POS_L1, ST_VEL_L1, ST_ACT_L1, ST_REACT_A_L1, ST_REACT_B_L1, ST_STATUS_L1 = \
    (i + LEG_OFFSET for i in STATE_IDS)
ST_CONTACT_L1 = ST_CONTACT + LEG_OFFSET
ROBOT_STATE_IDS = (ST_BOX,) + tuple(i + LEG_OFFSET * k for k in range(ROBOT_LEGS)
                                    for i in STATE_IDS + (ST_CONTACT,))
HIL_IDS = STATE_IDS + (FAULT, HEARTBEAT) + tuple(i for i in ROBOT_STATE_IDS if i not in STATE_IDS)
_TICK_SIGNAL = {ST_POS: "Pos_Tick", ST_VEL: "Vel_Tick", ST_ACT: "Act_Tick", ST_REACT_A: "RA_Tick",
                ST_REACT_B: "RB_Tick", ST_STATUS: "St_Tick", ST_CONTACT: "Ct_Tick"}


class Command(enum.IntEnum):
    RESET = 1
    STEP = 2
    START_RT = 3
    STOP_RT = 4


class Variant(enum.IntEnum):
    REVOLUTE = 0
    SLOT = 1


class Integrator(enum.IntEnum):
    RK4 = 0
    GENERALIZED_ALPHA = 1


class ActMode(enum.IntEnum):
    KEEP = 0
    FORCE = 1
    LENGTH = 2


class SimState(enum.IntEnum):
    IDLE = 0
    LOCKSTEP = 1
    REALTIME = 2
    HALTED = 3


class ContactLaw(enum.IntEnum):
    """Ctrl_ContactLaw: legsim_contact_law."""
    LCP = 0
    PAPER = 1


class ContactState(enum.IntEnum):
    FREE = 0
    STUCK = 1
    SLIDING = 2


class ContactEvent(enum.IntFlag):
    """Ct_Events: the contact events the core raised for this foot since the previous sample
    (legsim_contact_event_mask over every step between the two: none is lost), legsim_event's
    bits 4-9 shifted down by 4."""
    LIFTOFF = 1 << 0
    TOUCHDOWN = 1 << 1
    STICK_TO_SLIP = 1 << 2
    SLIP_TO_STICK = 1 << 3
    CONTACT_INCONSISTENT = 1 << 4
    CONTACT_AMBIGUOUS = 1 << 5


class FaultCode(enum.IntEnum):
    NONE = 0
    UNKNOWN_ID = 1
    BAD_LENGTH = 2
    NOT_FINITE = 3
    OUT_OF_RANGE = 4
    STALE_SEQ = 5
    BAD_STATE = 6
    CMD_TIMEOUT = 7
    SOLVER = 8


class Status(enum.IntFlag):
    """St_Status / Hb_Status bits."""
    ASSEMBLED = 1 << 0
    REALTIME = 1 << 1
    SAFE_STATE = 1 << 2
    STROKE_MIN = 1 << 3
    STROKE_MAX = 1 << 4
    FORCE_SATURATED = 1 << 5
    NEAR_SINGULAR = 1 << 6
    HALTED = 1 << 7
    FAULT = 1 << 8
    CMD_WATCHDOG = 1 << 9
    STEPPING = 1 << 10  # heartbeats only: a STEP is being worked


# legsim_disable flags for reset(disable=...)
DISABLE_GRAVITY = 1 << 0
DISABLE_FORCE_ELEMENTS = 1 << 1
DISABLE_REACTIONS = 1 << 2
DISABLE_PROJECTION = 1 << 3
DISABLE_ACTUATORS = 1 << 4
DISABLE_STROKE_LIMITS = 1 << 5
DISABLE_ACCELERATIONS = 1 << 6

CMD_TIMEOUT_DEFAULT = 0      # Ctrl_CmdTimeout: hil_sim's --cmd-timeout-ms
CMD_TIMEOUT_NONE = 65535

# signal names of the state arrays, in array order
Q_SIGNALS = [f"Pos_B{i}_{c}" for i in range(1, 6) for c in ("x", "y", "phi")] + \
    [f"Act_B6_{c}" for c in ("x", "y", "phi")]
QD_SIGNALS = [f"Vel_B{i}_{c}" for i in range(1, 6) for c in ("vx", "vy", "omega")] + \
    [f"Act_B6_{c}" for c in ("vx", "vy", "omega")]
REACTION_SIGNALS = [f"{'RA' if j < 5 else 'RB'}_{name}_{c}"
                    for j, name in enumerate(JOINTS) for c in ("fx", "fy", "m")]


class HilError(RuntimeError):
    """No answer in time, or a malformed exchange."""


@dataclass
class Fault:
    code: FaultCode
    frame_id: int
    frame_len: int
    seq: int
    detail: int
    value: float
    step_count: int
    count: int
    signal: str | None = None   # NOT_FINITE / OUT_OF_RANGE: the offending signal's name

    def __str__(self) -> str:
        where = f" signal {self.signal}" if self.signal else ""
        return (f"{self.code.name} (frame 0x{self.frame_id:03x} len {self.frame_len} seq {self.seq}"
                f"{where}, detail {self.detail}, value {self.value:g}, step {self.step_count})")


class HilFault(HilError):
    """hil_sim refused a request: the FAULT frame that answered it."""

    def __init__(self, fault: Fault):
        super().__init__(str(fault))
        self.fault = fault


@dataclass
class Contact:
    """One foot against the ground (ST_CONTACT): the ground force on it is N n + T t (n the
    line's upward normal, t its tangent), float32 values."""
    state: ContactState
    events: ContactEvent
    normal: float          # N
    tangential: float      # N
    friction_use: float    # |T| / N
    x: float               # m, world
    y: float
    slip: float            # m/s along the tangent
    impulse_n: float       # N s, last impact
    impulse_t: float


@dataclass(eq=False)   # compared by identity: arrays have no single truth value
class State:
    q: np.ndarray              # (18,) x, y, phi of bodies 1-6 (m, rad)
    qd: np.ndarray             # (18,)
    lengths: np.ndarray        # (2,) m, upper and lower actuator
    rates: np.ndarray          # (2,) m/s
    forces: np.ndarray         # (2,) N, > 0 extends
    reactions: np.ndarray      # (8, 3) fx, fy (N, world, on the first-listed body), moment (N m)
    t: float                   # s (float64, exact)
    step_count: int
    residual: float            # max |Phi(q)|
    condition: float
    status: Status
    stroke_mask: int
    state: SimState
    legsim_status: int
    last_fault: FaultCode
    iterations: int
    variant: Variant
    integrator: Integrator
    act_seq: int
    ctrl_seq: int
    step_ns: int
    faults: list[Fault] = field(default_factory=list)   # faults received since the previous sample
    received: float = 0.0      # link.clock() when ST_STATUS arrived
    legs: int = 1              # 2: the robot (box first in q, contacts, per-leg counters)
    contacts: list[Contact] = field(default_factory=list)   # robot: one per foot, leg order
    act_seqs: tuple[int, ...] = ()   # robot: each leg's St_ActSeq (act_seq is leg 0's)
    statuses: tuple[Status, ...] = ()   # robot: each leg node's St_Status (status is leg 0's)

    @property
    def status_names(self) -> list[str]:
        return [s.name for s in Status if s in self.status]

    @property
    def body_q(self) -> np.ndarray:
        """q as (bodies, 3): (6, 3) for the leg, (13, 3) for the robot (the box first)."""
        return self.q.reshape(-1, 3)

    @property
    def box_q(self) -> np.ndarray | None:
        """The robot's box (x, y, phi), None for the one leg."""
        return self.q[:3] if self.legs > 1 else None

    @property
    def box_qd(self) -> np.ndarray | None:
        return self.qd[:3] if self.legs > 1 else None


@dataclass
class Heartbeat:
    counter: int
    state: SimState
    status: Status
    protocol_version: int
    uptime_ms: int
    rt_ticks: int
    rt_overruns: int
    jitter_max_us: float
    jitter_mean_us: float
    jitter_p99_us: float
    rt_rate_hz: float
    rx_frames: int
    rx_rejected: int
    fault_count: int
    tx_errors: int
    sim_time: float
    received: float = 0.0


def bus_config(interface: str | None = None, channel: str | int | None = None,
               **kwargs) -> dict:
    """python-can configuration: arguments, then python-can's sources, then socketcan/vcan0."""
    given = {k: v for k, v in (("interface", interface), ("channel", channel)) if v is not None}
    try:
        cfg = can.util.load_config(config=dict(given))
    except can.CanInterfaceNotImplementedError:
        if "interface" in given:
            raise
        cfg = can.util.load_config(config={**given, "interface": "socketcan"})
    if cfg.get("channel") is None:
        cfg["channel"] = "vcan0"
    cfg.update(kwargs)
    cfg["fd"] = True
    return cfg


def _config_file_with(key: str) -> str | None:
    """The last of python-can's config files whose [default] section sets `key` (later files
    override earlier ones in can.util.load_file_config)."""
    found = None
    for name in can.util.CONFIG_FILES:
        path = Path(name).expanduser()
        if not path.is_file():
            continue
        cp = configparser.ConfigParser()
        try:
            cp.read(path)
        except configparser.Error:
            continue
        if cp.has_option("default", key) or (key == "interface" and cp.has_option("default", "bustype")):
            found = str(path)
    return found


def bus_origin(interface: str | None, channel: str | int | None, cfg: dict,
               given_by: dict[str, str] | None = None) -> dict[str, str]:
    """Where bus_config() took the interface and the channel from, in python-can's order:
    the arguments (named as in `given_by`, default --interface/--channel), can.rc, the
    environment, a config file, else the bench's default."""
    given = {"interface": interface, "channel": channel}
    env = can.util.load_environment_config()
    out = {}
    for key in ("interface", "channel"):
        value = str(cfg.get(key))
        rc = can.rc.get(key, can.rc.get("bustype") if key == "interface" else None)
        if given[key] is not None:
            out[key] = (given_by or {}).get(key, f"--{key}")
        elif rc is not None and str(rc) == value:
            out[key] = "can.rc"
        elif key in env and str(env[key]) == value:
            out[key] = f"CAN_{key.upper()}"
        elif (f := _config_file_with(key)) is not None:
            out[key] = f
        else:
            out[key] = "default"
    return out


def describe_bus(cfg: dict, origin: dict[str, str] | None = None) -> str:
    """'socketcan channel vcan0, CAN FD (interface: default, channel: CAN_CHANNEL)'."""
    text = f"{cfg.get('interface')} channel {cfg.get('channel')}" + (", CAN FD" if cfg.get("fd") else "")
    if origin:
        text += f" (interface: {origin['interface']}, channel: {origin['channel']})"
    return text


class HilLink:
    """One bench's connection to hil_sim. Not thread-safe: use it from one thread."""

    def __init__(self, interface: str | None = None, channel: str | int | None = None, *,
                 bus: can.BusABC | None = None, dbc: str | os.PathLike | None = None,
                 timeout: float = 5.0, given_by: dict[str, str] | None = None, **bus_kwargs):
        self.db = cantools.database.load_file(str(dbc or DBC_PATH), strict=True)
        self.timeout = timeout
        self._own_bus = bus is None
        if bus is None:
            filters = [{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in HIL_IDS]
            cfg = bus_config(interface, channel, **bus_kwargs)
            #: which bus this is and where its configuration came from (for the user)
            self.description = describe_bus(cfg, bus_origin(interface, channel, cfg, given_by))
            bus = can.Bus(**cfg, can_filters=filters)
            self._channel = cfg.get("channel")
        else:
            self.description = f"a given bus: {bus.channel_info}"
            self._channel = None   # a given bus's channel may be anything (virtual: queues)
        self.bus = bus
        #: the clock the link waits on and stamps samples with (s): the monotonic clock, or a
        #: replayed trace's own (trace.TraceBus.clock)
        self.clock: Callable[[], float] = getattr(bus, "clock", time.monotonic)
        self._trace = None   # a trace.TraceWriter while a session is logged
        self._seq = {CONTROL: 0, START_CMD: 0, **{fid + LEG_OFFSET * k: 0 for k in range(ROBOT_LEGS)
                                    for fid in (ACT_CMD, LOAD_CMD)}}
        self._partial: dict[int, dict[int, dict]] = {}   # tick -> frame id -> signals
        self._states: Deque[State] = collections.deque()
        self._faults: Deque[Fault] = collections.deque()
        self._pending_faults: list[Fault] = []           # for the next State.faults
        self._heartbeats: Deque[Heartbeat] = collections.deque(maxlen=1000)
        self.last_heartbeat: Heartbeat | None = None
        self.last_state: State | None = None

    # ---- lifetime ----------------------------------------------------------------------

    def close(self) -> None:
        if self._own_bus:
            self.bus.shutdown()

    def __enter__(self) -> "HilLink":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @contextlib.contextmanager
    def trace(self, path: str | os.PathLike | None):
        """Within the block, every frame sent and read goes to a raw CAN trace at `path`
        (python-can's writer for its suffix: .log candump, .asc, .blf; see hil/trace.py).
        None: no trace. Yields the writer (its `frames` count) or None."""
        if path is None:
            yield None
            return
        from .trace import TraceWriter

        writer = TraceWriter(path, self._channel)
        self._trace = writer
        try:
            yield writer
        finally:
            self._trace = None
            writer.close()

    def _send(self, msg: can.Message) -> None:
        sent = time.time()   # python-can's time base (Message.timestamp: s since the epoch)
        self.bus.send(msg)
        if self._trace is not None:   # a frame the bus refused is not in the trace
            self._trace.write(msg, rx=False, timestamp=sent)

    # ---- encoding ----------------------------------------------------------------------

    def encode(self, name: str, signals: dict, *, strict: bool = True,
               frame_id: int | None = None) -> can.Message:
        """A frame of the DBC as a python-can message. Missing signals are 0. strict=False
        lets out-of-range values (and NaN) through: for bad-input tests with send_raw()."""
        msg = self.db.get_message_by_name(name)
        data = {s.name: 0 for s in msg.signals}
        data.update(signals)
        payload = msg.encode(data, strict=strict, padding=False, scaling=True)
        return can.Message(arbitration_id=msg.frame_id if frame_id is None else frame_id,
                           data=payload, is_extended_id=False, is_fd=True, bitrate_switch=False)

    def next_seq(self, frame_id: int) -> int:
        self._seq[frame_id] = (self._seq[frame_id] + 1) & 0xFFFFFFFF
        return self._seq[frame_id]

    def send_raw(self, msg: can.Message) -> None:
        """Sends any frame as it is (no counter, no checks): for bad-input tests."""
        self._send(msg)

    # ---- receiving ---------------------------------------------------------------------

    def _handle(self, msg: can.Message) -> None:
        if self._trace is not None:
            self._trace.write(msg, rx=True)
        if msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
            return
        fid = msg.arbitration_id
        if fid not in HIL_IDS:
            return
        try:
            sig = self.db.decode_message(fid, msg.data, decode_choices=False, scaling=True)
        except (cantools.database.DecodeError, ValueError, KeyError):
            return
        if fid == FAULT:
            f = self._fault_from(sig)
            self._faults.append(f)
            self._pending_faults.append(f)
        elif fid == HEARTBEAT:
            hb = Heartbeat(
                counter=sig["Hb_Counter"], state=SimState(sig["Hb_State"]),
                status=Status(sig["Hb_Status"]), protocol_version=sig["Hb_ProtocolVersion"],
                uptime_ms=sig["Hb_UptimeMs"], rt_ticks=sig["Hb_RtTicks"],
                rt_overruns=sig["Hb_RtOverruns"], jitter_max_us=sig["Hb_JitterMax"],
                jitter_mean_us=sig["Hb_JitterMean"], jitter_p99_us=sig["Hb_JitterP99"],
                rt_rate_hz=sig["Hb_RtRate"], rx_frames=sig["Hb_RxFrames"],
                rx_rejected=sig["Hb_RxRejected"], fault_count=sig["Hb_FaultCount"],
                tx_errors=sig["Hb_TxErrors"], sim_time=sig["Hb_SimTime"],
                received=self.clock())
            self.last_heartbeat = hb
            self._heartbeats.append(hb)
        else:
            tick = sig["Box_Tick" if fid == ST_BOX else _TICK_SIGNAL[fid % LEG_OFFSET + 0x200]]
            parts = self._partial.setdefault(tick, {})
            parts[fid] = sig
            robot = ST_BOX in parts   # a robot sample: ST_BOX comes first
            last = ST_STATUS + LEG_OFFSET * (ROBOT_LEGS - 1) if robot else ST_STATUS
            if fid == last:
                del self._partial[tick]
                # older incomplete samples will never complete
                for old in [k for k in self._partial if k != tick]:
                    del self._partial[old]
                ids = ROBOT_STATE_IDS if robot else STATE_IDS
                if all(i in parts for i in ids):
                    s = self._robot_state_from(parts) if robot else self._state_from(parts)
                    self.last_state = s
                    self._states.append(s)

    def _fault_from(self, sig: dict) -> Fault:
        code = FaultCode(sig["Fault_Code"]) if sig["Fault_Code"] in FaultCode._value2member_map_ \
            else sig["Fault_Code"]
        f = Fault(code=code, frame_id=sig["Fault_FrameId"], frame_len=sig["Fault_FrameLen"],
                  seq=sig["Fault_Seq"], detail=sig["Fault_Detail"], value=sig["Fault_Value"],
                  step_count=sig["Fault_StepCount"], count=sig["Fault_Count"])
        if f.code in (FaultCode.NOT_FINITE, FaultCode.OUT_OF_RANGE):
            f.signal = self.signal_at(f.frame_id, f.detail)
        return f

    def signal_at(self, frame_id: int, start_bit: int) -> str | None:
        """Name of the signal of a frame starting at a bit (Fault_Detail of range faults)."""
        try:
            msg = self.db.get_message_by_frame_id(frame_id)
        except KeyError:
            return None
        return next((s.name for s in msg.signals if s.start == start_bit), None)

    def _state_from(self, parts: dict[int, dict], take_faults: bool = True) -> State:
        allsig: dict = {}
        for fid in STATE_IDS:
            allsig.update(parts[fid])
        st = parts[ST_STATUS]
        faults = []
        if take_faults:
            faults, self._pending_faults = self._pending_faults, []
        return State(
            q=np.array([allsig[n] for n in Q_SIGNALS]),
            qd=np.array([allsig[n] for n in QD_SIGNALS]),
            lengths=np.array([allsig[f"Act_{a}_length"] for a in ACTUATORS]),
            rates=np.array([allsig[f"Act_{a}_rate"] for a in ACTUATORS]),
            forces=np.array([allsig[f"Act_{a}_force"] for a in ACTUATORS]),
            reactions=np.array([allsig[n] for n in REACTION_SIGNALS]).reshape(8, 3),
            t=st["St_Time"], step_count=st["St_StepCount"], residual=st["St_Residual"],
            condition=st["St_Condition"], status=Status(st["St_Status"]),
            stroke_mask=st["St_StrokeMask"], state=SimState(st["St_State"]),
            legsim_status=st["St_LegsimStatus"], last_fault=FaultCode(st["St_LastFault"]),
            iterations=st["St_Iterations"], variant=Variant(st["St_Variant"]),
            integrator=Integrator(st["St_Integrator"]), act_seq=st["St_ActSeq"],
            ctrl_seq=st["St_CtrlSeq"], step_ns=st["St_StepSize"], faults=faults,
            received=self.clock())

    def _robot_state_from(self, parts: dict[int, dict]) -> State:
        """The robot's sample: leg k's frames decoded as the one leg's, placed in the core's
        order (box, leg 0, leg 1)."""
        box = parts[ST_BOX]
        legs = []
        for k in range(ROBOT_LEGS):
            one = {i: parts[i + LEG_OFFSET * k] for i in STATE_IDS}
            leg = self._state_from(one, take_faults=False)
            legs.append(leg)
        s = legs[0]
        s.q = np.concatenate([[box["Box_x"], box["Box_y"], box["Box_phi"]]] + [leg.q for leg in legs])
        s.qd = np.concatenate([[box["Box_vx"], box["Box_vy"], box["Box_omega"]]] + [leg.qd for leg in legs])
        for name in ("lengths", "rates", "forces"):
            setattr(s, name, np.concatenate([getattr(leg, name) for leg in legs]))
        s.reactions = np.concatenate([leg.reactions for leg in legs])
        s.stroke_mask = sum(leg.stroke_mask << (2 * k) for k, leg in enumerate(legs))
        s.act_seqs = tuple(leg.act_seq for leg in legs)
        s.statuses = tuple(leg.status for leg in legs)
        s.legs = ROBOT_LEGS
        s.contacts = []
        for k in range(ROBOT_LEGS):
            c = parts[ST_CONTACT + LEG_OFFSET * k]
            s.contacts.append(Contact(
                state=ContactState(c["Ct_State"]), events=ContactEvent(c["Ct_Events"]),
                normal=c["Ct_Normal"], tangential=c["Ct_Tangential"],
                friction_use=c["Ct_FrictionUse"], x=c["Ct_X"], y=c["Ct_Y"], slip=c["Ct_Slip"],
                impulse_n=c["Ct_ImpulseN"], impulse_t=c["Ct_ImpulseT"]))
        s.faults, self._pending_faults = self._pending_faults, []
        return s

    def poll(self, timeout: float = 0.0) -> bool:
        """Reads what the bus has within timeout; True if a frame was read."""
        msg = self.bus.recv(timeout)
        if msg is None:
            return False
        self._handle(msg)
        # Then what is queued, within the caller's time budget: on a bus faster than this
        # process decodes (an emulated VM in real time) an unbounded drain never returns.
        end = self.clock() + max(timeout, 0.05)
        while self.clock() < end and (msg := self.bus.recv(0)) is not None:
            self._handle(msg)
        return True

    def _wait(self, ready: Callable[[], object], timeout: float, what: str):
        deadline = self.clock() + timeout
        while True:
            got = ready()
            if got is not None and got is not False:
                return got
            left = deadline - self.clock()
            if left <= 0:
                raise HilError(f"no {what} from hil_sim within {timeout:g} s "
                               f"(is it running on this bus?)")
            self.poll(min(left, 0.1))

    # ---- requests ----------------------------------------------------------------------

    def _control(self, command: Command, timeout: float | None = None, **signals) -> State:
        seq = self.next_seq(CONTROL)
        values = {"Ctrl_Seq": seq, "Ctrl_Command": int(command), "Ctrl_StepSize": 1_000_000,
                  "Ctrl_NSteps": 1, "Ctrl_RtStepsPerTick": 1}
        values.update(signals)
        self._send(self.encode("CONTROL", values))

        def answer():
            for s in self._states:  # the sample answering this frame; others stay queued
                if s.ctrl_seq == seq:
                    self._states.remove(s)
                    return s
            for f in self._faults:
                if f.frame_id == CONTROL and f.seq == seq:
                    if f.code == FaultCode.SOLVER and command != Command.RESET:
                        continue  # a failed step: its sample (HALTED) follows, with the fault
                    self._faults.remove(f)
                    raise HilFault(f)
            return None

        return self._wait(answer, self.timeout if timeout is None else timeout,
                          f"answer to {command.name} (seq {seq})")

    def reset(self, variant: str | int = "revolute", integrator: str | int = "rk4",
              step_s: float = 1e-3, pose: int = 0, *, lengths=None, hold_length: bool = False,
              disable: int = 0, cmd_timeout_ms: int | None = None, contact_law: str | int = 0,
              free_contacts: int = 0, start: dict | None = None) -> State:
        """New session: builds the sim, assembles the pose (then the actuator lengths, if
        given) and sets every actuator to zero force (or, hold_length, to hold its assembled
        length); lockstep mode. cmd_timeout_ms: None = hil_sim's default, 0 = no timeout.
        The robot: contact_law ("lcp" 0, "paper" 1) and free_contacts (bit k: foot k free
        after the assembly on the ground); start (a scene's [start]: lift, tilt, velocity, spin,
        and the feet given stuck_contacts, sliding_contacts as bit masks) goes first, in a
        START_CMD that this RESET uses (a refused one raises its HilFault). Returns the
        assembled state (step 0)."""
        step_ns = round(step_s * 1e9)
        timeout = CMD_TIMEOUT_DEFAULT if cmd_timeout_ms is None else \
            (CMD_TIMEOUT_NONE if cmd_timeout_ms == 0 else int(cmd_timeout_ms))
        sig = {"Ctrl_Variant": _enum(Variant, variant), "Ctrl_Integrator": _enum(Integrator, integrator),
               "Ctrl_Pose": pose, "Ctrl_StepSize": step_ns, "Ctrl_Disable": disable,
               "Ctrl_ActInit": 1 if hold_length else 0, "Ctrl_CmdTimeout": timeout,
               "Ctrl_ContactLaw": _enum(ContactLaw, contact_law), "Ctrl_FreeContacts": int(free_contacts)}
        if lengths is not None:   # a leg's, or the robot's: leg 0's, then leg 1's, ...
            sig["Ctrl_UseLengths"] = 1
            for i, v in enumerate(lengths):
                leg, a = divmod(i, len(ACTUATORS))
                sig[leg_frame(f"Ctrl_Length_{ACTUATORS[a]}", leg)] = float(v)
        self._states.clear()
        if start is not None:
            self.send_start(**start)
        state = self._control(Command.RESET, **sig)
        if start is not None:   # hil_sim answers frames in order: a START_CMD's FAULT came first
            for f in list(self._faults):
                if f.frame_id == START_CMD:
                    self._faults.remove(f)
                    raise HilFault(f)
        return state

    def send_start(self, lift: float = 0.0, tilt: float = 0.0, velocity=(0.0, 0.0), spin: float = 0.0,
                   stuck_contacts: int = 0, sliding_contacts: int = 0, use: bool = True) -> int:
        """One START_CMD: the next RESET moves the robot's stance rigidly (float32 values, as
        the DBC carries them). Returns its counter."""
        seq = self.next_seq(START_CMD)
        self._send(self.encode("START_CMD", {
            "Start_Seq": seq, "Start_Use": 1 if use else 0, "Start_StuckContacts": int(stuck_contacts),
            "Start_SlidingContacts": int(sliding_contacts), "Start_Lift": float(lift),
            "Start_Tilt": float(tilt), "Start_Vx": float(velocity[0]), "Start_Vy": float(velocity[1]),
            "Start_Spin": float(spin)}))
        return seq

    def step(self, n: int = 1, timeout: float | None = None) -> State:
        """Lockstep: exactly n fixed steps, then the state after them (n = 0: no step, the
        contact modes checked at the current state and commands, and the state there)."""
        return self._control(Command.STEP, timeout if timeout is not None else self.timeout + 2e-3 * n,
                             Ctrl_NSteps=int(n))

    def start_realtime(self, decimation: int | None = None, steps_per_tick: int = 1) -> State:
        """Real time at one tick per steps_per_tick * step_s; a state sample every
        `decimation` ticks (None: hil_sim's --decimation). Returns the state at the start."""
        return self._control(Command.START_RT, Ctrl_RtDecimation=decimation or 0,
                             Ctrl_RtStepsPerTick=steps_per_tick)

    def stop_realtime(self) -> State:
        """Back to lockstep (paused); returns the state where it stopped."""
        return self._control(Command.STOP_RT)

    stop = stop_realtime

    def command(self, upper: tuple[ActMode, float] | None = None,
                lower: tuple[ActMode, float] | None = None, leg: int = 0) -> int:
        """One ACT_CMD (leg k of the robot: ACT_CMD_Lk): (mode, setpoint) per actuator, None =
        keep. Returns its counter."""
        fid = ACT_CMD + LEG_OFFSET * leg
        seq = self.next_seq(fid)
        sig = {"Act_Seq": seq}
        for name, cmd in (("upper", upper), ("lower", lower)):
            mode, value = cmd if cmd is not None else (ActMode.KEEP, 0.0)
            sig[f"Act_Mode_{name}"] = int(mode)
            sig[f"Act_Setpoint_{name}"] = float(value)
        self._send(self.encode(leg_frame("ACT_CMD", leg), sig))
        return seq

    def command_force(self, actuator: int | str, newtons: float) -> int:
        """Axial force on one actuator (N, > 0 extends, |F| <= max_force)."""
        return self._command_one(actuator, ActMode.FORCE, newtons)

    def command_length(self, actuator: int | str, metres: float) -> int:
        """The servo of one actuator holds a length (m, inside the stroke)."""
        return self._command_one(actuator, ActMode.LENGTH, metres)

    def keepalive(self) -> int:
        """An ACT_CMD that changes nothing but feeds the command timeout."""
        return self.command()

    def _command_one(self, actuator, mode, value) -> int:
        """actuator: 'upper'/'lower' or an index (the robot: leg a // 2's actuator a % 2)."""
        a = ACTUATORS.index(actuator) if isinstance(actuator, str) else int(actuator)
        leg, a = divmod(a, len(ACTUATORS))
        cmds: list = [None] * len(ACTUATORS)
        cmds[a] = (mode, value)
        return self.command(*cmds, leg=leg)

    def set_load(self, index: int, fx: float, fy: float = 0.0, leg: int = 0) -> int:
        """A force element's value (0 = foot_load: world force (fx, fy) N); of leg k of the
        robot (its own force elements) in LOAD_CMD_Lk."""
        fid = LOAD_CMD + LEG_OFFSET * leg
        seq = self.next_seq(fid)
        self._send(self.encode(leg_frame("LOAD_CMD", leg),
                                  {"Load_Seq": seq, "Load_Index": index,
                                   "Load_Value1": float(fx), "Load_Value2": float(fy)}))
        return seq

    # ---- streams -----------------------------------------------------------------------

    def read_state(self, timeout: float | None = None) -> State:
        """The next state sample (real time: the periodic ones)."""
        return self._wait(lambda: self._states.popleft() if self._states else None,
                          self.timeout if timeout is None else timeout, "state sample")

    def states(self, duration: float) -> Iterator[State]:
        """State samples for `duration` seconds of wall time."""
        end = self.clock() + duration
        while (left := end - self.clock()) > 0:
            if self._states:
                yield self._states.popleft()
            else:
                self.poll(min(left, 0.05))
        while self._states:
            yield self._states.popleft()

    def wait_fault(self, timeout: float | None = None, code: FaultCode | None = None) -> Fault:
        """The next FAULT (of that code) received, waiting up to timeout."""
        def match():
            for f in self._faults:
                if code is None or f.code == code:
                    self._faults.remove(f)
                    return f
            return None
        return self._wait(match, self.timeout if timeout is None else timeout, "FAULT")

    def faults(self) -> list[Fault]:
        """Faults received and not yet taken by wait_fault (and takes them)."""
        self.poll(0)
        out = list(self._faults)
        self._faults.clear()
        return out

    def heartbeat(self, timeout: float | None = None) -> Heartbeat:
        """The next HEARTBEAT (every 100 ms by default) sent after this call."""
        # Older ones still in the socket's buffer do not count, nor are they part of a traced
        # session: the trace starts with what came after this call, so that its replay (whose
        # clock starts at the trace's first frame) waits for the same HEARTBEAT as live.
        trace, self._trace = self._trace, None
        try:
            self.poll(0)
        finally:
            self._trace = trace
        self._heartbeats.clear()
        return self._wait(lambda: self._heartbeats.popleft() if self._heartbeats else None,
                          self.timeout if timeout is None else timeout, "HEARTBEAT")

    def drain(self, quiet: float = 0.05) -> None:
        """Reads and forgets everything until the bus has been quiet for `quiet` seconds."""
        while self.poll(quiet):
            pass
        self._states.clear()
        self._faults.clear()
        self._pending_faults.clear()


def _enum(kind: type[enum.IntEnum], value: str | int) -> int:
    if isinstance(value, str):
        return int(kind[value.upper()])
    return int(kind(value))


__all__ = [
    "HilLink", "State", "Fault", "Heartbeat", "HilError", "HilFault", "bus_config",
    "Contact", "ContactState", "ContactEvent", "ContactLaw", "LEG_OFFSET", "ROBOT_STATE_IDS",
    "Command", "Variant", "Integrator", "ActMode", "SimState", "FaultCode", "Status",
    "BODIES", "JOINTS", "ACTUATORS", "DBC_PATH", "CMD_TIMEOUT_NONE",
    "DISABLE_GRAVITY", "DISABLE_FORCE_ELEMENTS", "DISABLE_REACTIONS", "DISABLE_PROJECTION",
    "DISABLE_ACTUATORS", "DISABLE_STROKE_LIMITS", "DISABLE_ACCELERATIONS",
]
