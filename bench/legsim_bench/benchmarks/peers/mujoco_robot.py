"""The two-leg robot in MuJoCo: box, both six-bar legs, soft foot contacts.

The MJCF is written in code from the bench's reference model of the robot file
(``RobotModel``: bodies, masses, inertias, composed joints with mirrored
points, actuators with kp, kd, max_force, foot points, ground line and
friction). No number of the robot is retyped here.

Tree (all hinges about z, every motion in the xy plane, gravity (0, -g, 0)):

* the box: slide x, slide y (world axes), hinge z at its centre: 3 dofs;
* each leg hangs from the box by a spanning tree taken from the joint list in
  order: a joint joining a body of the tree to a new body becomes a tree
  joint of the new body (revolute: a hinge at its point; prismatic: a slide
  along the cylinder axis u, oriented so that positive qpos extends); the
  joints left over close the loops as ``connect`` equalities (for leg.toml:
  C_rod_thigh and D, the shank hanging on the upper rod at C). 2 x 7 tree
  dofs + 3 - 2 x 2 x 2 planar closure rows = 7 dofs, as the reference's z;
  the connects' z rows are identically zero and only regularized.
* Body frames sit at the centres of mass with local x = n(phi) and local
  -y = u(phi) (so a mirrored body, whose world angle is psi - phi, is an
  ordinary body with points (xi, -eta), as in the reference). The model is
  written at the scene's start pose: qpos = 0 is that pose, the connects hold
  there exactly.

Feet: a sphere of radius ``foot_radius`` (default 0.1 mm) centred on each
foot point, the only geoms that collide, against a plane whose surface is the
ground line moved down by the radius (so the foot point is on the line when
the sphere touches). condim 3 with an elliptic cone: in the plane the
out-of-plane friction direction has a zero Jacobian, so the cone is exactly
|T| <= mu N with one coefficient mu (MuJoCo has no static/kinetic pair; the
scene says which mu). margin = gap = 0 (MuJoCo's soft contact pushes
towards distance = margin, whatever gap is): a contact exists from zero
distance on.

Actuators (order of the robot file): ``force`` mode is a ``motor`` on the
slide (ctrl = axial force, N); ``servo`` mode is a ``general`` actuator with
gain kp and affine bias (0, -kp, -kd) on the slide, ctrl = l_cmd - l_0
(l_0 the length at the start pose), forcerange +-max_force: exactly
F = kp (l_cmd - l) - kd l_dot, saturated.

Soft constraints (both the loop closures and the contacts, friction included):
solref = (2 h, 1), a time constant of 2 h with critical damping, the stiffest
MuJoCo's ``refsafe`` admits. solimp = (0.9999, 0.9999, 0.001, 0.5, 2) for the
loop closures, the largest impedance (mjMAXIMP); (0.99, 0.99, 0.001, 0.5, 2)
for the contacts: MuJoCo's contact exists only below its rest distance, and
with 0.9999 a loaded foot sinks so little (nanometres) that RK4 loses and
finds the contact again (13 of 1000 steps of Fig. 7 at h = 1e-4, force
spikes of 60 N); with 0.99 it never lets go and the end forces converge. Newton solver, tolerance 1e-12, islands
disabled (``island`` flag), autoreset disabled (a blow-up shows as ok=False).
The integrator is RK4 by default (``euler`` and ``implicitfast`` also).
"""
from __future__ import annotations

import math
import time

import numpy as np

from . import robot_scenes as rs
from .peer_tables import option_block

try:
    import mujoco
    import mujoco.rollout as _rollout

    VERSION = mujoco.__version__
except ImportError:  # pragma: no cover - mujoco is in the bench's [peers] extra
    mujoco = None
    _rollout = None
    VERSION = None

METHODS = ("rk4", "euler", "implicitfast")
_INTEGRATOR = {"rk4": "RK4", "euler": "Euler", "implicitfast": "implicitfast"}
SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)            # loop closures
CONTACT_SOLIMP = (0.99, 0.99, 0.001, 0.5, 2.0)         # feet (see the module doc)
FOOT_RADIUS = 1e-4          # m


