"""The leg in MuJoCo: a kinematic tree of hinges and slides, loops closed by
``connect`` equalities, no contacts.

Tree (all hinges about z, the motion stays in the xy plane, gravity (0, -g, 0)):

    world -hinge A-> upper_cylinder(1) -slide-> upper_rod(2)
    world -hinge B-> thigh(3)
    world -hinge B-> lower_cylinder(4) -slide-> lower_rod(5) -hinge D-> shank(6)
                                                 [slot variant: hinge D + slide
                                                  along the shank axis]
    connect: upper_rod distal = thigh distal        (C, rod-thigh)
    connect: shank proximal   = thigh distal        (C, rod-shank by transitivity)

Two connects = 6 equality rows, 4 of them in the plane (the two z rows are
identically satisfied and only regularized). 6 (7) tree dofs - 4 = 2 (3) dofs,
as ours. Every body's frame sits at its centre of mass with its local x axis
along n(phi) and its local -y axis along u(phi), so x, y = xpos and
phi = the frame's rotation about z (see README.md). The model is written at the
stand pose, so qpos = 0 is the stand pose and the connects hold there exactly.

The shank hangs on the lower rod so that the slot variant (the rod's distal end
slides on the shank axis) is a tree joint (hinge then slide, in the shank's
frame) and needs no equality MuJoCo does not have (MuJoCo has no point-on-line
equality).

Actuators: a ``motor`` (gear 1) on each slide, ctrl = the axial force:
positive extends (the slide axis is the cylinder's u), the generalized force
is +F u on the rod and -F u on the cylinder -- equivalent to forces through
the centres, which are on the (common) axis.

Loop closures are soft in MuJoCo. Defaults here (see README.md for the study):
solref = (2 h, 1) -- time constant 2 h, critical damping, the stiffest
MuJoCo's ``refsafe`` rule admits -- and solimp = (0.9999, 0.9999, ...), the
largest impedance MuJoCo allows (mjMAXIMP). Newton solver, tolerance 1e-12.
"""
from __future__ import annotations

import math
import time

import numpy as np

from . import leg_model as lm

METHODS = ("rk4", "euler", "implicitfast")
VARIANTS = ("revolute", "slot")

try:
    import mujoco
    import mujoco.rollout as _rollout

    VERSION = mujoco.__version__
except ImportError:  # pragma: no cover - depends on the environment
    mujoco = None
    _rollout = None
    VERSION = None

_INTEGRATOR = {"rk4": "RK4", "euler": "Euler", "implicitfast": "implicitfast",
               "implicit": "implicit"}


def available() -> bool:
    return mujoco is not None


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in x)


def _local(xi: float, eta: float) -> tuple:
    """Our body-fixed (xi, eta) as the MuJoCo body frame's (x, y, z)."""
    return (eta, -xi, 0.0)


def _quat_z(a: float) -> tuple:
    return (math.cos(0.5 * a), 0.0, 0.0, math.sin(0.5 * a))


def _rel(q: np.ndarray, parent: int | None, child: int) -> tuple:
    """pos, angle of the child's frame in the parent's (or the world's) frame."""
    xc, yc, pc = q[3 * child: 3 * child + 3]
    if parent is None:
        return (xc, yc, 0.0), pc
    xp, yp, pp = q[3 * parent: 3 * parent + 3]
    c, s = math.cos(pp), math.sin(pp)
    dx, dy = xc - xp, yc - yp
    return (c * dx + s * dy, -s * dx + c * dy, 0.0), pc - pp


