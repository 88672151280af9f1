"""The hexapod in MuJoCo (3D): free box, six yokes, six six-bar legs, held feet.

The MJCF is written in code from the bench's hexapod reference
(``HexapodModel.from_toml(models/hexapod.toml)``: box, yoke, hip offset, bar
radius, each leg's LegModel of leg.toml: bars, joints, points, actuators,
foot). No number of the robot is retyped here.

Bodies and frames, as the reference and legsim's spatial model
(docs/design/spatial.md) place them, written at the scene's start pose so
that qpos0 is that pose and every equality holds there exactly:

* the box: a free joint, its frame the box's (principal inertia, centre);
* leg k's yoke: a hinge about the box's z at the hip point, its frame
  R_box Rz(heading + psi) (x out along the leg's plane), inertia principal in
  it about its centre of mass ``yoke.com``;
* the leg's bars: the leg file's planar point (x, y) at (hip_offset + x, 0, y)
  of the yoke frame; a bar's frame at its centre of mass with axes
  (u, n, -y_yoke) (u, n the leg file's axis and normal), inertia
  (m r^2 / 2, J, J) about them, r the file's bar_radius, J the leg file's;
* the leg's joints as a spanning tree from the yoke, taken from its joint
  list in order (mujoco_robot.spanning_tree's rule): a revolute a hinge about
  the bar's local z (the plane's normal) at its point, a prismatic a slide
  along the cylinder's axis u (positive extends: the length is l0 + qpos);
  the joints left over (leg.toml: C_rod_thigh and D) close the loops as
  ``connect`` equalities. Per leg 7 tree dofs, 2 x 2 independent loop rows
  (each connect's out-of-plane row is identically zero and only regularized),
  3 dofs (psi, phi3, phi6) as the reference's;
* a held foot: a ``connect`` of the shank's foot point to the world point
  where the start pose puts it (3 rows, the ground's force on the foot its
  multiplier, world frame).

No geoms and no contacts: the scenes' feet are held or in the air (scene b's
free feet are lifted 8.6 cm). Actuators (ctrl order): each leg's two linear
actuators in its file's order, leg by leg, as ``motor`` on their slides
(gear 1, ctrl = axial force, N, +F u on the rod, -F u on the cylinder), then
the six rowing torques as ``motor`` on the yoke hinges (N m on the yoke, its
reaction on the box). Gravity the file's.

Soft constraints: MuJoCo's equalities are not exact. solref = (2 h, 1) (a
time constant of 2 h, critically damped: the stiffest ``refsafe`` admits),
solimp = (0.9999, 0.9999, 0.001, 0.5, 2) (the largest impedance), as
mujoco_robot.py. The held feet drift and the loops open by amounts that
shrink with h; that is the floor of the error in the table. Newton solver,
tolerance 1e-12, islands off, autoreset off (a blow-up shows as ok=False).
Integrator RK4 by default (``euler``, ``implicitfast`` also).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...reference.hexapod import LEGS, HexapodModel, _rz, quat_matrix
from ...reference.model import n as _n, u as _u
from ...scene import find_root

# MuJoCo (optional: the bench's [peers] extra), its methods and the loop closures' stiffest
# equality settings: the two-leg robot peer's
from .mujoco_robot import _INTEGRATOR, METHODS, SOLIMP, VERSION, _rollout, mujoco  # noqa: F401
from .peer_tables import option_block
ROW = (0.3, 0.1, -0.2, 0.0, 0.25, -0.15)      # scene b's rowing angles (test_hexapod_reference's)
T_END = 0.2
SCENES = ("a_six", "b_tripod")


def available() -> bool:
    return mujoco is not None


def default_path():
    return find_root() / "models" / "hexapod.toml"


# ------------------------------------------------------------------ scenes
@dataclass
class Scene:
    """A start pose (legsim.Hexapod's keys), the held legs, constant actuator forces (6, 2) and
    rowing torques (6,), the end time."""
    name: str
    pose: dict
    stance: tuple
    force_n: np.ndarray
    torque_nm: np.ndarray
    t_end: float = T_END


def lifted(pose, legs=(1, 3, 5), by=0.03) -> dict:
    """pose with the upper actuators of ``legs`` shorter by ``by`` m: their feet off the ground."""
    lengths = [list(x) for x in pose["length_m"]]
    for k in legs:
        lengths[k][0] -= by
    return dict(pose, length_m=lengths)


def setup(name: str, ref: HexapodModel) -> Scene:
    """tests/bench/test_hexapod_reference.py's scenes. a_six: the stand at box height 1 m, all
    six feet held, the six-feet statics' forces plus 50 N on the right legs' (0, 1, 2) upper
    actuators. b_tripod: legs 0, 2, 4 held at unequal rowing angles ROW, legs 1, 3, 5 free with
    their feet lifted, the tripod statics' forces plus 50 N on legs 0 and 2's uppers."""
    if name == "a_six":
        pose, stance, push = ref.stand_pose(1.0), tuple(range(LEGS)), (0, 1, 2)
    elif name == "b_tripod":
        pose, stance, push = lifted(ref.stand_pose(1.0, ROW)), (0, 2, 4), (0, 2)
    else:
        raise ValueError(f"unknown scene {name!r}; known: {SCENES}")
    s = ref.statics(pose, stance=stance)
    Fa = np.array(s["actuator_force_n"], float)
    Fa[list(push), 0] += 50.0
    return Scene(name, pose, stance, Fa, np.array(s["rowing_torque_nm"], float))


def reference(sc: Scene, ref: HexapodModel):
    """The reference (minimal coordinates, DOP853 at rtol 1e-12) at the scene's end."""
    return ref.simulate(sc.pose, sc.stance, sc.force_n, sc.torque_nm, sc.t_end, [0.0, sc.t_end])


# ------------------------------------------------------------------ MJCF
def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def _quat(R) -> np.ndarray:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, float).reshape(9))
    return q


