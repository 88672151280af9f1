"""Plots and animation of the two-leg robot on the ground (issue 9, section 7).

matplotlib with the Agg backend (no display needed); the GIF goes through
matplotlib's PillowWriter (Pillow comes with matplotlib), an MP4 only when
ffmpeg is on the PATH.

RobotTrajectory     what every source fills: the core, the CLI's output, the
                    reference (RobotTrajectory.from_reference)
plot_snapshots      stick figures of the box and both legs at chosen instants, a
                    strip of panels, older instants faded behind; the ground line,
                    per foot its contact state (marker) and ground force (arrow)
plot_time_series    box x, y, phi; per foot N and T with the friction cone; the
                    contact states
write_robot_animation   a scene as GIF (or MP4) with a time label

    python -m legsim_bench.report.robot_plots --reference fig7 -o out/robot/

runs the reference's Fig. 7 Scene A (docs/design/robot-on-ground.md section 7)
and writes robot_snapshots.png, robot_time_series.png and robot.gif.

Conventions are the model files' (leg.toml): a body's axis is u(phi) =
(sin phi, -cos phi); a leg body is drawn as the segment between its ends
(-L/2, 0) and (L/2, 0) along that axis, which holds every joint point of
leg.toml (all on the axis). The box is the rectangle of its size, rotated by
its phi about its centre. The ground line passes through ``ground_point`` at
angle ``ground_slope``: tangent t = (cos, sin), normal n = (-sin, cos) up; the
ground force on a foot is N n + T t.
"""
from __future__ import annotations

import argparse
import math
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from ..reference import ForceCommand, LengthCommand
from ..reference.robot import RobotModel
from ..scene import find_root

__all__ = ["FREE", "STUCK", "SLIDING", "STATE_NAMES", "RobotTrajectory", "RobotArtists",
           "plot_snapshots", "snapshot_samples", "CONTACT_EVENTS", "plot_time_series", "write_robot_animation", "reference_fig7",
           "write_robot_plots", "main"]

# contact states, in the order of the core's legsim_contact_state {FREE, STUCK, SLIDING}
FREE, STUCK, SLIDING = 0, 1, 2
STATE_NAMES = ("free", "stuck", "sliding")
# marker, face colour, edge colour per state (distinct in shape and colour)
_STATE_STYLE = {FREE: ("o", "none", "0.35"), STUCK: ("s", "tab:green", "darkgreen"),
                SLIDING: ("D", "tab:orange", "saddlebrown")}
_LEG_COLOURS = ("tab:blue", "tab:purple", "tab:cyan", "tab:brown")
_ARROW_COLOUR = "tab:red"


def _plt():
    # matplotlib (heavy, optional for the rest of the bench) is imported when a figure is drawn,
    # here and in the drawing functions below
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


def _u(phi):
    """Body axis u(phi) = (sin, -cos) for scalar or array phi: (..., 2)."""
    return np.stack([np.sin(phi), -np.cos(phi)], axis=-1)