def build_xml(model: lm.LegModel, h: float, method: str = "rk4", *,
              solref=None, solimp=(0.9999, 0.9999, 0.001, 0.5, 2.0),
              tolerance: float = 1e-12, iterations: int = 100, refsafe: bool = True,
              islands: bool = True) -> str:
    """MJCF of the leg at the stand pose. ``solref`` None: (2 h, 1). ``islands`` False:
    MuJoCo's constraint-island discovery off (the leg is one island: it only costs)."""
    if method not in _INTEGRATOR:
        raise ValueError(f"unknown method {method!r}; known: {METHODS}")
    if solref is None:
        solref = (2.0 * h, 1.0)
    q0 = lm.stand_q0(model)
    B = model.bodies
    names = [b.name for b in B]
    jn = {j.name: j for j in model.joints}
    # tree joints from the model's joints (this tree is specific to this leg:
    # bodies 1..6 as in leg.toml; checked below against the joint list)
    ja, jb3, jb4 = jn["A"], jn["B_thigh"], jn["B_lower"]
    jup, jlo, jd = jn["upper_actuator"], jn["lower_actuator"], jn["D"]
    jc_rt, jc_rs = jn["C_rod_thigh"], jn["C_rod_shank"]
    assert ja.bodies == (0,) and jb3.bodies == (2,) and jb4.bodies == (3,)
    assert jup.bodies == (0, 1) and jlo.bodies == (3, 4) and jd.bodies == (4, 5)
    assert jc_rt.bodies == (1, 2) and jc_rs.bodies == (1, 5)

    def inertial(i):
        b = B[i]
        return (f'<inertial pos="0 0 0" mass="{b.mass!r}" '
                f'diaginertia="{_f([b.inertia] * 3)}"/>')

    def body_open(i, parent):
        pos, ang = _rel(q0, parent, i)
        return f'<body name="{names[i]}" pos="{_f(pos)}" quat="{_f(_quat_z(ang))}">'

    def hinge(name, xi_eta):
        return f'<joint name="{name}" type="hinge" axis="0 0 1" pos="{_f(_local(*xi_eta))}"/>'

    def slide(name, xi_eta=(0.0, 0.0)):
        return (f'<joint name="{name}" type="slide" axis="{_f(_local(1.0, 0.0))}" '
                f'pos="{_f(_local(*xi_eta))}"/>')

    # D: on the lower rod (5) its distal end; on the shank (6) its point
    xi5 = 0.5 * B[4].length
    d5 = _local(xi5, 0.0)
    if jd.kind == "revolute":
        (p5, p6) = jd.points
        shank_joints = [hinge("D", p6)]
    else:  # slot: the rod's distal end on the shank axis. Put the shank's hinge
        # at the material point of the shank that sits at D in the stand pose.
        p5 = jd.points[0]
        D = lm.point(q0, 4, *p5)
        r6, phi6 = q0[15:17], q0[17]
        xi6 = float((D - r6) @ lm.u(phi6))
        eta6 = float((D - r6) @ lm.n(phi6))
        assert abs(eta6) < 1e-12, "slot: D must be on the shank axis in the stand pose"
        shank_joints = [hinge("D", (xi6, 0.0)), slide("D_slot", (xi6, 0.0))]
    assert abs(p5[0] - xi5) < 1e-12 and abs(p5[1]) < 1e-12 and d5 is not None

    xml = f"""<mujoco model="{model.name}-{model.variant}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{h!r}" integrator="{_INTEGRATOR[method]}" gravity="{_f([*model.gravity, 0.0])}"
          solver="Newton" iterations="{iterations}" tolerance="{tolerance!r}" ls_iterations="50">
    <flag contact="disable" autoreset="disable" refsafe="{'enable' if refsafe else 'disable'}"
          island="{'enable' if islands else 'disable'}"/>
  </option>
  <default>
    <equality solref="{_f(solref)}" solimp="{_f(solimp)}"/>
  </default>
  <worldbody>
    {body_open(0, None)}{inertial(0)}{hinge("A", ja.points[0])}
      {body_open(1, 0)}{inertial(1)}{slide("upper")}</body>
    </body>
    {body_open(2, None)}{inertial(2)}{hinge("B_thigh", jb3.points[0])}</body>
    {body_open(3, None)}{inertial(3)}{hinge("B_lower", jb4.points[0])}
      {body_open(4, 3)}{inertial(4)}{slide("lower")}
        {body_open(5, 4)}{inertial(5)}{"".join(shank_joints)}</body>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect name="C_rod_thigh" body1="{names[1]}" body2="{names[2]}" anchor="{_f(_local(*jc_rt.points[0]))}"/>
    <connect name="C_rod_shank" body1="{names[5]}" body2="{names[1]}" anchor="{_f(_local(*jc_rs.points[1]))}"/>
  </equality>
  <actuator>
    <motor name="upper" joint="upper" gear="1"/>
    <motor name="lower" joint="lower" gear="1"/>
  </actuator>
</mujoco>
"""
    return xml