def available() -> bool:
    return mujoco is not None


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in x)


def _local(pt) -> tuple:
    """Body-fixed (xi, eta) as the MuJoCo body frame's (x, y, z)."""
    return (float(pt[1]), -float(pt[0]), 0.0)


def _quat_z(a: float) -> tuple:
    return (math.cos(0.5 * a), 0.0, 0.0, math.sin(0.5 * a))


def _rel(q: np.ndarray, parent: int, child: int) -> tuple:
    """pos, angle of the child's frame in the parent's frame (q: (nb, 3))."""
    xc, yc, pc = q[child]
    xp, yp, pp = q[parent]
    c, s = math.cos(pp), math.sin(pp)
    dx, dy = xc - xp, yc - yp
    return (c * dx + s * dy, -s * dx + c * dy, 0.0), pc - pp


def spanning_tree(robot) -> tuple:
    """(parent joint index per body (None for the box), cut joint indices)."""
    in_tree = {0}
    via = {0: None}
    used = set()
    changed = True
    while changed:
        changed = False
        for k, j in enumerate(robot.joints):
            if k in used or len(j.bodies) != 2:
                continue
            a, b = j.bodies
            if (a in in_tree) != (b in in_tree):
                new = b if a in in_tree else a
                in_tree.add(new)
                via[new] = k
                used.add(k)
                changed = True
    if len(in_tree) != robot.nb:
        raise ValueError("the joints do not connect every body to the box")
    cuts = [k for k in range(robot.nj) if k not in used]
    for k in cuts:
        if robot.joints[k].kind != "revolute":
            raise NotImplementedError(f"joint {robot.joints[k].name}: only revolute loop closures "
                                      "are modelled (MuJoCo connect)")
    return via, cuts


