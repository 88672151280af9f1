"""The hexapod walking (scenes/hexapod_walk.toml) in legsim and MuJoCo: the same servos, set-points
and start, the feet on the ground's cones.

The plan: legsim.Hexapod.walk's commands, taken from legsim itself: the gait's set-points
(Hexapod.gait_setpoints: lengths, rowing angles, stance) and, as feed-forward, the statics of the
planned pose on its planned stance (Hexapod.statics), exactly as ``walk`` sends them, at every
multiple of the command period h_plan (the scene's step_s, 1 ms: a controller at that rate).
A step h that divides h_plan holds the command of the period it is in (the one walk() sends at
the period's end); a step that is a multiple of it takes the command at its own end, as walk()
at step h. Why a fixed command period: walk() commands at every step's end, so its forcing is a
zero-order hold of the gait that changes with h; its runs then converge at order 1 whatever the
integrator (legsim 7.4e-4, 3.6e-4, 1.7e-4, 7.2e-5 m of box at h = 4, 2, 1, 0.5 ms against its
run at 0.125 ms), which measures the hold, not the engine.

legsim (``legsim_walk``): Hexapod.sim at the gait's pose at t = 0 (the box level at box_height over
the origin, the stance's feet stuck), then per step HexapodSim.command_pose and step(1): walk()'s
loop without its sampling (the test checks both give the same walk). Its cost: the step(1) calls
alone (perf_counter around each), the commands outside the clock as MuJoCo's.

MuJoCo (``MujocoWalk``): mujoco_hexapod.build_xml(walk=...) at the same start pose, no held feet:
each foot a sphere of radius FOOT_RADIUS centred on its foot point on a plane moved down by the
radius, condim 3, cone elliptic, one mu (``mu``: the file's mu_static by default; MuJoCo has no
static/kinetic pair), margin = gap = 0. Servos as legsim's (motion.cpp command_forces): a
``general`` actuator on each slide and yoke hinge, gain kp, bias (0, -kp, -kd), ctrl = set-point -
start value + feed-forward / kp, forcerange +-max_force (max_torque): kp (cmd - q) + ff - kd q',
saturated, the same law and the same saturation of the sum. Each step's controls are the plan's
entry legsim's step takes (Plan.index), held over the step (mujoco.rollout). Soft constraints: solref (2 h, 1) for the loops
and the contacts (the stiffest ``refsafe`` admits: the contact stiffens as h falls, so the runs
tend to the rigid model), solimp 0.9999 for the loops, CONTACT_SOLIMP for the contacts, impratio
IMPRATIO (the friction rows' impedance over the normal's: stiffer sticking), RK4.

Errors: box centre and the six feet (world, m) on the samples every SAMPLE_S, max over time and
entries of the distance (Euclidean norm per point) to the reference's.
"""
from __future__ import annotations

import time
import tomllib
from dataclasses import dataclass, field

import numpy as np

from ...reference.hexapod import LEGS, HexapodModel
from ...scene import find_root
from . import mujoco_hexapod as mh
from .mujoco_hexapod import VERSION, _rollout, mujoco

SAMPLE_S = 4e-3                 # the errors' grid: a multiple of every step h used
FOOT_RADIUS = 1e-4              # m
CONTACT_SOLIMP = (0.99, 0.99, 0.001, 0.5, 2.0)
IMPRATIO = 100.0           # the friction rows stiffer than the normal (see the peers README's sweep)
NOSLIP = 0


def walk_scene(path=None) -> dict:
    """scenes/hexapod_walk.toml: its gait (legsim.Hexapod.walk's keys) and duration."""
    path = path or find_root() / "scenes" / "hexapod_walk.toml"
    with open(path, "rb") as f:
        d = tomllib.load(f)
    return {"gait": dict(d["gait"]), "duration": float(d["duration"]), "step_s": float(d["step_s"])}


def _hexapod():
    import legsim
    return legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))