def _tree(model) -> tuple:
    """Leg's spanning tree from the yoke ("Y"): (parent joint index per bar, cut joints)."""
    in_tree, via, used = {"Y"}, {}, set()
    changed = True
    while changed:
        changed = False
        for k, j in enumerate(model.joints):
            if k in used:
                continue
            ends = ("Y", j.bodies[0]) if j.kind == "revolute_to_frame" else j.bodies
            a, b = ends
            if (a in in_tree) != (b in in_tree):
                new = b if a in in_tree else a
                in_tree.add(new)
                via[new] = k
                used.add(k)
                changed = True
    if len(in_tree) != model.nb + 1:
        raise ValueError("the leg's joints do not connect every bar to the yoke")
    cuts = [k for k in range(model.nj) if k not in used]
    for k in cuts:
        if model.joints[k].kind != "revolute":
            raise NotImplementedError(f"joint {model.joints[k].name}: only revolute loop closures")
    return via, cuts


def build_xml(sc: Scene, ref: HexapodModel, h: float, method: str = "rk4", *, solref=None,
              solimp=SOLIMP, tolerance: float = 1e-12, iterations: int = 100, walk: dict | None = None) -> tuple:
    """(MJCF, layout): the hexapod at the scene's start pose; layout names the slides, yokes and
    held feet. ``solref`` None: (2 h, 1). ``walk`` (hexapod_walk.mjcf_walk's keys): the feet as
    spheres on the ground plane with contacts (no held feet), the actuators as servos."""
    if method not in _INTEGRATOR:
        raise ValueError(f"unknown method {method!r}; known: {METHODS}")
    if not (h > 0 and math.isfinite(h)):
        raise ValueError("h must be a positive number of seconds")
    solref = (2.0 * h, 1.0) if solref is None else solref
    pose = sc.pose
    r = np.asarray(pose["box_m"], float)
    R = quat_matrix(pose["box_quat"])
    th = ref._thetas(pose)
    lay = {"slides": [], "yokes": [], "feet": [], "l0": np.zeros((LEGS, 2)),
           "psi0": np.array(pose["rowing_rad"], float)}
    box = [f'    <body name="box" pos="{_f(r)}" quat="{_f(_quat(R))}">',
           f'      <inertial pos="0 0 0" mass="{ref.box_mass!r}" diaginertia="{_f(ref.box_inertia)}"/>',
           '      <freejoint name="box"/>']
    eqs = []
    for k, leg in enumerate(ref.legs):
        lm, nm = leg.model, leg.name
        psi = float(pose["rowing_rad"][k])
        Ryb = _rz(leg.heading + psi)                     # yoke in the box frame
        Ry = R @ Ryb
        oy = r + R @ leg.hip
        # world frames of the bars: centre and rotation (u, n, -y_yoke)
        q = lm.absolute_q(th[k]).reshape(-1, 3)
        Xw, Rw = {"Y": oy}, {"Y": Ry}
        for i, (x, y, ph) in enumerate(q):
            Xw[i] = oy + Ry @ np.array([ref.hip_offset + x, 0.0, y])
            uu, nn = _u(ph), _n(ph)
            Rw[i] = Ry @ np.column_stack([[uu[0], 0.0, uu[1]], [nn[0], 0.0, nn[1]], [0.0, -1.0, 0.0]])
        lay["l0"][k] = lm.lengths(th[k])
        via, cuts = _tree(lm)
        children = {"Y": [], **{i: [] for i in range(lm.nb)}}
        for b, j in via.items():
            jt = lm.joints[j]
            parent = "Y" if jt.kind == "revolute_to_frame" else (jt.bodies[0] if jt.bodies[1] == b else jt.bodies[1])
            children[parent].append(b)
        slide, foot_geom = {}, {}
        if walk is not None:
            # the foot point the sphere's centre: on the ground (moved down by the radius) when it touches
            fp = lm._foot_pt
            foot_geom[lm._shank] = (f'<geom name="{nm}_foot" type="sphere" size="{walk["foot_radius"]!r}" '
                                    f'pos="{_f((fp[0], fp[1], 0.0))}" contype="1" conaffinity="0" condim="3" '
                                    f'friction="{walk["mu"]!r} 0 0"/>')
            lay["feet"].append((k, f"{nm}_foot"))

        def bar(b, parent, ind):
            pos = Rw[parent].T @ (Xw[b] - Xw[parent])
            rel = Rw[parent].T @ Rw[b]
            bd = lm.bodies[b]
            jt = lm.joints[via[b]]
            jn = f"{nm}_{jt.name}"
            if jt.kind in ("revolute", "revolute_to_frame"):
                pt = jt.points[jt.bodies.index(b)]
                joint = f'<joint name="{jn}" type="hinge" axis="0 0 1" pos="{_f((pt[0], pt[1], 0.0))}"/>'
            elif jt.kind == "prismatic":
                cyl, rod = jt.bodies
                slide[(cyl, rod)] = jn
                joint = f'<joint name="{jn}" type="slide" axis="{"1 0 0" if b == rod else "-1 0 0"}"/>'
            else:
                raise NotImplementedError(f"joint {jt.name}: kind {jt.kind}")
            I = (0.5 * bd.mass * ref.bar_radius ** 2, bd.inertia, bd.inertia)
            out = [f'{ind}<body name="{nm}_{bd.name}" pos="{_f(pos)}" quat="{_f(_quat(rel))}">',
                   f'{ind}  <inertial pos="0 0 0" mass="{bd.mass!r}" diaginertia="{_f(I)}"/>',
                   f'{ind}  {joint}']
            if b in foot_geom:
                out.append(f"{ind}  {foot_geom[b]}")
            for c in children[b]:
                out += bar(c, b, ind + "  ")
            out.append(f"{ind}</body>")
            return out

        box += [f'      <body name="{nm}_yoke" pos="{_f(leg.hip)}" quat="{_f(_quat(Ryb))}">',
                f'        <inertial pos="{_f(ref.yoke_com)}" mass="{ref.yoke_mass!r}" '
                f'diaginertia="{_f(ref.yoke_inertia)}"/>',
                f'        <joint name="{nm}_row" type="hinge" axis="0 0 1" pos="0 0 0"/>']
        for c in children["Y"]:
            box += bar(c, "Y", "        ")
        box.append("      </body>")
        for j in cuts:
            jt = lm.joints[j]
            b1, b2 = jt.bodies
            pt = jt.points[0]
            eqs.append(f'    <connect name="{nm}_{jt.name}" body1="{nm}_{lm.bodies[b1].name}" '
                       f'body2="{nm}_{lm.bodies[b2].name}" anchor="{_f((pt[0], pt[1], 0.0))}"/>')
        if walk is None and k in sc.stance:
            fp = lm._foot_pt
            eqs.append(f'    <connect name="{nm}_foot" body1="{nm}_{lm.bodies[lm._shank].name}" '
                       f'anchor="{_f((fp[0], fp[1], 0.0))}"/>')
            lay["feet"].append((k, f"{nm}_foot"))
        for a in lm.actuators:
            if (a.cylinder, a.rod) not in slide:
                raise NotImplementedError(f"actuator {a.name}: its joint closes a loop")
            lay["slides"].append(slide[(a.cylinder, a.rod)])
        lay["yokes"].append(f"{nm}_row")
    box.append("    </body>")
    if walk is None:
        acts = [f'    <motor name="{j}" joint="{j}" gear="1"/>' for j in lay["slides"] + lay["yokes"]]
    else:
        # servos: kp ctrl - kp q - kd q' with ctrl = set-point + feed-forward / kp (hexapod_walk.controls),
        # the sum saturated as legsim's
        gains = [walk["actuator"][i % 2] for i in range(len(lay["slides"]))] + [walk["rowing"]] * LEGS
        acts = [f'    <general name="{j}" joint="{j}" gear="1" gaintype="fixed" gainprm="{kp!r}" '
                f'biastype="affine" biasprm="0 {-kp!r} {-kd!r}" forcelimited="true" '
                f'forcerange="{-fmax!r} {fmax!r}"/>'
                for j, (kp, kd, fmax) in zip(lay["slides"] + lay["yokes"], gains)]
    opts = {} if walk is None else {"cone": "elliptic", "impratio": walk["impratio"],
                                    "noslip_iterations": walk["noslip_iterations"]}
    ground = "" if walk is None else (
        f'    <geom name="ground" type="plane" size="0 0 1" pos="0 0 {-walk["foot_radius"]!r}" '
        f'contype="0" conaffinity="1" condim="3" friction="{walk["mu"]!r} 0 0"/>\n')
    geom_default = "" if walk is None else \
        f'    <geom solref="{_f(solref)}" solimp="{_f(walk["contact_solimp"])}"/>\n'
    xml = f"""<mujoco model="{ref.name}-{sc.name}">
  <compiler angle="radian" autolimits="true"/>
{option_block(h, _INTEGRATOR[method], ref.gravity, tolerance=tolerance, iterations=iterations,
              flags={"contact": "disable"} if walk is None else {}, **opts)}
  <default>
    <equality solref="{_f(solref)}" solimp="{_f(solimp)}"/>
{geom_default}  </default>
  <worldbody>
{ground}{chr(10).join(box)}
  </worldbody>
  <equality>
{chr(10).join(eqs)}
  </equality>
  <actuator>
{chr(10).join(acts)}
  </actuator>
</mujoco>
"""
    return xml, lay