class MujocoLeg:
    def __init__(self, scene: str, h: float, method: str = "rk4", variant: str = "revolute",
                 model_path=None, **xml_kw):
        if mujoco is None:
            raise ImportError("mujoco is not installed (pip install mujoco)")
        self.model = lm.load(model_path, variant)
        self.scene, self.h, self.method = scene, h, method
        self.forces = np.array(lm.scene_forces(self.model, scene), float)
        self.q0 = lm.stand_q0(self.model)
        self.xml = build_xml(self.model, h, method, **xml_kw)
        self.m = mujoco.MjModel.from_xml_string(self.xml)
        self.d = mujoco.MjData(self.m)
        self.body_ids = [mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_BODY, b.name)
                         for b in self.model.bodies]

    def q_of(self, qpos: np.ndarray) -> np.ndarray:
        """Our 18 absolute coordinates for a MuJoCo qpos (forward kinematics)."""
        d = self.d
        d.qpos[:] = qpos
        mujoco.mj_kinematics(self.m, d)
        q = np.empty(18)
        for i, bid in enumerate(self.body_ids):
            q[3 * i: 3 * i + 2] = d.xpos[bid, :2]
            R = d.xmat[bid]
            phi = math.atan2(R[3], R[0])
            phi0 = self.q0[3 * i + 2]
            q[3 * i + 2] = phi0 + math.remainder(phi - phi0, 2.0 * math.pi)
        return q

    def qd_of(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        d = self.d
        d.qpos[:] = qpos
        d.qvel[:] = qvel
        mujoco.mj_forward(self.m, d)
        qd = np.empty(18)
        v = np.zeros(6)
        for i, bid in enumerate(self.body_ids):
            # velocity of the body frame origin (= centre of mass) in world axes
            mujoco.mj_objectVelocity(self.m, d, mujoco.mjtObj.mjOBJ_BODY, bid, v, 0)
            qd[3 * i: 3 * i + 2] = v[3:5]
            qd[3 * i + 2] = v[2]
        return qd

    def simulate(self, t_end: float, *, every: int = 1, loop: str = "rollout") -> dict:
        h = self.h
        n_steps = int(round(t_end / h))
        if abs(n_steps * h - t_end) > 1e-9 * max(1.0, t_end):
            raise ValueError(f"t_end={t_end} is not a multiple of h={h}")
        m, d = self.m, self.d
        mujoco.mj_resetData(m, d)
        d.ctrl[:] = self.forces
        nq, nv = m.nq, m.nv
        if loop == "rollout":
            spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
            size = mujoco.mj_stateSize(m, spec)
            x0 = np.empty(size)
            mujoco.mj_getState(m, d, x0, spec)
            ctrl = np.tile(self.forces, (1, n_steps, 1))
            state = np.empty((1, n_steps, size))
            sens = np.empty((1, n_steps, max(m.nsensordata, 0)))
            t0 = time.perf_counter()
            _rollout.rollout(m, d, x0[None, :], ctrl, nstep=n_steps, state=state,
                             sensordata=sens)
            wall = time.perf_counter() - t0
            # FULLPHYSICS layout: time, qpos, qvel, ...
            ts = state[0, :, 0]
            qpos = state[0, :, 1: 1 + nq]
            qvel = state[0, :, 1 + nq: 1 + nq + nv]
        elif loop == "python":
            qpos = np.empty((n_steps, nq))
            qvel = np.empty((n_steps, nv))
            ts = np.empty(n_steps)
            step = mujoco.mj_step
            t0 = time.perf_counter()
            for k in range(n_steps):
                step(m, d)
                qpos[k] = d.qpos
                qvel[k] = d.qvel
                ts[k] = d.time
            wall = time.perf_counter() - t0
        else:
            raise ValueError(loop)
        bad = d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        t = np.concatenate([[0.0], ts])
        qpos = np.vstack([np.zeros(nq), qpos])
        qvel = np.vstack([np.zeros(nv), qvel])
        keep = np.arange(0, n_steps + 1, every) if every > 0 else np.array([0, n_steps])
        if keep[-1] != n_steps:
            keep = np.append(keep, n_steps)
        q = np.array([self.q_of(qpos[k]) for k in keep])
        qd_end = self.qd_of(qpos[-1], qvel[-1])
        return {"t": t[keep], "q": q, "q_end": q[-1], "qd_end": qd_end, "wall_s": wall,
                "ok": bool(np.all(np.isfinite(qpos))) and bad == 0, "n_steps": n_steps,
                "engine": f"mujoco {VERSION}", "method": self.method, "h": h,
                "variant": self.model.variant, "scene": self.scene,
                "qpos_end": qpos[-1].copy(), "loop": loop}


def run(scene: str, t_end: float, h: float, method: str = "rk4", *,
        variant: str = "revolute", every: int = 1, loop: str = "rollout",
        model_path=None, **xml_kw) -> dict:
    """Builds the MJCF, then integrates with fixed step h.

    Returns dict(t, q (N x 18, our absolute coordinates), wall_s (the
    integration only: time.perf_counter around mujoco.rollout, or around the
    Python mj_step loop with ``loop="python"``), q_end, qd_end, ...).
    ``xml_kw``: solref, solimp, tolerance, iterations (see build_xml).
    """
    return MujocoLeg(scene, h, method, variant, model_path, **xml_kw).simulate(
        t_end, every=every, loop=loop)
