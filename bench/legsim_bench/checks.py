"""Checks of a recording: hil_sim's states against the bench's own model of the leg.

Three independent sources of truth, none of them the core:

* the reference model (legsim_bench.reference: minimal coordinates, DOP853, Newton-Euler),
  replayed with exactly what the bench sent (the float32 setpoints and loads, held between
  exchanges as hil_sim holds them, and the safe state after a command timeout);
* leg.toml's joint equations, written here (absolute coordinates, as in the paper) and
  evaluated on the received positions: the constraint residual;
* the free-body equations of the six bodies, written here, with the received positions,
  reactions and actuator forces: the static balance.

`evaluate(rec)` returns an Evaluation: the rows of the pass/fail table (CheckResult) and
the arrays behind them (for CSV, JSON and plots).
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .scene import ACTUATORS, Scene, find_root

__all__ = ["Leg", "CheckResult", "Evaluation", "evaluate", "reference_run", "constraint_residual",
           "static_balance", "float32_quantum", "STATUS_BITS"]

# St_Status bits (can/legsim.dbc)
STATUS_BITS = {"ASSEMBLED": 0, "REALTIME": 1, "SAFE_STATE": 2, "STROKE_MIN": 3, "STROKE_MAX": 4,
               "FORCE_SATURATED": 5, "NEAR_SINGULAR": 6, "HALTED": 7, "FAULT": 8,
               "CMD_WATCHDOG": 9, "STEPPING": 10}


def u(phi):
    """Body axis, leg.toml's convention (phi = 0 hangs down)."""
    return np.stack([np.sin(phi), -np.cos(phi)], axis=-1)


def nrm(phi):
    """Body normal (CCW from the axis)."""
    return np.stack([np.cos(phi), np.sin(phi)], axis=-1)


def cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


# ---- leg.toml ------------------------------------------------------------------------

@dataclass
class Joint:
    name: str
    kind: str                 # revolute_to_frame | revolute | prismatic | slot
    bodies: tuple[int, ...]   # 0-based
    points: tuple             # body-fixed (xi, eta) per body, None = the axis (slot)
    frame_point: tuple[float, float] | None = None

    @property
    def n_eq(self) -> int:
        return 1 if self.kind == "slot" else 2