# ------------------------------------------------------------------ running
class MujocoHexapod:
    """One scene at one step: build, then ``simulate``."""

    def __init__(self, sc: Scene, ref: HexapodModel, h: float, method: str = "rk4", **xml_kw):
        if mujoco is None:
            raise ImportError("mujoco is not installed (the bench's [peers] extra)")
        self.sc, self.ref, self.h, self.method = sc, ref, float(h), method
        self.xml, self.lay = build_xml(sc, ref, h, method, **xml_kw)
        self.m = mujoco.MjModel.from_xml_string(self.xml)
        self.d = mujoco.MjData(self.m)
        jid = lambda n: mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_JOINT, n)   # noqa: E731
        self.slide_adr = np.array([self.m.jnt_qposadr[jid(n)] for n in self.lay["slides"]]).reshape(LEGS, 2)
        self.yoke_adr = np.array([self.m.jnt_qposadr[jid(n)] for n in self.lay["yokes"]])
        self.feet = [(k, mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_EQUALITY, n)) for k, n in self.lay["feet"]]
        self.ctrl = np.concatenate([np.ravel(sc.force_n), sc.torque_nm])

    def outputs(self, qpos, qvel) -> dict:
        """Box place and quaternion, rowing angles, lengths, the held feet's ground forces
        (world, N: the multipliers of their connects from mj_forward at that state)."""
        m, d = self.m, self.d
        d.qpos[:] = qpos
        d.qvel[:] = qvel
        d.ctrl[:] = self.ctrl
        mujoco.mj_forward(m, d)
        f = np.zeros((LEGS, 3))
        eq = d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY
        for k, e in self.feet:
            rows = np.flatnonzero(eq & (d.efc_id == e))
            f[k] = d.efc_force[rows]
        return {"box_m": qpos[:3].copy(), "box_quat": qpos[3:7] / np.linalg.norm(qpos[3:7]),
                "rowing_rad": self.lay["psi0"] + qpos[self.yoke_adr],
                "length_m": self.lay["l0"] + qpos[self.slide_adr], "foot_force_n": f}

    def simulate(self) -> dict:
        """Fixed step h from the start at rest to t_end (mujoco.rollout, one thread);
        ``per_step_s``: time.perf_counter around rollout only, over the steps."""
        h, m, d = self.h, self.m, self.d
        n_steps = int(round(self.sc.t_end / h))
        if n_steps < 1 or abs(n_steps * h - self.sc.t_end) > 1e-9:
            raise ValueError(f"t_end={self.sc.t_end} is not a positive multiple of h={h}")
        mujoco.mj_resetData(m, d)
        d.ctrl[:] = self.ctrl
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        x0 = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, x0, spec)
        ctrl = np.tile(self.ctrl, (1, n_steps, 1))
        state = np.empty((1, n_steps, x0.size))
        t0 = time.perf_counter()
        _rollout.rollout(m, d, x0[None, :], ctrl, nstep=n_steps, state=state)
        wall = time.perf_counter() - t0
        bad = d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        qpos = state[0, -1, 1:1 + m.nq]
        qvel = state[0, -1, 1 + m.nq:1 + m.nq + m.nv]
        ok = bool(np.all(np.isfinite(state[0, -1]))) and bad == 0
        out = self.outputs(qpos, qvel) if ok else {}
        out.update(ok=ok, wall_s=wall, per_step_s=wall / n_steps, n_steps=n_steps, h=h,
                   engine=f"mujoco {VERSION}", method=self.method, scene=self.sc.name)
        return out