@dataclass
class Plan:
    """legsim.Hexapod.walk's commands at t = i h_plan, i = 0..n (plan())."""
    h: float
    gait: dict
    pose: dict                      # the start pose (walk's)
    stance0: list                   # the feet stuck at the start
    length_m: np.ndarray            # (n + 1, 6, 2)
    rowing_rad: np.ndarray          # (n + 1, 6)
    ff_n: np.ndarray                # (n + 1, 6, 2)
    ff_nm: np.ndarray               # (n + 1, 6)
    stance: np.ndarray              # (n + 1, 6) bool
    extra: dict = field(default_factory=dict)

    def save(self, path) -> None:
        import json
        np.savez(path, h=self.h, gait=json.dumps(self.gait), pose=json.dumps(self.pose, default=float),
                 stance0=self.stance0,
                 length_m=self.length_m, rowing_rad=self.rowing_rad, ff_n=self.ff_n, ff_nm=self.ff_nm,
                 stance=self.stance)

    @classmethod
    def load(cls, path) -> "Plan":
        import json
        z = np.load(path)
        return cls(float(z["h"]), json.loads(str(z["gait"])), json.loads(str(z["pose"])),
                   [int(k) for k in z["stance0"]], z["length_m"], z["rowing_rad"], z["ff_n"], z["ff_nm"],
                   z["stance"])

    @property
    def t_end(self) -> float:
        return (len(self.rowing_rad) - 1) * self.h

    def index(self, h: float, n: int) -> np.ndarray:
        """(n,): the plan's entry each of n steps of h takes: the commands at the end of the
        command period (h_plan) that holds the step's end, i.e. t_(i+1) for h a multiple of
        h_plan (walk()'s commands at step h), held over the period when h divides it."""
        r = h / self.h
        if not (abs(r - round(r)) < 1e-9 * r or abs(1 / r - round(1 / r)) < 1e-9 / r):
            raise ValueError(f"h = {h} neither divides nor is a multiple of the command period {self.h}")
        idx = np.ceil((np.arange(n) + 1) * r - 1e-9).astype(int)
        if idx[-1] >= len(self.rowing_rad):
            raise ValueError("the run ends after the plan")
        return idx


def plan(h_plan: float, t_end: float, gait: dict | None = None, hexapod=None) -> Plan:
    """The commands walk() sends, at every multiple of h_plan up to t_end (legsim computes them:
    gait_setpoints, then statics at the planned pose on the planned stance)."""
    hx = hexapod or _hexapod()
    gait = gait or walk_scene()["gait"]
    n = int(round(t_end / h_plan))
    sp0 = hx.gait_setpoints(0.0, **gait)
    box = sp0["box_m"] if "box_m" in sp0 else [0.0, 0.0, float(gait["box_height_m"])]   # walk()'s start
    pose = {"box_m": [float(x) for x in box], "box_quat": [1.0, 0.0, 0.0, 0.0],
            "rowing_rad": list(sp0["rowing_rad"]), "length_m": sp0["length_m"].tolist()}
    L, P, F, M, S = [], [], [], [], []
    for i in range(n + 1):
        sp = hx.gait_setpoints(i * h_plan, **gait) if i else sp0
        at = dict(pose, rowing_rad=list(sp["rowing_rad"]), length_m=sp["length_m"].tolist())
        s = hx.statics(at, stance=[k for k in range(LEGS) if sp["stance"][k]])
        L.append(sp["length_m"]); P.append(sp["rowing_rad"]); S.append(sp["stance"])
        F.append(s["actuator_force_n"]); M.append(s["rowing_torque_nm"])
    return Plan(h_plan, dict(gait), pose, [k for k in range(LEGS) if sp0["stance"][k]],
                np.array(L), np.array(P), np.array(F), np.array(M), np.array(S))


# ------------------------------------------------------------------ legsim
def legsim_walk(pl: Plan, h: float, t_end: float | None = None, hexapod=None, integrator: str = "rk4") -> dict:
    """legsim walking by the plan at step h to t_end: box (n, 3) and feet (n, 6, 3) every
    SAMPLE_S (the start included), the feet's forces and states there, the cone's statistics,
    ``per_step_s`` (the step calls' wall time over the steps)."""
    import legsim

    hx = hexapod or _hexapod()
    t_end = pl.t_end if t_end is None else t_end
    n = int(round(t_end / h))
    idx = pl.index(h, n)
    every = max(1, int(round(SAMPLE_S / h)))
    sim = hx.sim(pl.pose, stuck=pl.stance0, integrator=integrator)
    sim.command_pose(pl.length_m[0], pl.rowing_rad[0], pl.ff_n[0], pl.ff_nm[0])
    box, feet, force, state, t = [], [], [], [], []

    def sample(st):
        t.append(st["t_s"]); box.append(st["box_m"]); feet.append(st["foot_m"])
        force.append(st["foot_force_n"]); state.append(st["foot_state"])

    sample(sim.state())
    wall, ok = 0.0, True
    for i in range(n):
        j = idx[i]
        sim.command_pose(pl.length_m[j], pl.rowing_rad[j], pl.ff_n[j], pl.ff_nm[j])
        t0 = time.perf_counter()
        try:
            sim.step(1, h_s=h)
        except legsim.LegsimError as e:     # a failed step ends the run (ok False)
            ok = False
            note = str(e)
            break
        wall += time.perf_counter() - t0
        if (i + 1) % every == 0 or i + 1 == n:
            st = sim.state()
            sample(st)
    st = sim.state()
    out = {"t": np.array(t), "box": np.array(box), "feet": np.array(feet), "force": np.array(force),
           "foot_state": state, "ok": ok, "per_step_s": wall / max(1, n), "n_steps": n, "h": h,
           "impacts": st["impacts"], "cone": st["cone"], "engine": "legsim double",
           "method": f"{'RK4' if integrator == 'rk4' else 'generalized-alpha'} (rotation group), events located"}
    if not ok:
        out["note"] = note
    return out