@dataclass
class Leg:
    """The leg of models/leg.toml as this module needs it (its own reading of the file)."""
    body_names: list[str]
    lengths: np.ndarray       # (6,)
    masses: np.ndarray
    inertias: np.ndarray
    joints: list[Joint]
    actuators: list[dict]     # name, cylinder, rod, stroke (min, max), max_force
    gravity: np.ndarray
    load_body: int
    load_point: tuple[float, float]
    variant: str
    frame: dict = field(default_factory=dict)   # named frame points (A, B)

    @classmethod
    def from_toml(cls, path, variant: str = "revolute") -> "Leg":
        data = tomllib.loads(Path(path).read_text())
        ids = {int(b["id"]): i for i, b in enumerate(data["body"])}
        L = np.array([float(b["length"]) for b in data["body"]])
        m = np.array([float(b["mass"]) for b in data["body"]])
        J = np.array([float(b.get("inertia", b["mass"] * b["length"] ** 2 / 12.0)) for b in data["body"]])
        frame = {k: tuple(map(float, v)) for k, v in data.get("frame", {}).items()}
        over = data.get("variant", {}).get(variant, {}) if variant != "revolute" else {}
        if variant != "revolute" and not over:
            raise ValueError(f"leg.toml has no variant {variant!r}")

        def point(bi, end, spec):
            if end == "proximal":
                return (-L[bi] / 2, 0.0)
            if end == "distal":
                return (L[bi] / 2, 0.0)
            if end in ("center", "centre"):
                return (0.0, 0.0)
            if end == "at":
                return tuple(map(float, spec["at"]))
            if end == "axis":
                return None
            raise ValueError(f"unknown end {end!r}")

        joints = []
        for jd in data["joint"]:
            spec = dict(over.get(jd["name"], jd), name=jd["name"])
            kind = spec["kind"]
            if kind == "revolute_to_frame":
                bi = ids[int(spec["body"])]
                fp = spec["point"]
                fp = frame[fp] if isinstance(fp, str) else tuple(map(float, fp))
                joints.append(Joint(spec["name"], kind, (bi,), (point(bi, spec["end"], spec),), fp))
            elif kind in ("revolute", "slot"):
                bs = tuple(ids[int(x)] for x in spec["bodies"])
                joints.append(Joint(spec["name"], kind, bs,
                                    tuple(point(b, e, spec) for b, e in zip(bs, spec["ends"]))))
            elif kind == "prismatic":
                bs = tuple(ids[int(x)] for x in spec["bodies"])
                joints.append(Joint(spec["name"], kind, bs, (None, None)))
            else:
                raise ValueError(f"joint {spec['name']}: unknown kind {kind!r}")
        byname = {j.name: j for j in joints}
        acts = []
        for a in data.get("actuator", []):
            j = byname[a["joint"]]
            acts.append({"name": a["name"], "cylinder": j.bodies[0], "rod": j.bodies[1],
                         "stroke": tuple(map(float, a["stroke"])), "max_force": float(a["max_force"])})
        load = next((f for f in data.get("force", []) if f["name"] == "foot_load"), None)
        if load is None:
            foot = data["foot"]
            lb, lp = ids[int(foot["body"])], point(ids[int(foot["body"])], foot["end"], foot)
        else:
            lb = ids[int(load["body"])]
            lp = point(lb, load.get("end", "at"), load)
        return cls([b.get("name", str(b["id"])) for b in data["body"]], L, m, J, joints, acts,
                   np.array(data.get("gravity", [0.0, -9.81]), float), lb, lp, variant, frame)

    @property
    def n_constraints(self) -> int:
        return sum(j.n_eq for j in self.joints)

    @property
    def joint_names(self) -> list[str]:
        return [j.name for j in self.joints]

    def world(self, q, bi, pt):
        """World position of body-fixed point pt = (xi, eta) of body bi; q (..., 18)."""
        r = q[..., 3 * bi:3 * bi + 2]
        ph = q[..., 3 * bi + 2]
        return r + pt[0] * u(ph) + pt[1] * nrm(ph)

    def constraints(self, q) -> np.ndarray:
        """Phi(q) (..., n_constraints): leg.toml's joint equations in absolute coordinates
        (revolute: the two points coincide; revolute_to_frame: the point is on its frame
        point; prismatic (eqs. 12-16): equal angles and the second body's centre on the first
        one's axis; slot (eq. 18): the first body's point on the second body's axis)."""
        q = np.asarray(q, float)
        rows = []
        for j in self.joints:
            if j.kind == "revolute_to_frame":
                d = self.world(q, j.bodies[0], j.points[0]) - np.asarray(j.frame_point)
                rows += [d[..., 0], d[..., 1]]
            elif j.kind == "revolute":
                d = self.world(q, j.bodies[0], j.points[0]) - self.world(q, j.bodies[1], j.points[1])
                rows += [d[..., 0], d[..., 1]]
            elif j.kind == "prismatic":
                i, k = j.bodies
                rows.append(q[..., 3 * i + 2] - q[..., 3 * k + 2])
                rows.append(np.sum(nrm(q[..., 3 * i + 2]) * (q[..., 3 * k:3 * k + 2] - q[..., 3 * i:3 * i + 2]), -1))
            elif j.kind == "slot":
                i, k = j.bodies
                p = self.world(q, i, j.points[0])
                rows.append(np.sum(nrm(q[..., 3 * k + 2]) * (p - q[..., 3 * k:3 * k + 2]), -1))
        return np.stack(rows, axis=-1)

    def actuator_lengths(self, q) -> np.ndarray:
        """Proximal end of the cylinder to the distal end of the rod (..., n_actuators)."""
        out = []
        for a in self.actuators:
            c, r = a["cylinder"], a["rod"]
            p0 = self.world(q, c, (-self.lengths[c] / 2, 0.0))
            p1 = self.world(q, r, (self.lengths[r] / 2, 0.0))
            out.append(np.linalg.norm(p1 - p0, axis=-1))
        return np.stack(out, -1)

    def balance(self, q, reactions, forces, foot_load=(0.0, 0.0), gravity=True, qdd=None) -> np.ndarray:
        """Residual of the free-body equations (..., 6, 3): for every body the sum of the
        forces (N) and of the moments about its centre of mass (N m) of gravity, the foot
        load, the actuators' axial forces (-F u on the cylinder, +F u on the rod) and the joint
        reactions, minus m a (qdd; None = static). A reaction (F, M) acts on the joint's
        first-listed body (M about its centre); the second body gets -F and the moment
        -M + (r2 - r1) x F about its own centre."""
        q = np.asarray(q, float)
        R = np.asarray(reactions, float).reshape(q.shape[:-1] + (len(self.joints), 3))
        Fa = np.asarray(forces, float)
        nb = len(self.lengths)
        res = np.zeros(q.shape[:-1] + (nb, 3))
        g = self.gravity if gravity else np.zeros(2)
        res[..., :, 0:2] += self.masses[:, None] * g
        lb = self.load_body
        F = np.broadcast_to(np.asarray(foot_load, float), q.shape[:-1] + (2,))
        p = self.world(q, lb, self.load_point)
        res[..., lb, 0:2] += F
        res[..., lb, 2] += cross(p - q[..., 3 * lb:3 * lb + 2], F)
        for ai, a in enumerate(self.actuators):
            e = u(q[..., 3 * a["cylinder"] + 2])
            f = Fa[..., ai:ai + 1] * e
            res[..., a["cylinder"], 0:2] -= f
            res[..., a["rod"], 0:2] += f
        for k, j in enumerate(self.joints):
            Fk, Mk = R[..., k, 0:2], R[..., k, 2]
            i = j.bodies[0]
            res[..., i, 0:2] += Fk
            res[..., i, 2] += Mk
            if len(j.bodies) == 2:
                b = j.bodies[1]
                res[..., b, 0:2] -= Fk
                res[..., b, 2] += -Mk + cross(q[..., 3 * b:3 * b + 2] - q[..., 3 * i:3 * i + 2], Fk)
        if qdd is not None:
            a = np.asarray(qdd, float).reshape(q.shape[:-1] + (nb, 3))
            res -= a * np.stack([self.masses, self.masses, self.inertias], -1)
        return res