def legsim_run(sc: Scene, h: float, hexapod=None) -> dict:
    """legsim itself on the scene (legsim.Hexapod.sim with the stance's feet stuck, its RK4 on the
    rotation group at step h, the scene's forces and torques): its end state; ``per_step_s``
    the wall time of one ``step(n)`` call (a compiled loop) over the steps, set-up excluded."""
    import legsim

    hx = hexapod or legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))
    n_steps = int(round(sc.t_end / h))
    sim = hx.sim(sc.pose, stuck=sc.stance)
    sim.command(sc.force_n, sc.torque_nm)
    t0 = time.perf_counter()
    sim.step(n_steps, h_s=h)
    wall = time.perf_counter() - t0
    st = sim.state()
    ok = all(st["foot_state"][k] == "stuck" for k in sc.stance) and bool(np.all(np.isfinite(st["box_m"])))
    st.update(ok=ok, per_step_s=wall / n_steps, n_steps=n_steps, h=h, engine="legsim double",
              method="RK4 (rotation group) + projection", scene=sc.name)
    return st


def errors(out: dict, res, stance) -> dict:
    """Against the reference's end (res: HexapodResult): box place (m), box rotation (the angle
    of R_ref^T R, rad), rowing (rad), lengths (m), the held feet's ground forces (N); max abs."""
    if not out.get("ok"):
        return {k: float("nan") for k in ("box", "rot", "rowing", "lengths", "force")}
    q = np.asarray(out["box_quat"], float)
    q = q / np.linalg.norm(q)
    qr = res.box_q[-1, 3:] / np.linalg.norm(res.box_q[-1, 3:])
    # the vector part of q_ref^-1 q (acos of the scalar part loses the small angles)
    dv = qr[0] * q[1:] - q[0] * qr[1:] - np.cross(qr[1:], q[1:])
    st = list(stance)
    return {"box": float(np.abs(out["box_m"] - res.box_q[-1, :3]).max()),
            "rot": 2.0 * math.asin(min(1.0, float(np.linalg.norm(dv)))),
            "rowing": float(np.abs(out["rowing_rad"] - res.rowing[-1]).max()),
            "lengths": float(np.abs(np.asarray(out["length_m"]) - res.lengths[-1]).max()),
            "force": float(np.abs(np.asarray(out["foot_force_n"])[st] - res.foot_force[-1][st]).max())}