def _rot(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def _states(values, shape) -> np.ndarray:
    """Contact states as int codes from codes or names ('free', 'stuck', 'sliding')."""
    a = np.asarray(values)
    if a.dtype.kind in "US":
        lut = {n: i for i, n in enumerate(STATE_NAMES)}
        bad = sorted({str(x) for x in a.reshape(-1)} - set(lut))
        if bad:
            raise ValueError(f"contact: unknown state(s) {bad}; use {list(STATE_NAMES)}")
        a = np.vectorize(lut.__getitem__, otypes=[int])(a)
    a = np.asarray(a)
    if a.shape != shape:
        raise ValueError(f"contact: shape {a.shape}, expected {shape}")
    if a.size and (a.dtype.kind not in "iu" or a.min() < 0 or a.max() > 2):
        raise ValueError(f"contact: states are {FREE} (free), {STUCK} (stuck), {SLIDING} (sliding)")
    return a.astype(int)


# the contact events (legsim_event bits 4-7) and the state change each one is
CONTACT_EVENTS = {"liftoff": ("stuck", "sliding"), "touchdown": ("free",),
                  "stick_to_slip": ("stuck",), "slip_to_stick": ("sliding",)}
_EVENT_TO = {"liftoff": "free", "touchdown": None, "stick_to_slip": "sliding", "slip_to_stick": "stuck"}


def _foot_events(names, before, after, events) -> list[str]:
    """A sample's contact events ("liftoff", ...: the core's, for every foot at once) as
    "FOOT EVENT", each put on the foot whose state changed that way (else unnamed)."""
    out = []
    for e in events:
        if e not in CONTACT_EVENTS:
            continue
        feet = [f for f, a, b in zip(names, before, after) if a != b and a in CONTACT_EVENTS[e]
                and (_EVENT_TO[e] is None or b == _EVENT_TO[e])] if before is not None else []
        out += [f"{f} {e}" for f in feet] or [e]
    return out


@dataclass
class RobotTrajectory:
    """A run of the robot, N samples, nb bodies, nf feet (any source).

    t (N,) s; q (N, nb, 3) world (x, y, phi) per body in ``body_names`` order,
    m and rad; ``body_lengths`` (nb,) m, the drawn segment of each leg body
    (the box's entry is not used); ``box`` the box's body index, ``box_size``
    (w, h) m. Per foot (``foot_names``): ``feet`` (N, nf, 2) world position,
    ``contact`` (N, nf) state codes FREE / STUCK / SLIDING (or their names),
    ``normal``, ``tangential`` (N, nf) the ground force on the foot along the
    ground normal and tangent, N. The ground line: ``ground_point`` (2,) m,
    ``ground_slope`` rad, friction ``mu_static``, ``mu_kinetic``.
    """
    t: np.ndarray
    body_names: list
    q: np.ndarray
    body_lengths: np.ndarray
    box_size: np.ndarray
    foot_names: list
    feet: np.ndarray
    contact: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    ground_point: np.ndarray
    ground_slope: float
    mu_static: float
    mu_kinetic: float
    box: int = 0
    title: str = ""
    events: Optional[list] = None   # per sample: its contact events, "left.foot liftoff", ...

    def __post_init__(self):
        f = lambda x: np.asarray(x, float)  # noqa: E731
        self.t, self.q, self.body_lengths = f(self.t), f(self.q), f(self.body_lengths)
        self.box_size, self.feet = f(self.box_size), f(self.feet)
        self.normal, self.tangential = f(self.normal), f(self.tangential)
        self.ground_point, self.ground_slope = f(self.ground_point), float(self.ground_slope)
        self.mu_static, self.mu_kinetic = float(self.mu_static), float(self.mu_kinetic)
        self.body_names, self.foot_names = list(self.body_names), list(self.foot_names)
        N, nb, nf = len(self.t), len(self.body_names), len(self.foot_names)
        want = {"t": (N,), "q": (N, nb, 3), "body_lengths": (nb,), "box_size": (2,),
                "feet": (N, nf, 2), "normal": (N, nf), "tangential": (N, nf), "ground_point": (2,)}
        for name, shape in want.items():
            got = getattr(self, name).shape
            if got != shape:
                raise ValueError(f"RobotTrajectory.{name}: shape {got}, expected {shape}")
        if N == 0:
            raise ValueError("RobotTrajectory: no samples")
        if np.any(np.diff(self.t) <= 0):
            raise ValueError("RobotTrajectory.t: times must increase")
        for name in ("t", "q", "body_lengths", "box_size", "feet", "normal", "tangential",
                     "ground_point", "ground_slope", "mu_static", "mu_kinetic"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise ValueError(f"RobotTrajectory.{name}: not finite")
        if not 0 <= self.box < nb:
            raise ValueError(f"RobotTrajectory.box: {self.box} is not a body index (0..{nb - 1})")
        if not 0.0 <= self.mu_kinetic <= self.mu_static:
            raise ValueError("RobotTrajectory: need 0 <= mu_kinetic <= mu_static")
        self.contact = _states(self.contact, (N, nf))
        self.events = [[] for _ in range(N)] if self.events is None else [list(e) for e in self.events]
        if len(self.events) != N:
            raise ValueError(f"RobotTrajectory.events: {len(self.events)} samples, expected {N}")

    def event_samples(self) -> list[tuple[int, str]]:
        """(sample index, its events joined) of every sample with a contact event."""
        return [(k, ", ".join(e)) for k, e in enumerate(self.events) if e]

    # --------------------------------------------------------- construction
    @classmethod
    def from_reference(cls, model, result, title: str = "") -> "RobotTrajectory":
        """From RobotModel.simulate's RobotResult: both feet stuck throughout
        (the reference's stance), the feet at ``result.feet``."""
        N = len(result.t)
        lengths = np.zeros(model.nb)
        for leg in model.legs:
            for i, b in enumerate(leg.model.bodies):
                lengths[leg.body0 + i] = b.length
        nf = len(model.foot_names)
        g = model.ground
        return cls(t=result.t, body_names=model.body_names, q=result.q.reshape(N, model.nb, 3),
                   body_lengths=lengths, box_size=model.box_size, foot_names=model.foot_names,
                   feet=np.broadcast_to(result.feet, (N, nf, 2)),
                   contact=np.full((N, nf), STUCK), normal=result.normal,
                   tangential=result.tangential, ground_point=g.point, ground_slope=g.slope,
                   mu_static=g.mu_static, mu_kinetic=g.mu_kinetic, box=0, title=title)

    @classmethod
    def from_recording(cls, rec: dict, model, box_size, title: str = "",
                       ground: dict | None = None) -> "RobotTrajectory":
        """From a robot scene recorded over CAN (the bench's recording: per sample the flat
        q of every body and per foot its ST_CONTACT state, N, T and x, y). ``model``: the
        scene's ``legsim.Model`` (body names and lengths, feet, ground); ``box_size`` (w, h) m
        as for from_cli_json; ``ground``: the ground the run had (point, slope, mu_static,
        mu_kinetic: a scene's [ground]), else the model's."""
        feet, g, nb = model.contact_names, ground or model.ground, len(model.body_names)
        # The RESET's sample (step 0) is left out, as legsim_cli leaves out its first sample's
        # forces: its ground forces are the assembly's multipliers (32.6 N per foot for the
        # stand), not the dynamics' forces, which the first step solves (159-180 N).
        S = [s for s in rec["samples"] if s.get("step", 1) > 0 and
             len(s.get("contacts") or []) == len(feet) and
             all(c["normal"] is not None and c["tangential"] is not None for c in s["contacts"])]
        if not S:
            raise ValueError("recording: no sample with every foot's ST_CONTACT (a robot scene?)")
        per = lambda key: [[c[key] for c in s["contacts"]] for s in S]  # noqa: E731
        events = [[f"{f} {e}" for f, c in zip(feet, s["contacts"]) for e in c.get("events", [])
                   if e in CONTACT_EVENTS] for s in S]
        return cls(t=[s["t"] for s in S], body_names=model.body_names,
                   q=np.array([s["q"] for s in S], float).reshape(len(S), nb, 3),
                   body_lengths=model.lengths, box_size=box_size, foot_names=feet,
                   feet=np.stack([np.array(per("x"), float), np.array(per("y"), float)], axis=-1),
                   contact=np.array(per("state")), normal=per("normal"), tangential=per("tangential"),
                   ground_point=g["point"], ground_slope=g["slope"], mu_static=g["mu_static"],
                   mu_kinetic=g["mu_kinetic"], box=0, title=title, events=events)

    @classmethod
    def from_cli_json(cls, out: dict, box_size, title: str = "") -> "RobotTrajectory":
        """From legsim_cli's JSON output of a robot scene (its "contacts", "ground" and
        "body_lengths"; scenes/README.md). ``box_size`` (w, h) m: the robot file's [box] size
        (the core keeps only the width). Samples whose ground forces are not solved (null:
        a dynamics run's first) are left out, never filled in."""
        S = [s for s in out["samples"] if s.get("contacts") and
             all(v["normal"] is not None and v["tangential"] is not None for v in s["contacts"].values())]
        if not S:
            raise ValueError("legsim_cli output: no sample with solved ground forces (a robot scene?)")
        bodies, feet, g = out["bodies"], out["contacts"], out["ground"]
        per = lambda key: [[s["contacts"][f][key] for f in feet] for s in S]  # noqa: E731
        states = per("state")
        events = [_foot_events(feet, states[k - 1] if k else None, states[k], s.get("events") or [])
                  for k, s in enumerate(S)]
        return cls(t=[s["t"] for s in S], body_names=bodies,
                   q=[[[s["q"][b][c] for c in ("x", "y", "phi")] for b in bodies] for s in S],
                   body_lengths=out["body_lengths"], box_size=box_size, foot_names=feet,
                   feet=np.stack([np.array(per("x"), float), np.array(per("y"), float)], axis=-1),
                   contact=np.array(states), normal=per("normal"), tangential=per("tangential"),
                   ground_point=g["point"], ground_slope=g["slope"], mu_static=g["mu_static"],
                   mu_kinetic=g["mu_kinetic"], box=0, title=title, events=events)

    # ------------------------------------------------------------- geometry
    @property
    def tangent(self) -> np.ndarray:
        return np.array([math.cos(self.ground_slope), math.sin(self.ground_slope)])

    @property
    def ground_normal(self) -> np.ndarray:
        return np.array([-math.sin(self.ground_slope), math.cos(self.ground_slope)])

    def box_corners(self, k: int) -> np.ndarray:
        """(4, 2) world corners of the box at sample k (counter-clockwise from lower left)."""
        w, h = self.box_size
        local = 0.5 * np.array([[-w, -h], [w, -h], [w, h], [-w, h]])
        x, y, phi = self.q[k, self.box]
        return np.array([x, y]) + local @ _rot(phi).T

    def segments(self, k: int) -> np.ndarray:
        """(nb, 2, 2) proximal and distal end of every body at sample k (box: its centre twice)."""
        r, phi = self.q[k, :, :2], self.q[k, :, 2]
        half = 0.5 * self.body_lengths[:, None] * _u(phi)
        half[self.box] = 0.0
        return np.stack([r - half, r + half], axis=1)

    def ground_forces(self, k: Optional[int] = None) -> np.ndarray:
        """World ground force on each foot, N n + T t ((T, N) rotated by the slope): (nf, 2) or (N, nf, 2)."""
        G = self.tangential[..., None] * self.tangent + self.normal[..., None] * self.ground_normal
        return G if k is None else G[k]

    def leg_of(self, b: int) -> str:
        """The leg a body belongs to: its name's prefix before the first '.'."""
        name = self.body_names[b]
        return name.split(".", 1)[0] if "." in name else ""

    def leg_colours(self) -> dict:
        """A colour per leg, in the order the legs' bodies come (right first in robot.toml)."""
        legs = []
        for b in range(len(self.body_names)):
            if b != self.box and self.leg_of(b) not in legs:
                legs.append(self.leg_of(b))
        return {leg: _LEG_COLOURS[i % len(_LEG_COLOURS)] for i, leg in enumerate(legs)}

    def at_times(self, times: Sequence[float]) -> np.ndarray:
        """Sample indices nearest to the given times."""
        times = np.asarray(times, float)
        i = np.clip(np.searchsorted(self.t, times), 1, len(self.t) - 1) if len(self.t) > 1 else \
            np.zeros(len(times), int)
        if len(self.t) > 1:
            i = np.where(np.abs(self.t[i - 1] - times) <= np.abs(self.t[i] - times), i - 1, i)
        return i.astype(int)


# ---------------------------------------------------------------- drawing
def nice_force_scale(traj: RobotTrajectory, arrow_m: float = 0.4) -> float:
    """N per m for the arrows: a 1-2-5 number so the largest force is at most ``arrow_m`` long."""
    fmax = float(np.max(np.hypot(traj.normal, traj.tangential), initial=0.0))
    if fmax <= 0.0:
        return 100.0
    raw = fmax / arrow_m
    e = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * e >= raw:
            return m * e
    return 10.0 * e


def _scale_bar_force(n_per_m: float) -> float:
    """A round force whose arrow is 0.05-0.15 m long."""
    for f in (1, 2, 5):
        for e in range(-3, 7):
            F = f * 10.0 ** e
            if 0.05 <= F / n_per_m <= 0.15:
                return F
    return 0.1 * n_per_m


def _body_width(name: str) -> float:
    """Line widths in points: actuator cylinders as tubes, rods thin, links in between."""
    if "cylinder" in name:
        return 6.0
    if "rod" in name:
        return 2.0
    return 3.5


def scene_limits(traj: RobotTrajectory, n_per_m: float, idx=None, margin: float = 0.08):
    """x and y limits holding every drawn thing of the samples idx, and some ground."""
    idx = range(len(traj.t)) if idx is None else idx
    pts = []
    for k in idx:
        pts.append(traj.box_corners(k))
        pts.append(traj.segments(k).reshape(-1, 2))
        pts.append(traj.feet[k])
        pts.append(traj.feet[k] + traj.ground_forces(k) / n_per_m)
    P = np.concatenate(pts)
    lo, hi = P.min(axis=0) - margin, P.max(axis=0) + margin
    # some ground below the lowest foot, so the hatching reads as ground
    lo[1] = min(lo[1], float(np.min(traj.feet[list(idx), :, 1])) - 0.12)
    return lo, hi


class RobotArtists:
    """The artists of one robot drawing on an axes; ``update(k)`` moves them to sample k.

    box: Polygon; bodies: Line2D per body (segment); feet: Line2D per contact
    state holding the feet in that state; arrows: one Quiver of the ground
    forces (data units: n_per_m N per m).
    """

    def __init__(self, ax, traj: RobotTrajectory, k: int, n_per_m: float, alpha: float = 1.0,
                 arrows: bool = True, feet: bool = True, zorder: float = 2.0, lw: float = 1.0):
        from matplotlib.patches import Polygon
        self.traj, self.n_per_m = traj, n_per_m
        colour = traj.leg_colours()
        self.box = Polygon(traj.box_corners(k), closed=True, facecolor="0.85", edgecolor="0.2",
                           lw=1.5, alpha=alpha, zorder=zorder)
        ax.add_patch(self.box)
        self.bodies = []
        for b, name in enumerate(traj.body_names):
            if b == traj.box:
                self.bodies.append(None)
                continue
            (line,) = ax.plot([], [], "-", color=colour[traj.leg_of(b)], lw=lw * _body_width(name),
                              alpha=alpha, solid_capstyle="round", zorder=zorder + 0.1)
            self.bodies.append(line)
        self.feet = {}
        if feet:
            for s, (m, fc, ec) in _STATE_STYLE.items():
                (mk,) = ax.plot([], [], m, ms=9 * lw, mfc=fc, mec=ec, mew=1.8 * lw, alpha=alpha, ls="none",
                                zorder=zorder + 0.3)
                self.feet[s] = mk
        self.arrows = None
        if arrows:
            nf = len(traj.foot_names)
            self.arrows = ax.quiver(np.zeros(nf), np.zeros(nf), np.zeros(nf), np.zeros(nf),
                                    angles="xy", scale_units="xy", scale=1.0, color=_ARROW_COLOUR,
                                    width=0.008 * lw, alpha=alpha, zorder=zorder + 0.2)
        self.update(k)

    def update(self, k: int):
        tr = self.traj
        self.box.set_xy(tr.box_corners(k))
        seg = tr.segments(k)
        for b, line in enumerate(self.bodies):
            if line is not None:
                line.set_data(seg[b, :, 0], seg[b, :, 1])
        for s, mk in self.feet.items():
            on = tr.contact[k] == s
            mk.set_data(tr.feet[k, on, 0], tr.feet[k, on, 1])
        if self.arrows is not None:
            G = tr.ground_forces(k) / self.n_per_m
            # a free foot carries no force: its arrow has zero length
            self.arrows.set_offsets(tr.feet[k])
            self.arrows.set_UVC(G[:, 0], G[:, 1])
        return self.artists()

    def artists(self):
        out = [self.box] + [b for b in self.bodies if b is not None] + list(self.feet.values())
        return out + ([self.arrows] if self.arrows is not None else [])


def draw_ground(ax, traj: RobotTrajectory, lo, hi, depth: float = 0.06):
    """The ground line over the view, hatched below; returns (line, fill)."""
    t, nrm = traj.tangent, traj.ground_normal
    span = 4.0 * float(np.max(hi - lo)) + float(np.max(np.abs(traj.ground_point)))
    a = traj.ground_point - span * t
    b = traj.ground_point + span * t
    deg = math.degrees(traj.ground_slope)
    (line,) = ax.plot([a[0], b[0]], [a[1], b[1]], "-", color="saddlebrown", lw=1.5, zorder=1.5,
                      label=f"ground, slope {deg:.3g} deg, mu_s {traj.mu_static:g}")
    poly = np.array([a, b, b - depth * nrm, a - depth * nrm])
    from matplotlib.patches import Polygon
    fill = Polygon(poly, closed=True, facecolor="none", edgecolor="peru", hatch="///", lw=0,
                   zorder=1.0)
    ax.add_patch(fill)
    return line, fill


def _legend_handles(traj: RobotTrajectory, n_per_m: float):
    from matplotlib.lines import Line2D
    h = []
    for leg, c in traj.leg_colours().items():
        h.append(Line2D([], [], color=c, lw=3.5, label=f"{leg} leg" if leg else "leg"))
    for s, (m, fc, ec) in _STATE_STYLE.items():
        h.append(Line2D([], [], marker=m, ms=8, mfc=fc, mec=ec, mew=1.8, ls="none",
                        label=f"foot {STATE_NAMES[s]}"))
    h.append(Line2D([], [], color=_ARROW_COLOUR, lw=2, marker=">", ms=6,
                    label=f"ground force ({n_per_m:g} N per m)"))
    return h


def _scale_bar(ax, n_per_m: float, loc="upper left"):
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar
    F = _scale_bar_force(n_per_m)
    bar = AnchoredSizeBar(ax.transData, F / n_per_m, f"{F:g} N", loc=loc, color=_ARROW_COLOUR,
                          frameon=False, size_vertical=0.004, pad=0.3, sep=3,
                          fontproperties={"size": 8})
    ax.add_artist(bar)
    return bar


def _box_delta(traj: RobotTrajectory, k: int) -> str:
    d = traj.q[k, traj.box] - traj.q[0, traj.box]
    return f"box moved {1e3 * d[0]:+.2f}, {1e3 * d[1]:+.2f} mm, {d[2]:+.5f} rad"


MAX_EVENT_PANELS = 12


def snapshot_samples(traj: RobotTrajectory, n: int = 4) -> np.ndarray:
    """The default instants of the snapshots: n evenly over the run, and every sample with a
    contact event (lift-off, touchdown, stick/slip; the first MAX_EVENT_PANELS), in time order."""
    even = traj.at_times(np.linspace(traj.t[0], traj.t[-1], n))
    events = [k for k, _ in traj.event_samples()][:MAX_EVENT_PANELS]
    return np.array(sorted(set(int(k) for k in even) | set(events)), int)


def plot_snapshots(traj: RobotTrajectory, path, times: Optional[Sequence[float]] = None,
                   n: int = 4, n_per_m: Optional[float] = None, panel_in: float = 3.4):
    """A strip of panels, one per instant (default: n evenly over the run and one at every
    contact event, snapshot_samples); each panel draws its instant in full (feet, ground
    forces, its events in the title) and the earlier instants of the strip faded behind it.
    Equal axis scale."""
    plt = _plt()
    if times is None:
        idx = snapshot_samples(traj, n)
    else:
        times = np.asarray(times, float)
        if times.size == 0:
            raise ValueError("plot_snapshots: no instants")
        if np.any(times < traj.t[0] - 1e-12) or np.any(times > traj.t[-1] + 1e-12):
            raise ValueError(f"plot_snapshots: instants outside the run [{traj.t[0]:g}, {traj.t[-1]:g}] s")
        idx = traj.at_times(times)
    n_per_m = nice_force_scale(traj) if n_per_m is None else float(n_per_m)
    lo, hi = scene_limits(traj, n_per_m, idx)
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])
    fig, axes = plt.subplots(1, len(idx), figsize=(panel_in * len(idx), panel_in * aspect + 1.5),
                             sharey=True, squeeze=False, layout="constrained")
    axes = axes[0]
    drawn = []
    for p, (ax, k) in enumerate(zip(axes, idx)):
        draw_ground(ax, traj, lo, hi)
        for j, kk in enumerate(idx[:p]):
            # older instants: fainter the older they are
            RobotArtists(ax, traj, kk, n_per_m, alpha=0.12 + 0.25 * (j + 1) / (p + 1), arrows=False,
                         feet=False, zorder=2.0)
        drawn.append(RobotArtists(ax, traj, k, n_per_m, zorder=3.0))
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal", adjustable="box")
        ax.grid(True, alpha=0.3)
        what = ("\n" + ", ".join(traj.events[k])) if traj.events[k] else ""
        ax.set_title(f"t = {traj.t[k]:.4g} s{what}\n{_box_delta(traj, k)}", fontsize=9,
                     color="darkred" if what else "black")
        ax.set_xlabel("x (m)")
        _scale_bar(ax, n_per_m, loc="upper left" if p == 0 else "upper right")
    axes[0].set_ylabel("y (m)")
    from matplotlib.lines import Line2D
    handles = _legend_handles(traj, n_per_m)
    if len(idx) > 1:
        handles.append(Line2D([], [], color="0.6", lw=3.5, alpha=0.4, label="earlier panels' instants"))
    ground = axes[0].get_lines()[0]
    fig.legend(handles=handles + [ground], loc="outside lower center", ncol=5,
               fontsize=8, frameon=False)
    title = traj.title or "robot"
    fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path, drawn