def constraint_residual(leg: Leg, q) -> np.ndarray:
    """max |Phi(q)| per sample."""
    return np.max(np.abs(leg.constraints(q)), axis=-1)


def static_balance(leg: Leg, q, reactions, forces, foot_load=(0.0, 0.0), gravity=True):
    """(max force residual (N), max moment residual (N m)) per sample."""
    r = leg.balance(q, reactions, forces, foot_load, gravity)
    return np.max(np.abs(r[..., 0:2]), axis=(-1, -2)), np.max(np.abs(r[..., 2]), axis=-1)


def float32_quantum(x) -> float:
    """Spacing of float32 values at the largest |x| (the DBC's resolution there)."""
    m = float(np.max(np.abs(np.asarray(x, float)))) if np.size(x) else 0.0
    if m == 0 or not math.isfinite(m):
        return float(np.finfo(np.float32).tiny)
    return float(np.spacing(np.float32(m)))


# ---- results ---------------------------------------------------------------------------

@dataclass
class CheckResult:
    name: str
    passed: bool
    error: float | None = None        # worst error (or the measured value)
    tolerance: float | None = None
    unit: str = ""
    where: str = ""
    detail: str = ""
    got: str | None = None            # non-numeric outcome (e.g. the fault code received)
    want: str | None = None           # and what was expected

    @property
    def verdict(self) -> str:
        return "PASS" if self.passed else "FAIL"

    def as_dict(self) -> dict:
        return {"check": self.name, "result": self.verdict, "error": self.error,
                "tolerance": self.tolerance, "unit": self.unit, "where": self.where,
                "detail": self.detail, "got": self.got, "expected": self.want}


@dataclass
class Evaluation:
    scene: Scene
    rec: dict
    results: list[CheckResult]
    data: dict = field(default_factory=dict)     # arrays: t, q, ... (received)
    ref: dict | None = None                      # arrays of the reference at the same times
    leg: Leg | None = None

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results) and bool(self.results)

    @property
    def n_failed(self) -> int:
        return sum(not r.passed for r in self.results)


def _arrays(rec: dict) -> dict:
    S = rec["samples"]
    n = len(S)

    def arr(key, width):
        return np.array([s[key] for s in S], float).reshape(n, width)

    return {
        "t": np.array([s["t"] for s in S], float),
        "step": np.array([s["step"] for s in S], int),
        "q": arr("q", 18), "qd": arr("qd", 18), "lengths": arr("lengths", 2),
        "rates": arr("rates", 2), "forces": arr("forces", 2),
        "reactions": arr("reactions", 24).reshape(n, 8, 3),
        "residual": np.array([s["residual"] for s in S], float),
        "condition": np.array([s["condition"] for s in S], float),
        "status": np.array([s["status"] for s in S], int),
        "stroke_mask": np.array([s["stroke_mask"] for s in S], int),
    }


# ---- the reference, replayed -------------------------------------------------------------

class Staircase:
    """What hil_sim holds: value v[i] after t[i] (left-continuous: at t[i] itself the previous
    value, which is what a sample taken at t[i], before the new setpoint arrives, reflects).
    A schedule of the reference model (callable, breakpoints: its integrator restarts there)."""

    def __init__(self, times, values):
        self.times = np.asarray(times, float)
        self.values = np.asarray(values, float)
        self.breakpoints = tuple(float(t) for t in self.times[1:])

    def __call__(self, t: float) -> float:
        i = int(np.searchsorted(self.times, t, side="left")) - 1
        return float(self.values[max(i, 0)])

    def rate(self, t: float) -> float:
        return 0.0

    def accel(self, t: float) -> float:
        return 0.0


def _timeline(scene: Scene, rec: dict, faults: list[dict]) -> list[tuple[int, list]]:
    """[(step, [(mode, value) | None per actuator])]: what each actuator did from that step on
    (value None: hold the length it has then). From the RESET's initial commands, the logged
    ACT_CMDs and the safe state after a command timeout."""
    init_len = rec.get("initial_lengths") or [None, None]
    if scene.init == "hold_length":
        cur = [("length", init_len[0]), ("length", init_len[1])]
    else:
        cur = [("force", 0.0), ("force", 0.0)]
    events: list[tuple[int, int, list]] = [(0, 0, list(cur))]
    for c in rec["commands"]:
        events.append((c["step"], 1, [tuple(c[a]) if a in c else None for a in ACTUATORS]))
    for f in faults:
        if f["code"] == "CMD_TIMEOUT":
            v = [("force", 0.0)] * 2 if scene.safe_state == "zero_force" else [("length", None)] * 2
            events.append((f["step"], 0, v))
    events.sort(key=lambda e: (e[0], e[1]))
    out = []
    for step, _, v in events:
        cur = [v[a] if v[a] is not None else cur[a] for a in range(2)]
        if out and out[-1][0] == step:
            out[-1] = (step, list(cur))
        else:
            out.append((step, list(cur)))
    return out