def build_xml(scene: rs.Scene, h: float, method: str = "rk4", *, solref=None, solimp=SOLIMP,
              contact_solimp=CONTACT_SOLIMP, foot_radius: float = FOOT_RADIUS, tolerance: float = 1e-12, iterations: int = 100,
              refsafe: bool = True, cone: str = "elliptic") -> str:
    """MJCF of the robot of ``scene`` at its start pose. ``solref`` None: (2 h, 1)."""
    if method not in _INTEGRATOR:
        raise ValueError(f"unknown method {method!r}; known: {METHODS}")
    if not (h > 0 and math.isfinite(h)):
        raise ValueError("h must be a positive number of seconds")
    if not foot_radius > 0:
        raise ValueError("foot_radius must be positive")
    if solref is None:
        solref = (2.0 * h, 1.0)
    robot = scene.robot
    q = robot.absolute_q(scene.z0).reshape(-1, 3)
    via, cuts = spanning_tree(robot)
    children = {i: [] for i in range(robot.nb)}
    for body, k in via.items():
        if k is not None:
            j = robot.joints[k]
            parent = j.bodies[0] if j.bodies[1] == body else j.bodies[1]
            children[parent].append(body)
    names = [n.replace(".", "_") for n in robot.body_names]
    masses = robot._Md                       # (nb, 3): m, m, J (read only)
    foot_of = dict(zip(robot._foot_body, robot._foot_pt))
    foot_names = [n.replace(".", "_") for n in robot.foot_names]
    slide_of = {}                            # prismatic joint index -> slide name

    def tree_joint(body: int) -> str:
        k = via[body]
        j = robot.joints[k]
        name = j.name.replace(".", "_")
        if j.kind == "revolute":
            pt = j.points[j.bodies.index(body)]
            return f'<joint name="{name}" type="hinge" axis="0 0 1" pos="{_f(_local(pt))}"/>'
        if j.kind == "prismatic":
            cyl, rod = j.bodies
            # local u = (0, -1, 0); positive qpos extends whichever end is the child
            axis = (0.0, -1.0, 0.0) if body == rod else (0.0, 1.0, 0.0)
            slide_of[k] = name
            return f'<joint name="{name}" type="slide" axis="{_f(axis)}"/>'
        raise NotImplementedError(f"joint {j.name}: kind {j.kind} is not modelled")

    def body_xml(body: int, parent: int, indent: str) -> str:
        pos, ang = _rel(q, parent, body)
        m, _, J = map(float, masses[body])
        lines = [f'{indent}<body name="{names[body]}" pos="{_f(pos)}" quat="{_f(_quat_z(ang))}">',
                 f'{indent}  <inertial pos="0 0 0" mass="{m!r}" diaginertia="{_f([J] * 3)}"/>',
                 f'{indent}  {tree_joint(body)}']
        if body in foot_of:
            fi = robot._foot_body.index(body)
            lines.append(f'{indent}  <geom name="{foot_names[fi]}" type="sphere" size="{foot_radius!r}" '
                         f'pos="{_f(_local(foot_of[body]))}" contype="1" conaffinity="0" condim="3" '
                         f'friction="{scene.mu!r} 0 0"/>')
        for c in children[body]:
            lines.append(body_xml(c, body, indent + "  "))
        lines.append(f"{indent}</body>")
        return "\n".join(lines)

    # the box: world-axis slides expressed in its start frame, then the hinge
    x0, y0, psi0 = q[0]
    cb, sb = math.cos(psi0), math.sin(psi0)
    mb, _, Jb = map(float, masses[0])
    box = [f'    <body name="{names[0]}" pos="{_f((x0, y0, 0.0))}" quat="{_f(_quat_z(psi0))}">',
           f'      <inertial pos="0 0 0" mass="{mb!r}" diaginertia="{_f([Jb] * 3)}"/>',
           f'      <joint name="box_x" type="slide" axis="{_f((cb, -sb, 0.0))}"/>',
           f'      <joint name="box_y" type="slide" axis="{_f((sb, cb, 0.0))}"/>',
           '      <joint name="box_phi" type="hinge" axis="0 0 1"/>']
    for c in children[0]:
        box.append(body_xml(c, 0, "      "))
    box.append("    </body>")

    # the ground: a plane whose local z is the line's normal (-sin a, cos a, 0)
    g = robot.ground
    a = g.slope
    qx = (math.cos(-math.pi / 4), math.sin(-math.pi / 4), 0.0, 0.0)      # z -> +y
    qz = _quat_z(a)
    qg = (qz[0] * qx[0] - qz[3] * qx[3], qz[0] * qx[1] - qz[3] * qx[2],
          qz[0] * qx[2] + qz[3] * qx[1], qz[0] * qx[3] + qz[3] * qx[0])
    gp = np.asarray(g.point, float) - foot_radius * g.normal
    ground = (f'    <geom name="ground" type="plane" size="0 0 1" pos="{_f((gp[0], gp[1], 0.0))}" '
              f'quat="{_f(qg)}" contype="0" conaffinity="1" condim="3" friction="{scene.mu!r} 0 0"/>')

    eqs = []
    for k in cuts:
        j = robot.joints[k]
        b1, b2 = j.bodies
        eqs.append(f'    <connect name="{j.name.replace(".", "_")}" body1="{names[b1]}" '
                   f'body2="{names[b2]}" anchor="{_f(_local(j.points[0]))}"/>')

    # actuators, robot file order: the slide of the prismatic joint (cylinder, rod)
    acts = []
    for a_i, ((cyl, rod), mode) in enumerate(zip(robot._actuator_bodies(), scene.modes)):
        k = next(k for k, j in enumerate(robot.joints) if j.kind == "prismatic" and j.bodies == (cyl, rod))
        if k not in slide_of:
            raise NotImplementedError(f"actuator {robot.actuator_names[a_i]}: its joint closes a loop")
        an = robot.actuator_names[a_i].replace(".", "_")
        if mode == "force":
            acts.append(f'    <motor name="{an}" joint="{slide_of[k]}" gear="1"/>')
        elif mode == "servo":
            kp, kd, fmax = (float(x[a_i]) for x in (robot._kp, robot._kd, robot._fmax))
            acts.append(f'    <general name="{an}" joint="{slide_of[k]}" gear="1" gaintype="fixed" '
                        f'gainprm="{kp!r}" biastype="affine" biasprm="0 {-kp!r} {-kd!r}" '
                        f'forcelimited="true" forcerange="{-fmax!r} {fmax!r}"/>')
        else:
            raise ValueError(f"actuator mode {mode!r}: force or servo")

    grav = [*robot.gravity, 0.0]
    return f"""<mujoco model="{robot.name}-{scene.name}">
  <compiler angle="radian" autolimits="true"/>
{option_block(h, _INTEGRATOR[method], grav, tolerance=tolerance, iterations=iterations, cone=cone,
              flags={"refsafe": "enable" if refsafe else "disable"})}
  <default>
    <equality solref="{_f(solref)}" solimp="{_f(solimp)}"/>
    <geom solref="{_f(solref)}" solimp="{_f(contact_solimp)}"/>
  </default>
  <worldbody>
{ground}
{chr(10).join(box)}
  </worldbody>
  <equality>
{chr(10).join(eqs)}
  </equality>
  <actuator>
{chr(10).join(acts)}
  </actuator>
</mujoco>
"""