def compare(sc: Scene, ref: HexapodModel, h: float, res=None, *, engine: str = "mujoco",
            repeats: int = 1, method: str = "rk4", hexapod=None, **xml_kw) -> dict:
    """One engine on one scene at one step: its errors against the reference at t_end and its
    cost per step (the smallest over ``repeats`` runs)."""
    res = reference(sc, ref) if res is None else res
    best = None
    for _ in range(max(1, repeats)):
        if engine == "mujoco":
            out = MujocoHexapod(sc, ref, h, method, **xml_kw).simulate()
        elif engine == "legsim":
            out = legsim_run(sc, h, hexapod)
        else:
            raise ValueError(f"engine: mujoco or legsim, not {engine!r}")
        if best is None or out["per_step_s"] < best["per_step_s"]:
            best = out
    best["err"] = errors(best, res, sc.stance)
    return best


# ------------------------------------------------------------------ instructions
def _run_once(engine: str, name: str, h: float) -> None:
    """One run of a scene (the process callgrind counts)."""
    ref = HexapodModel.from_toml(default_path())
    sc = setup(name, ref)
    if engine == "mujoco":
        MujocoHexapod(sc, ref, h).simulate()
    else:
        legsim_run(sc, h)


def instructions_per_step(engine: str, name: str, h: float) -> float:
    """Instructions per step (valgrind callgrind, collecting only inside mj_step, which
    mujoco.rollout calls once a step, or inside legsim's robot_step, which
    legsim_hexapod_step calls once a step): one run of the scene, set-up and Python outside
    the count."""
    from .peer_tables import callgrind_total

    return callgrind_total(engine, __name__, [engine, name, repr(h)]) / int(round(T_END / h))


if __name__ == "__main__":
    import sys

    _run_once(sys.argv[1], sys.argv[2], float(sys.argv[3]))