def _slot_s(leg: Leg, q) -> float:
    """Distance from the shank's proximal end C along its axis to the slot's point D."""
    j = next(j for j in leg.joints if j.kind == "slot")
    rod, shank = j.bodies
    D = leg.world(q, rod, j.points[0])
    C = leg.world(q, shank, (-leg.lengths[shank] / 2, 0.0))
    return float(np.dot(u(q[3 * shank + 2]), D - C))


def reference_run(scene: Scene, rec: dict, model_path, *, rtol=1e-10, atol=1e-11) -> dict:
    """The reference model at the recorded sample steps, driven as hil_sim was."""
    from .reference import ForceCommand, LegModel, LengthCommand

    h = scene.step_s
    model = LegModel.from_toml(model_path, variant=scene.variant)
    steps = np.array([s["step"] for s in rec["samples"]], int)
    faults = [f for s in rec["samples"] for f in s["faults"]]
    tl = _timeline(scene, rec, faults)
    if "actuators" in scene.disable:
        tl = [(k, [None, None]) for k, _ in tl]
    gravity = "gravity" not in scene.disable
    loads = [(0, (0.0, 0.0))] + [(x["step"], tuple(x["value"])) for x in rec["loads"] if x["index"] == 0]
    if "force_elements" in scene.disable:
        loads = [(0, (0.0, 0.0))]
    if scene.lengths is not None:
        if scene.variant != "revolute":
            raise NotImplementedError("assembly at given lengths: revolute variant only")
        theta = model.theta_from_lengths(scene.lengths, near=model.stand_theta())
    else:
        theta = model.stand_theta()
    if scene.variant == "slot":
        # the stand pose drives phi3 and phi6 only: the slot coordinate s (C to D along the
        # shank axis, the reference's third coordinate) is wherever the core's assembly put
        # it. Take it from the received pose at t = 0.
        theta = theta.copy()
        theta[2] = _slot_s(Leg.from_toml(model_path, "slot"), np.asarray(rec["samples"][0]["q"], float))
    thetad = np.zeros(model.ndof)
    theta0 = np.array(theta, float)

    # segments: where an actuator changes mode (within one the setpoints are a staircase)
    def modes(entry):
        return tuple(None if c is None else c[0] for c in entry[1])

    seg_starts = [0] + [tl[i][0] for i in range(1, len(tl)) if modes(tl[i]) != modes(tl[i - 1])]
    seg_starts = sorted(set(k for k in seg_starts if k < scene.n_steps))
    end_step = int(steps.max()) if len(steps) else 0
    out = {k: np.full((len(steps),) + s, np.nan) for k, s in
           (("q", (18,)), ("qd", (18,)), ("lengths", (2,)), ("forces", (2,)), ("reactions", (8, 3)),
            ("foot", (2,)), ("ne_residual", ()))}
    out["t"] = steps * h
    nfev = 0
    cur_len = None
    for si, k0 in enumerate(seg_starts):
        if k0 >= end_step:
            break
        k1 = seg_starts[si + 1] if si + 1 < len(seg_starts) else end_step
        k1 = min(k1, end_step)
        # commands of this segment: the entry in force at k0, then the changes before k1
        entries = [e for e in tl if e[0] <= k0][-1:] + [e for e in tl if k0 < e[0] < k1]
        cmds = []
        for a in range(2):
            if entries[0][1][a] is None:
                cmds.append(None)
                continue
            ts, vs = [], []
            for k, e in entries:
                val = e[a][1]
                if val is None:  # hold the length it has (hold-length safe state)
                    val = float(cur_len[a]) if cur_len is not None else float(rec["initial_lengths"][a])
                ts.append((k - k0) * h if k > k0 else 0.0)
                vs.append(float(val))
            sc = Staircase(ts, vs)
            cmds.append(ForceCommand(sc) if entries[0][1][a][0] == "force" else LengthCommand(sc))
        lent = [e for e in loads if e[0] <= k0][-1:] + [e for e in loads if k0 < e[0] < k1]
        lts = [((k - k0) * h if k > k0 else 0.0) for k, _ in lent]
        foot = (Staircase(lts, [v[0] for _, v in lent]), Staircase(lts, [v[1] for _, v in lent]))
        sel = (steps > k0) & (steps <= k1) if si > 0 else (steps >= k0) & (steps <= k1)
        local = np.unique(np.concatenate([(steps[sel] - k0) * h, [(k1 - k0) * h]]))
        res = model.simulate((k1 - k0) * h, t_eval=local, actuators=cmds, foot_load=foot,
                             gravity=gravity, theta0=theta, thetad0=thetad, rtol=rtol, atol=atol)
        nfev += res.nfev
        idx = np.nonzero(sel)[0]
        pos = np.searchsorted(res.t, (steps[idx] - k0) * h - 1e-12)
        for key, src in (("q", res.q), ("qd", res.qd), ("lengths", res.lengths),
                         ("forces", res.actuator_forces), ("reactions", res.reactions),
                         ("foot", res.foot), ("ne_residual", res.ne_residual)):
            out[key][idx] = src[pos]
        theta, thetad = res.theta[-1].copy(), res.thetad[-1].copy()
        cur_len = res.lengths[-1].copy()
    out["nfev"] = nfev
    out["theta0"] = theta0
    out["stroke"] = [a.stroke for a in model.actuators]
    return out