# ------------------------------------------------------------------ MuJoCo
def mjcf_walk(ref: HexapodModel, *, mu=None, impratio=IMPRATIO, noslip_iterations=NOSLIP,
              contact_solimp=CONTACT_SOLIMP, foot_radius=FOOT_RADIUS, path=None) -> dict:
    """build_xml's ``walk``: the servos' gains (the legs' actuators', [rowing]'s), the ground's mu
    (None: mu_static), the contacts' settings."""
    path = path or mh.default_path()
    with open(path, "rb") as f:
        d = tomllib.load(f)
    ro, gr = d["rowing"], d["ground"]
    if gr["normal"] != [0.0, 0.0, 1.0] or any(gr["point"]):
        raise NotImplementedError("the MuJoCo walk takes the level ground through the origin")
    acts = ref.legs[0].model.actuators
    if any(leg.model is not ref.legs[0].model for leg in ref.legs):
        raise NotImplementedError("the MuJoCo walk takes one leg file for the six legs")
    return {"actuator": [(a.kp, a.kd, a.max_force) for a in acts],
            "rowing": (float(ro["servo_kp"]), float(ro["servo_kd"]), float(ro["max_torque"])),
            "mu": float(gr["mu_static"] if mu is None else mu), "mu_static": float(gr["mu_static"]),
            "mu_kinetic": float(gr["mu_kinetic"]), "impratio": float(impratio),
            "noslip_iterations": int(noslip_iterations), "contact_solimp": tuple(contact_solimp),
            "foot_radius": float(foot_radius)}