def plot_time_series(traj: RobotTrajectory, path, reference: Optional[RobotTrajectory] = None):
    """Box x, y (from the first sample), phi; per foot N and T with the friction
    cone |T| <= mu_s N shaded and mu_k N dashed; the contact states. ``reference``: the
    bench's RobotModel over the times it applies (both feet stuck), drawn dashed black over
    the run's curves. The contact events are marked by vertical lines."""
    plt = _plt()
    nf = len(traj.foot_names)
    rows = max(3, nf + 1)
    fig, axes = plt.subplots(rows, 2, figsize=(11, 2.1 * rows + 0.6), sharex=True)
    t = traj.t
    b0 = traj.q[0, traj.box]
    lab = ["box x - x(0) (mm)", "box y - y(0) (mm)", "box phi (rad)"]
    start = [f"x(0) = {b0[0]:.4f} m", f"y(0) = {b0[1]:.4f} m", None]
    vals = [1e3 * (traj.q[:, traj.box, 0] - b0[0]), 1e3 * (traj.q[:, traj.box, 1] - b0[1]),
            traj.q[:, traj.box, 2]]
    for r in range(rows):
        ax = axes[r, 0]
        if r < 3:
            ax.plot(t, vals[r], "-", color="0.2", lw=1.5, label="run")
            if reference is not None:
                rq = reference.q[:, reference.box]
                ax.plot(reference.t, [1e3 * (rq[:, 0] - b0[0]), 1e3 * (rq[:, 1] - b0[1]), rq[:, 2]][r],
                        "--", color="k", lw=1.0, label="reference (RobotModel)")
                if r == 0:
                    ax.legend(fontsize=7, frameon=False)
            ax.set_ylabel(lab[r] + (f"\n{start[r]}" if start[r] else ""), fontsize=8)
            ax.grid(True, alpha=0.3)
        else:
            ax.axis("off")
    for f in range(nf):
        ax = axes[f, 1]
        N, T = traj.normal[:, f], traj.tangential[:, f]
        ax.fill_between(t, -traj.mu_static * N, traj.mu_static * N, color="tab:green", alpha=0.15,
                        lw=0, label=f"cone |T| <= mu_s N (mu_s {traj.mu_static:g})")
        for sgn in (-1, 1):
            ax.plot(t, sgn * traj.mu_kinetic * N, "--", color="tab:green", lw=0.8,
                    label=f"mu_k N (mu_k {traj.mu_kinetic:g})" if sgn > 0 else None)
        ax.plot(t, N, "-", color="tab:blue", lw=1.5, label="N normal")
        ax.plot(t, T, "-", color=_ARROW_COLOUR, lw=1.5, label="T tangential")
        if reference is not None:
            j = reference.foot_names.index(traj.foot_names[f])
            ax.plot(reference.t, reference.normal[:, j], "--", color="k", lw=1.0,
                    label="reference N, T (RobotModel)")
            ax.plot(reference.t, reference.tangential[:, j], "--", color="k", lw=1.0)
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_ylabel(f"{traj.foot_names[f]} (N)", fontsize=8)
        ax.grid(True, alpha=0.3)
        if f == 0:
            ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    ax = axes[nf, 1]
    legc = traj.leg_colours()
    for f, name in enumerate(traj.foot_names):
        c = legc.get(name.split(".", 1)[0], _LEG_COLOURS[f % len(_LEG_COLOURS)])
        # a small offset per foot so that equal states stay apart
        ax.step(t, traj.contact[:, f] + 0.08 * (f - (nf - 1) / 2), where="post", color=c, lw=1.5,
                label=name)
    ax.set_yticks(range(3), [STATE_NAMES[s] for s in range(3)])
    ax.set_ylim(-0.4, 2.4)
    ax.set_ylabel("contact state", fontsize=8)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    for r in range(nf + 1, rows):
        axes[r, 1].axis("off")
    for k, what in traj.event_samples():   # the contact events, on every time axis
        for ax in list(axes[:3, 0]) + list(axes[:nf + 1, 1]):
            ax.axvline(t[k], color="darkred", lw=0.8, ls=":", alpha=0.8)
        axes[nf, 1].annotate(what, (t[k], 2.3), fontsize=6, color="darkred", rotation=90,
                             ha="right", va="top")
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    # the column bottoms that are switched off leave the x labels to the last drawn row
    axes[2, 0].set_xlabel("t (s)")
    axes[2, 0].xaxis.set_tick_params(labelbottom=True)
    axes[nf, 1].set_xlabel("t (s)")
    axes[nf, 1].xaxis.set_tick_params(labelbottom=True)
    fig.suptitle(f"{traj.title or 'robot'}\nbox pose; per foot the force of the ground on it "
                 "(N along the normal, T along the ground line)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# -------------------------------------------------------------- animation
def animation_frames(traj: RobotTrajectory, fps: float, speed: float = 1.0) -> np.ndarray:
    """Sample index of each frame: frame j shows simulated time t0 + j speed / fps."""
    if not (fps > 0 and speed > 0 and math.isfinite(fps) and math.isfinite(speed)):
        raise ValueError("animation: fps and speed must be positive and finite")
    dt = speed / fps
    n = int(math.floor((traj.t[-1] - traj.t[0]) / dt + 1e-9)) + 1
    return traj.at_times(traj.t[0] + dt * np.arange(n))


def write_robot_animation(traj: RobotTrajectory, path, fps: float = 25.0, speed: float = 1.0,
                          size_px=(400, 300), n_per_m: Optional[float] = None):
    """A GIF (PillowWriter) or, for a .mp4 path, an MP4 (needs ffmpeg) of the run.

    ``speed``: simulated seconds per second of playback (0.1 = ten times slower).
    Returns the path. Frame j shows the sample nearest t0 + j speed / fps."""
    plt = _plt()
    from matplotlib import animation
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"animation: {path.name}: use a .gif or .mp4 file name")
    if suffix == ".mp4" and not animation.writers.is_available("ffmpeg"):
        raise RuntimeError("animation: MP4 needs ffmpeg on the PATH; write a .gif instead")
    frames = animation_frames(traj, fps, speed)
    n_per_m = nice_force_scale(traj) if n_per_m is None else float(n_per_m)
    lo, hi = scene_limits(traj, n_per_m)
    dpi = 100
    fig = plt.figure(figsize=(size_px[0] / dpi, size_px[1] / dpi), dpi=dpi)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    # the view: the scene's limits widened to the figure's aspect, equal scale
    c, span = 0.5 * (lo + hi), hi - lo
    fa = size_px[1] / size_px[0]
    if span[1] / span[0] > fa:
        span[0] = span[1] / fa
    else:
        span[1] = span[0] * fa
    span *= 1.0 + 0.18    # room for the labels at the top
    ax.set_xlim(c[0] - span[0] / 2, c[0] + span[0] / 2)
    ax.set_ylim(c[1] - span[1] / 2 + 0.04 * span[1], c[1] + span[1] / 2 + 0.04 * span[1])
    ax.set_aspect("equal", adjustable="box")
    ax.axis("off")
    draw_ground(ax, traj, lo, hi)
    robot = RobotArtists(ax, traj, int(frames[0]), n_per_m, zorder=3.0, lw=0.7)
    _scale_bar(ax, n_per_m, loc="lower left")
    slow = "" if speed == 1.0 else f" ({1 / speed:.3g}x slower)" if speed < 1 else f" ({speed:.3g}x faster)"
    tlabel = ax.text(0.02, 0.97, "", transform=ax.transAxes, ha="left", va="top", fontsize=9,
                     family="monospace")
    flabel = ax.text(0.98, 0.97, "", transform=ax.transAxes, ha="right", va="top", fontsize=7,
                     family="monospace", color="0.2")
    ax.text(0.98, 0.03, f"arrows {n_per_m:g} N/m", transform=ax.transAxes, ha="right",
            va="bottom", fontsize=7, color=_ARROW_COLOUR)

    def update(j):
        k = int(frames[j])
        arts = robot.update(k)
        tlabel.set_text(f"t = {traj.t[k]:.3f} s{slow}")
        lines = [f"{name.split('.')[0]}: {STATE_NAMES[traj.contact[k, f]]} "
                 f"N {traj.normal[k, f]:6.1f} T {traj.tangential[k, f]:+6.1f}"
                 for f, name in enumerate(traj.foot_names)]
        flabel.set_text("\n".join(lines))
        return arts + [tlabel, flabel]

    anim = animation.FuncAnimation(fig, update, frames=len(frames), blit=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".gif":
        writer = animation.PillowWriter(fps=fps)
    else:
        writer = animation.FFMpegWriter(fps=fps)
    anim.save(str(path), writer=writer, dpi=dpi)
    plt.close(fig)
    return path


# -------------------------------------------------------------- the reference
def reference_fig7(model=None, t_end: float = 0.1, samples: int = 101,
                   constant_force: bool = False) -> RobotTrajectory:
    """The reference's Fig. 7 (docs/design/robot-on-ground.md section 7).

    Scene A (default): from the servo stand equilibrium at rest, the right
    upper actuator in force mode at its hold force + 50 N, the other three on
    their servos. Scene B (``constant_force``): all four at their
    equal_friction statics forces, + 50 N on the right upper, from the stand."""
    if model is None:
        model = RobotModel.from_toml(find_root() / "models" / "robot.toml")
    t_eval = np.linspace(0.0, t_end, samples)
    if constant_force:
        F = model.statics().actuator_forces
        cmds = [ForceCommand(float(F[0]) + 50.0)] + [ForceCommand(float(f)) for f in F[1:]]
        r = model.simulate(t_end, t_eval=t_eval, actuators=cmds)
        title = "Fig. 7 Scene B: constant forces, +50 N right upper"
    else:
        servo = [LengthCommand(float(x)) for x in model.stand_lengths()]
        z = model.equilibrium(servo)
        i0 = z[[2, 3, 4]]
        hold = model.simulate(1e-6, t_eval=[0.0], actuators=servo, i0=i0).actuator_forces[0]
        cmds = [ForceCommand(float(hold[0]) + 50.0)] + servo[1:]
        r = model.simulate(t_end, t_eval=t_eval, actuators=cmds, i0=i0)
        title = f"Fig. 7 Scene A: right upper at hold {hold[0]:.2f} + 50 N, servos hold the rest"
    return RobotTrajectory.from_reference(model, r, title=f"{title} (reference)")


def write_robot_plots(traj: RobotTrajectory, out, fps: float = 25.0, speed: float = 1.0,
                      snapshots: int = 4, animation_format: str = "gif") -> dict:
    """robot_snapshots.png, robot_time_series.png and robot.gif (or .mp4) in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = {"snapshots": plot_snapshots(traj, out / "robot_snapshots.png", n=snapshots)[0],
             "time_series": plot_time_series(traj, out / "robot_time_series.png")}
    files["animation"] = write_robot_animation(traj, out / f"robot.{animation_format}", fps=fps,
                                               speed=speed)
    return files


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m legsim_bench.report.robot_plots",
                                description="Plots and animation of the two-leg robot from the "
                                            "bench's reference model.")
    p.add_argument("--reference", choices=("fig7", "fig7-constant"), required=True,
                   help="fig7: Scene A (servo stand, +50 N right upper for 0.1 s); "
                        "fig7-constant: Scene B (constant forces)")
    p.add_argument("-o", "--out", default="out/robot", help="output directory (default out/robot)")
    p.add_argument("--fps", type=float, default=25.0, help="animation frames per second (25)")
    p.add_argument("--speed", type=float, default=0.1,
                   help="simulated seconds per second of playback (0.1: ten times slower)")
    p.add_argument("--snapshots", type=int, default=4, help="panels in the snapshot strip (4)")
    p.add_argument("--format", choices=("gif", "mp4"), default="gif",
                   help="animation format (mp4 needs ffmpeg)")
    a = p.parse_args(argv)
    if a.format == "mp4" and shutil.which("ffmpeg") is None:
        p.error("--format mp4 needs ffmpeg on the PATH")
    if a.snapshots < 1:
        p.error("--snapshots must be at least 1")
    traj = reference_fig7(constant_force=a.reference == "fig7-constant")
    try:
        files = write_robot_plots(traj, a.out, fps=a.fps, speed=a.speed, snapshots=a.snapshots,
                                  animation_format=a.format)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for k, f in files.items():
        size = Path(f).stat().st_size
        print(f"{k:12s} {f} ({size / 1024:.0f} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