# ---- the checks ----------------------------------------------------------------------------

def _where(data, i: int, label: str) -> str:
    return f"t={data['t'][i]:.4f}s {label}"


def _coord_label(leg: Leg, c: int) -> str:
    return f"{leg.body_names[c // 3]}.{('x', 'y', 'phi')[c % 3]}"


def _max_err(err, mask=None):
    """(value, row, col) of the largest |err| over the rows in mask."""
    e = np.abs(np.asarray(err, float))
    e = e.reshape(len(e), -1)
    e = np.where(np.isnan(e), np.inf, e)   # a NaN received (or not computed) fails, never hides
    if mask is not None:
        e = np.where(np.asarray(mask)[:, None], e, np.nan)
    if not np.any(np.isfinite(e)):
        return None, -1, -1
    flat = int(np.nanargmax(e))
    r, c = divmod(flat, e.shape[1])
    return float(e[r, c]), r, c


def _wrap(d):
    return (d + np.pi) % (2 * np.pi) - np.pi


def evaluate(rec: dict, root: Path | None = None, *, scene: Scene | None = None,
             reference: bool = True) -> Evaluation:
    """All the checks the scene asks for, on one recording."""
    from .runner import scene_of

    root = root or find_root()
    scene = scene or scene_of(rec, root)
    if not scene.over_can or rec.get("runner") == "legsim_cli":   # statics, sweep, ...: legsim_cli
        from .analyses import evaluate_analysis
        return evaluate_analysis(rec, scene, root)
    if scene.robot:          # the two-leg robot over CAN, against RobotModel
        from .robot_can import evaluate_robot_can
        return evaluate_robot_can(rec, scene, root)
    ch = scene.checks
    model_path = scene.model_path or root / "models" / "leg.toml"   # the scene's model file
    leg = Leg.from_toml(model_path, scene.variant)
    results: list[CheckResult] = []
    ev = Evaluation(scene, rec, results, leg=leg)
    S = rec["samples"]
    if not S:
        results.append(CheckResult("run: all exchanges answered", False, 0.0,
                                   float(len(scene.boundaries()) + 1), "samples",
                                   detail="no state sample recorded: " +
                                   "; ".join(e["error"] for e in rec["errors"])))
        return ev
    d = ev.data = _arrays(rec)
    n = len(S)

    # -- the run itself
    expected = len(scene.boundaries()) + 1
    grid_err = float(np.max(np.abs(d["t"] - d["step"] * scene.step_s)))
    bad_state = [s for s in S if s["state"] == "HALTED" or s["legsim_status"] != 0]
    problems = [e["error"] for e in rec["errors"]]
    if not rec.get("complete"):
        problems.append("run not complete")
    if n != expected:
        problems.append(f"{n} samples, expected {expected}")
    if bad_state:
        problems.append(f"HALTED / legsim_status {bad_state[0]['legsim_status']} at t={bad_state[0]['t']:.4f}")
    if grid_err > 1e-9:
        problems.append(f"St_Time off the step grid by {grid_err:.2g} s")
    results.append(CheckResult(
        "run: all exchanges answered", not problems, float(n), float(expected), "samples",
        f"to t={d['t'][-1]:.4f}s",
        "; ".join(problems) or f"steps 0..{d['step'][-1]}, St_Time on the grid ({grid_err:.1g} s)"))

    # -- the DBC's resolution (float32) must sit well below every tolerance it bears on
    quanta = []
    xy = d["q"].reshape(n, 6, 3)
    for key, values, unit in (("position_m", xy[..., 0:2], "m"), ("angle_rad", xy[..., 2], "rad"),
                              ("reaction_n", d["reactions"][..., 0:2], "N"),
                              ("moment_nm", d["reactions"][..., 2], "N m"),
                              ("actuator_force_n", d["forces"], "N"),
                              ("balance_n", d["reactions"][..., 0:2], "N"),
                              ("balance_nm", d["reactions"][..., 2], "N m"),
                              ("residual", xy[..., 0:2], "m"), ("stays_put_m", xy[..., 0:2], "m"),
                              ("statics_reaction_n", d["reactions"][..., 0:2], "N")):
        tol = getattr(ch, key)
        if tol is not None:
            quanta.append((float32_quantum(values) / tol, key, float32_quantum(values), tol, unit))
    if quanta:
        worst = max(quanta)
        results.append(CheckResult(
            "DBC float32 resolution < tolerance x %g" % ch.resolution_ratio,
            worst[0] <= ch.resolution_ratio, worst[2], worst[3] * ch.resolution_ratio, worst[4],
            worst[1], "; ".join(f"{k} {qv:.2g} {un}" for _, k, qv, _, un in quanta)))

    # -- the window where the reference applies (no stroke stops in it)
    window = np.ones(n, bool)
    stroke_idx = None
    hit = (d["stroke_mask"] != 0) | ((d["status"] >> STATUS_BITS["STROKE_MIN"]) & 1).astype(bool) | \
        ((d["status"] >> STATUS_BITS["STROKE_MAX"]) & 1).astype(bool)
    if np.any(hit):
        stroke_idx = int(np.argmax(hit))
    if ch.compare == "until_stroke" and stroke_idx is not None:
        window[stroke_idx:] = False
    after0 = window & (d["step"] > 0)   # forces and reactions exist after the first step

    # -- the reference model
    need_ref = reference and any(getattr(ch, k) is not None for k in
                                 ("position_m", "angle_rad", "reaction_n", "moment_nm",
                                  "actuator_force_n", "statics_force_n", "statics_reaction_n"))
    ref = None
    if need_ref:
        try:
            ref = ev.ref = reference_run(scene, rec, model_path)
        except Exception as e:  # noqa: BLE001 - a failing reference is a failed check, not a crash
            results.append(CheckResult("reference model", False, detail=f"{type(e).__name__}: {e}"))
    if ref is not None:
        lo = np.array([s[0] for s in ref["stroke"]])
        hi = np.array([s[1] for s in ref["stroke"]])
        inside = np.all((ref["lengths"] >= lo) & (ref["lengths"] <= hi), axis=1)
        if ch.compare == "until_stroke":
            first_out = np.argmax(~inside) if np.any(~inside) else n
            window[first_out:] = False
            after0 &= window
        ref_note = f"{int(window.sum())}/{n} samples" + ("" if window.all() else
                                                          f" (to t={d['t'][window][-1]:.4f}s)")
        if stroke_idx is not None and ch.compare == "all":
            ref_note += (f"; a stroke stop at t={d['t'][stroke_idx]:.4f}s (the reference has none: "
                         "compare = \"until_stroke\" if the scene means it)")
        slot_note = "" if scene.variant != "slot" else \
            f"; slot s0 = {ref['theta0'][2]:.7f} m from the received pose at t = 0"
        dq = d["q"] - ref["q"]
        dq[:, 2::3] = _wrap(dq[:, 2::3])
        dq = dq.reshape(n, 6, 3)
        if ch.position_m is not None:
            v, r, c = _max_err(dq[..., 0:2].reshape(n, 12), window)
            results.append(CheckResult("positions x, y vs reference", v is not None and v <= ch.position_m,
                                       v, ch.position_m, "m",
                                       _where(d, r, _coord_label(leg, (c // 2) * 3 + c % 2)) if r >= 0 else "",
                                       ref_note + slot_note))
        if ch.angle_rad is not None:
            v, r, c = _max_err(dq[..., 2], window)
            results.append(CheckResult("angles vs reference", v is not None and v <= ch.angle_rad, v,
                                       ch.angle_rad, "rad",
                                       _where(d, r, _coord_label(leg, 3 * c + 2)) if r >= 0 else "", ref_note))
        if ch.actuator_force_n is not None:
            v, r, c = _max_err(d["forces"] - ref["forces"], after0)
            results.append(CheckResult("actuator forces vs reference", v is not None and v <= ch.actuator_force_n,
                                       v, ch.actuator_force_n, "N",
                                       _where(d, r, ACTUATORS[c]) if r >= 0 else "", ref_note))
        if "reactions" not in scene.disable:
            dr = d["reactions"] - ref["reactions"]
            if ch.reaction_n is not None:
                v, r, c = _max_err(dr[..., 0:2].reshape(n, 16), after0)
                results.append(CheckResult("reaction forces vs reference (Newton-Euler)",
                                           v is not None and v <= ch.reaction_n, v, ch.reaction_n, "N",
                                           _where(d, r, f"{leg.joint_names[c // 2]}.f{'xy'[c % 2]}") if r >= 0 else "",
                                           ref_note))
            if ch.moment_nm is not None:
                v, r, c = _max_err(dr[..., 2], after0)
                results.append(CheckResult("reaction moments vs reference", v is not None and v <= ch.moment_nm,
                                           v, ch.moment_nm, "N m",
                                           _where(d, r, f"{leg.joint_names[c]}.m") if r >= 0 else "", ref_note))

    d["window"] = window   # samples the reference comparison covers
    # -- invariants of the received data
    if ch.residual is not None:
        res = constraint_residual(leg, d["q"])
        i = int(np.argmax(res))
        results.append(CheckResult(f"constraint residual |Phi(q)| ({leg.n_constraints} eqs, leg.toml)",
                                   bool(res[i] <= ch.residual), float(res[i]), ch.residual, "m|rad",
                                   _where(d, i, ""), f"hil_sim's own St_Residual max {np.max(d['residual']):.2g}"))
    foot = _foot_loads(scene, rec, d["step"])
    if ch.balance_n is not None or ch.balance_nm is not None:
        bf, bm = static_balance(leg, d["q"], d["reactions"], d["forces"], foot, "gravity" not in scene.disable)
        m = d["step"] > 0
        if ch.balance_n is not None:
            v, r, _ = _max_err(bf, m)
            results.append(CheckResult("static balance, forces (received data)", v is not None and v <= ch.balance_n,
                                       v, ch.balance_n, "N", _where(d, r, "") if r >= 0 else "",
                                       "sum of forces on each body, qdd = 0"))
        if ch.balance_nm is not None:
            v, r, _ = _max_err(bm, m)
            results.append(CheckResult("static balance, moments (received data)",
                                       v is not None and v <= ch.balance_nm, v, ch.balance_nm, "N m",
                                       _where(d, r, "") if r >= 0 else "", "about each centre of mass"))
    if ch.stays_put_m is not None:
        disp = np.abs(xy[..., 0:2] - xy[0, :, 0:2]).reshape(n, 12)
        v, r, c = _max_err(disp)
        results.append(CheckResult("stays put (drift from the first sample)", v <= ch.stays_put_m, v,
                                   ch.stays_put_m, "m",
                                   _where(d, r, _coord_label(leg, (c // 2) * 3 + c % 2)), ""))
    if ch.statics_force_n is not None or ch.statics_reaction_n is not None:
        results.extend(_statics_checks(scene, rec, d, model_path, leg))

    if ch.stroke is not None:
        results.extend(_stroke_checks(scene, d, leg, ref, stroke_idx))
    results.extend(_fault_checks(scene, rec, d))
    return ev


def _foot_loads(scene: Scene, rec: dict, steps) -> np.ndarray:
    """The foot load in force at each sample (after the step that produced it)."""
    out = np.zeros((len(steps), 2))
    if "force_elements" in scene.disable:
        return out
    for x in sorted(rec["loads"], key=lambda x: x["step"]):
        if x["index"] == 0:
            out[np.asarray(steps) > x["step"]] = x["value"]
    return out


def _statics_checks(scene, rec, d, model_path, leg) -> list[CheckResult]:
    from .reference import LegModel

    ch = scene.checks
    out = []
    model = LegModel.from_toml(model_path, variant=scene.variant)
    load = (0.0, 0.0)
    if rec["loads"]:
        load = tuple(rec["loads"][0]["value"])
    th = model.stand_theta() if scene.lengths is None else model.theta_from_lengths(scene.lengths)
    try:
        F, R = model.statics(theta=th, foot_load=load, gravity="gravity" not in scene.disable)
    except Exception as e:  # noqa: BLE001
        return [CheckResult("reference statics", False, detail=f"{type(e).__name__}: {e}")]
    if ch.statics_force_n is not None:
        m = d["step"] > 0
        v, r, c = _max_err(d["forces"] - F[None], m)
        out.append(CheckResult("actuator forces vs reference statics", v is not None and v <= ch.statics_force_n,
                               v, ch.statics_force_n, "N",
                               _where(d, r, ACTUATORS[c]) if r >= 0 else "",
                               f"statics ({F[0]:.4f}, {F[1]:.4f}) N; received "
                               f"({d['forces'][-1, 0]:.4f}, {d['forces'][-1, 1]:.4f}) N at the end"))
    if ch.statics_reaction_n is not None:
        m = d["step"] > 0
        v, r, c = _max_err((d["reactions"] - R[None])[..., 0:2].reshape(len(m), 16), m)
        out.append(CheckResult("reactions vs reference statics", v is not None and v <= ch.statics_reaction_n,
                               v, ch.statics_reaction_n, "N",
                               _where(d, r, f"{leg.joint_names[c // 2]}.f{'xy'[c % 2]}") if r >= 0 else "",
                               f"load ({load[0]:g}, {load[1]:g}) N"))
    return out


def _stroke_checks(scene, d, leg, ref, stroke_idx) -> list[CheckResult]:
    s = scene.checks.stroke
    a = s.actuator
    name = ACTUATORS[a]
    lo, hi = leg.actuators[a]["stroke"]
    end = lo if s.end == "min" else hi
    bit = STATUS_BITS["STROKE_MIN" if s.end == "min" else "STROKE_MAX"]
    ev = ((d["stroke_mask"] >> a) & 1).astype(bool) & ((d["status"] >> bit) & 1).astype(bool)
    out = []
    first = int(np.argmax(ev)) if np.any(ev) else None
    detail = "never raised"
    if first is not None:
        detail = f"first at t={d['t'][first]:.4f}s (St_StrokeMask bit {a}, St_Status {['STROKE_MIN', 'STROKE_MAX'][s.end == 'max']})"
        if ref is not None:
            cross = np.nonzero((ref["lengths"][:, a] < end) if s.end == "min" else (ref["lengths"][:, a] > end))[0]
            if cross.size:
                detail += f"; the unstopped reference passes {end:g} m by t={d['t'][cross[0]]:.4f}s"
    out.append(CheckResult(f"stroke event: {name} reaches its {s.end} end", first is not None,
                           None if first is None else float(d["t"][first]), None, "s",
                           "" if first is None else _where(d, first, ""), detail))
    L = d["lengths"][:, a]
    over = (end - L) if s.end == "min" else (L - end)
    i = int(np.argmax(over))
    out.append(CheckResult(f"{name} length never passes {end:g} m", bool(over[i] <= s.tolerance_m),
                           float(max(over[i], 0.0)), s.tolerance_m, "m", _where(d, i, name),
                           f"length range {L.min():.6f} .. {L.max():.6f} m"))
    return out


def _fault_checks(scene: Scene, rec: dict, d) -> list[CheckResult]:
    out = []
    faults = [f for s in rec["samples"] for f in s["faults"]] + list(rec.get("late_faults", []))
    used = set()
    timeout_steps = math.ceil(scene.cmd_timeout_ms * 1e6 / scene.step_ns) if scene.cmd_timeout_ms else 0
    for inj in rec["injections"]:
        want = inj["expect"]
        got = None
        if inj["kind"] == "silence":
            last_cmd = max((c["step"] for c in rec["commands"] if c["step"] <= inj["step"]), default=None)
            trip = None if last_cmd is None else last_cmd + timeout_steps
            for i, f in enumerate(faults):
                if i not in used and f["code"] == want and inj["step"] <= f["step"] <= inj["step"] + inj["silence_steps"]:
                    got = i
                    break
            ok = got is not None and (trip is None or faults[got]["step"] == trip)
            # the row's name carries the label: the detail does not repeat it
            det = f"timeout {scene.cmd_timeout_ms} ms after the ACT_CMD at step {last_cmd}"
            if got is not None:
                used.add(got)
                f = faults[got]
                det += f" -> {f['code']} at step {f['step']} (expected {trip})"
                safe = _safe_state_ok(scene, rec, d, f["step"])
                if safe:
                    ok = False
                    det += "; " + safe
                else:
                    det += "; SAFE_STATE set until the next ACT_CMD" + \
                        (", actuator forces 0" if scene.safe_state == "zero_force" else "")
            else:
                det += " -> no " + want
            out.append(CheckResult(f"fault {want}: {inj['label']}", ok, None, None, "",
                                   f"t={inj['t']:.4f}s", det,
                                   got=faults[got]["code"] if got is not None else "none", want=want))
            continue
        for i, f in enumerate(faults):
            if i in used or f["code"] != want:
                continue
            if f["frame_id"] != inj["frame_id"] or f["step"] != inj["step"]:
                continue
            got = i
            break
        ok = got is not None
        near = [f["code"] for f in faults if f["step"] == inj["step"]]
        det = f"frame 0x{inj['frame_id']:03x} len {inj['length']}"
        if inj.get("seq") is not None:
            det += f" seq {inj['seq']}"
        if got is not None:
            used.add(got)
            f = faults[got]
            det += f" -> {f['code']}"
            if f.get("signal"):
                det += f" ({f['signal']})"
            if inj.get("expect_signal") and f.get("signal") != inj["expect_signal"]:
                ok = False
                det += f", expected signal {inj['expect_signal']}"
            # FAULT bit and St_LastFault in the sample after it
            nxt = next((s for s in rec["samples"] if s["step"] > inj["step"]), None)
            if nxt is not None:
                if "FAULT" not in nxt["status_names"]:
                    ok = False
                    det += "; St_Status FAULT bit not set"
                if nxt["last_fault"] != want:
                    ok = False
                    det += f"; St_LastFault {nxt['last_fault']}"
        else:
            det += f" -> no {want}" + (f" (got {', '.join(near)})" if near else "")
        shown = "none"
        if got is not None:
            shown = faults[got]["code"]
        elif near:
            shown = ",".join(near)
        out.append(CheckResult(f"fault {want}: {inj['label']}", ok, None, None, "",
                               f"t={inj['t']:.4f}s", det, got=shown, want=want))
    extra = [f for i, f in enumerate(faults) if i not in used]
    if rec["injections"] or extra:
        out.append(CheckResult("no unexpected faults", not extra, float(len(extra)), 0.0, "faults", "",
                               "; ".join(f"{f['code']} frame 0x{f['frame_id']:03x} step {f['step']}"
                                         for f in extra[:5]) or f"{len(used)} faults, all expected"))
    return out


def _safe_state_ok(scene, rec, d, trip_step) -> str:
    """'' if SAFE_STATE is set (and the forces are 0 in the zero-force safe state) in every
    sample from the trip to the next ACT_CMD, and cleared after it; else what is wrong."""
    nxt_cmd = min((c["step"] for c in rec["commands"] if c["step"] >= trip_step), default=None)
    bit = STATUS_BITS["SAFE_STATE"]
    for i, k in enumerate(d["step"]):
        in_safe = k > trip_step and (nxt_cmd is None or k <= nxt_cmd)
        on = bool((d["status"][i] >> bit) & 1)
        if in_safe and not on:
            return f"SAFE_STATE missing at step {k}"
        if nxt_cmd is not None and k > nxt_cmd and on:
            return f"SAFE_STATE still set at step {k} after the ACT_CMD at step {nxt_cmd}"
        if in_safe and scene.safe_state == "zero_force" and np.any(d["forces"][i] != 0):
            return f"actuator forces {d['forces'][i].tolist()} at step {k} in the safe state"
    return ""