class MujocoRobot:
    """One scene at one step: build, then ``simulate``."""

    def __init__(self, scene, h: float, method: str = "rk4", robot_path=None, **xml_kw):
        if mujoco is None:
            raise ImportError("mujoco is not installed (the bench's [peers] extra)")
        self.scene = rs.setup(scene, robot_path) if isinstance(scene, str) else scene
        self.h, self.method = float(h), method
        robot = self.scene.robot
        self.xml = build_xml(self.scene, h, method, **xml_kw)
        self.m = mujoco.MjModel.from_xml_string(self.xml)
        self.d = mujoco.MjData(self.m)
        bid = mujoco.mj_name2id
        self.body_ids = [bid(self.m, mujoco.mjtObj.mjOBJ_BODY, n.replace(".", "_"))
                         for n in robot.body_names]
        self.foot_geoms = [bid(self.m, mujoco.mjtObj.mjOBJ_GEOM, n.replace(".", "_"))
                           for n in robot.foot_names]
        self.q0 = robot.absolute_q(self.scene.z0).reshape(-1, 3)
        self.angle_bodies = rs.angle_bodies(robot)
        l0 = robot.lengths(self.scene.z0)
        self.ctrl = np.array([v if mode == "force" else v - l0[a]
                              for a, (mode, v) in enumerate(zip(self.scene.modes, self.scene.values))])

    def q_of(self, qpos) -> np.ndarray:
        """World poses (39,) of the 13 bodies for a qpos (forward kinematics)."""
        d = self.d
        d.qpos[:] = qpos
        mujoco.mj_kinematics(self.m, d)
        q = np.empty((len(self.body_ids), 3))
        for i, b in enumerate(self.body_ids):
            q[i, :2] = d.xpos[b, :2]
            R = d.xmat[b]
            phi = math.atan2(R[3], R[0])
            q[i, 2] = self.q0[i, 2] + math.remainder(phi - self.q0[i, 2], 2.0 * math.pi)
        return q.reshape(-1)

    def ground_forces(self, qpos, qvel) -> tuple:
        """(N (2,), T (2,), world force on each foot (2, 2)) at a state: the
        constraint forces of mj_forward at that state (a free foot: 0)."""
        m, d = self.m, self.d
        d.qpos[:] = qpos
        d.qvel[:] = qvel
        d.ctrl[:] = self.ctrl
        mujoco.mj_forward(m, d)
        G = np.zeros((2, 2))
        f = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            for k, gid in enumerate(self.foot_geoms):
                if gid in (c.geom1, c.geom2) and c.efc_address >= 0:
                    mujoco.mj_contactForce(m, d, i, f)
                    frame = np.asarray(c.frame).reshape(3, 3)   # rows: normal (geom1 -> geom2), t1, t2
                    Fw = frame.T @ f[:3]                          # on geom2
                    G[k] += (Fw if c.geom2 == gid else -Fw)[:2]
        g = self.scene.robot.ground
        return G @ g.normal, G @ g.tangent, G

    def simulate(self, t_end: float | None = None, *, every: int = 1) -> dict:
        """Fixed step h from the start pose at rest (mujoco.rollout, one
        thread). ``wall_s``: time.perf_counter around rollout only."""
        h = self.h
        t_end = self.scene.t_end if t_end is None else float(t_end)
        n_steps = int(round(t_end / h))
        if n_steps < 1 or abs(n_steps * h - t_end) > 1e-9 * max(1.0, t_end):
            raise ValueError(f"t_end={t_end} is not a positive multiple of h={h}")
        m, d = self.m, self.d
        mujoco.mj_resetData(m, d)
        d.ctrl[:] = self.ctrl
        nq, nv = m.nq, m.nv
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        x0 = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, x0, spec)
        ctrl = np.tile(self.ctrl, (1, n_steps, 1))
        state = np.empty((1, n_steps, x0.size))
        sens = np.empty((1, n_steps, max(m.nsensordata, 0)))
        t0 = time.perf_counter()
        _rollout.rollout(m, d, x0[None, :], ctrl, nstep=n_steps, state=state, sensordata=sens)
        wall = time.perf_counter() - t0
        bad = d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        qpos = np.vstack([np.zeros(nq), state[0, :, 1:1 + nq]])
        qvel = np.vstack([np.zeros(nv), state[0, :, 1 + nq:1 + nq + nv]])
        t = np.arange(n_steps + 1) * h
        keep = np.arange(0, n_steps + 1, every) if every > 0 else np.array([0, n_steps])
        if keep[-1] != n_steps:
            keep = np.append(keep, n_steps)
        robot = self.scene.robot
        q = np.array([self.q_of(qpos[k]) for k in keep])
        z = np.array([rs.z_of_q(robot, qk, self.angle_bodies) for qk in q])
        ok = bool(np.all(np.isfinite(qpos))) and bad == 0
        N, T, G = self.ground_forces(qpos[-1], qvel[-1]) if ok else (np.full(2, np.nan),) * 3
        return {"t": t[keep], "q": q, "z": z, "normal": N, "tangential": T, "ground": G,
                "qpos_end": qpos[-1].copy(), "qvel_end": qvel[-1].copy(),
                "wall_s": wall, "per_step_s": wall / n_steps, "n_steps": n_steps, "ok": ok,
                "engine": f"mujoco {VERSION}", "method": self.method, "h": h,
                "scene": self.scene.name, "mass": float(m.body_mass.sum())}