class MujocoWalk:
    """The hexapod walking in MuJoCo at step h: build, then ``simulate(plan)``."""

    def __init__(self, pl: Plan, ref: HexapodModel, h: float, method: str = "rk4", **walk_kw):
        if mujoco is None:
            raise ImportError("mujoco is not installed (the bench's [peers] extra)")
        self.walk = mjcf_walk(ref, **walk_kw)
        sc = mh.Scene("walk", pl.pose, (), np.zeros((LEGS, 2)), np.zeros(LEGS))
        self.pl, self.h, self.method = pl, float(h), method
        self.xml, self.lay = mh.build_xml(sc, ref, h, method, walk=self.walk)
        self.m = mujoco.MjModel.from_xml_string(self.xml)
        self.d = mujoco.MjData(self.m)
        jid = lambda n: mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_JOINT, n)   # noqa: E731
        self.slide_adr = np.array([self.m.jnt_qposadr[jid(n)] for n in self.lay["slides"]]).reshape(LEGS, 2)
        self.yoke_adr = np.array([self.m.jnt_qposadr[jid(n)] for n in self.lay["yokes"]])
        self.foot_geoms = [mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_GEOM, n) for _, n in self.lay["feet"]]
        kp = np.array([[g[0] for g in self.walk["actuator"]]] * LEGS)
        self.kp = np.concatenate([kp.ravel(), [self.walk["rowing"][0]] * LEGS])

    def controls(self, n: int, t_end: float | None = None) -> np.ndarray:
        """(n, nu): step i's controls, the plan's set-points and feed-forwards at t_(i+1)."""
        idx = self.pl.index(self.h, n)
        pl, lay = self.pl, self.lay
        sp = np.concatenate([(pl.length_m[idx] - lay["l0"]).reshape(n, -1), pl.rowing_rad[idx] - lay["psi0"]], axis=1)
        ff = np.concatenate([pl.ff_n[idx].reshape(n, -1), pl.ff_nm[idx]], axis=1)
        return sp + ff / self.kp

    def simulate(self, t_end: float | None = None) -> dict:
        """From the start at rest to t_end at fixed step h (mujoco.rollout, one thread): box and
        feet every SAMPLE_S (the start included), the feet's contact forces there (world, N),
        ``per_step_s`` (perf_counter around rollout only, over the steps)."""
        h, m, d = self.h, self.m, self.d
        t_end = self.pl.t_end if t_end is None else t_end
        n = int(round(t_end / h))
        every = max(1, int(round(SAMPLE_S / h)))
        mujoco.mj_resetData(m, d)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        x0 = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, x0, spec)
        ctrl = self.controls(n)[None]
        state = np.empty((1, n, x0.size))
        t0 = time.perf_counter()
        _rollout.rollout(m, d, x0[None, :], ctrl, nstep=n, state=state)
        wall = time.perf_counter() - t0
        bad = d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        ok = bool(np.all(np.isfinite(state[0, -1]))) and bad == 0
        keep = [i for i in range(n) if (i + 1) % every == 0 or i + 1 == n]
        t, box, feet, force = [0.0], [], [], []
        for k, x in [(-1, x0)] + [(i, state[0, i]) for i in keep]:
            if k >= 0:
                t.append((k + 1) * h)
            b, f, fo = self._outputs(x, None if k < 0 else ctrl[0, k])
            box.append(b); feet.append(f); force.append(fo)
        return {"t": np.array(t), "box": np.array(box), "feet": np.array(feet), "force": np.array(force),
                "ok": ok, "per_step_s": wall / n, "n_steps": n, "h": h, "engine": f"mujoco {VERSION}",
                "method": self.method}

    def _outputs(self, x, ctrl) -> tuple:
        """Box centre, feet (sphere centres), each foot's contact force (world, N) at a state."""
        m, d = self.m, self.d
        mujoco.mj_setState(m, d, x, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        if ctrl is not None:
            d.ctrl[:] = ctrl
        mujoco.mj_forward(m, d)
        force = np.zeros((LEGS, 3))
        c6 = np.zeros(6)
        for i in range(d.ncon):
            con = d.contact[i]
            g = con.geom2 if con.geom1 == 0 or con.geom1 not in self.foot_geoms else con.geom1
            if g not in self.foot_geoms:
                continue
            mujoco.mj_contactForce(m, d, i, c6)
            frame = con.frame.reshape(3, 3)          # rows: normal, tangents (world)
            # mj_contactForce: on geom2 from geom1 in the contact frame; the plane is geom1 or geom2
            sign = 1.0 if con.geom2 == g else -1.0
            force[self.foot_geoms.index(g)] += sign * frame.T @ c6[:3]
        return d.qpos[:3].copy(), d.geom_xpos[self.foot_geoms].copy(), force


# ------------------------------------------------------------------ errors
def errors(out: dict, ref: dict) -> dict:
    """Max over the common samples of the box centre's and the feet's distance (m) to ref's."""
    if not out.get("ok") or not ref.get("ok"):
        return {"box": float("nan"), "feet": float("nan")}
    n = min(len(out["t"]), len(ref["t"]))
    if np.abs(out["t"][:n] - ref["t"][:n]).max() > 1e-9:
        raise ValueError("the runs' samples are not at the same times")
    return {"box": float(np.linalg.norm(out["box"][:n] - ref["box"][:n], axis=-1).max()),
            "feet": float(np.linalg.norm(out["feet"][:n] - ref["feet"][:n], axis=-1).max())}


def cone_margin(out: dict, mu: float) -> float:
    """min over samples and feet in contact of mu N - |T| (N; >= 0 inside the cone)."""
    f = out["force"].reshape(-1, 3)
    on = f[:, 2] > 1e-9
    if not on.any():
        return float("inf")
    return float((mu * f[on, 2] - np.linalg.norm(f[on, :2], axis=1)).min())


def default_setup(t_end: float | None = None, h_plan: float | None = None, hexapod=None):
    """(ref model, plan) for the walking scene: its duration and its step_s as the command period
    by default."""
    sc = walk_scene()
    ref = HexapodModel.from_toml(mh.default_path())
    pl = plan(h_plan or sc["step_s"], t_end if t_end is not None else sc["duration"], sc["gait"], hexapod)
    return ref, pl



# ------------------------------------------------------------------ instructions


def _run_once(engine: str, h: float, t_end: float, plan_path: str) -> None:
    """One walk (the process callgrind counts)."""
    pl = Plan.load(plan_path)
    if engine == "mujoco":
        MujocoWalk(pl, HexapodModel.from_toml(mh.default_path()), h).simulate(t_end)
    else:
        legsim_walk(pl, h, t_end)


def instructions_per_step(engine: str, pl: Plan, h: float, t_end: float) -> float:
    """Instructions per step (valgrind callgrind, collecting only inside peer_tables.TOGGLE[engine], once a
    step): one walk of t_end at step h, set-up, the commands and Python outside the count."""
    import tempfile
    from pathlib import Path

    from .peer_tables import callgrind_total

    with tempfile.TemporaryDirectory() as tmp:
        pp = Path(tmp) / "plan.npz"
        pl.save(pp)
        total = callgrind_total(engine, __name__, [engine, repr(h), repr(t_end), str(pp)])
    return total / int(round(t_end / h))


if __name__ == "__main__":
    import sys

    _run_once(sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4])