def run(scene, h: float, method: str = "rk4", *, t_end=None, every: int = 1, robot_path=None,
        **xml_kw) -> dict:
    """Build and run one scene (a name of robot_scenes.SCENES or a Scene)."""
    return MujocoRobot(scene, h, method, robot_path, **xml_kw).simulate(t_end, every=every)


def compare(scene, h: float, method: str = "rk4", *, sample_dt: float = 1e-3, repeats: int = 1,
            ref=None, robot_path=None, **xml_kw) -> dict:
    """Run a stuck-feet scene and measure it against the reference along the
    whole trajectory, sampled every ``sample_dt`` (a multiple of h):
    err_z = max over samples and the 7 coordinates of |z - z_ref|;
    err_NT = max |N, T - reference| per foot at the end (N). Cost: the
    smallest wall time per step over ``repeats`` rollouts."""
    peer = MujocoRobot(scene, h, method, robot_path, **xml_kw)
    sc = peer.scene
    every = int(round(sample_dt / h))
    if every < 1 or abs(every * h - sample_dt) > 1e-9:
        raise ValueError(f"sample_dt={sample_dt} is not a multiple of h={h}")
    best = None
    for _ in range(max(1, repeats)):
        r = peer.simulate(every=every)
        if best is None or r["per_step_s"] < best["per_step_s"]:
            best = r
    if ref is None:
        ref = rs.reference(sc, best["t"])
    out = dict(best)
    out["err_z"] = rs.trajectory_error(best["z"], ref["z"])
    out["err_NT"] = float(max(np.max(np.abs(best["normal"] - ref["normal"][-1])),
                              np.max(np.abs(best["tangential"] - ref["tangential"][-1]))))
    out["ref"] = ref
    return out
