"""The bench's hexapod reference (legsim_bench.reference.hexapod: minimal coordinates on the planar
LegModel) against the core (legsim.Hexapod.statics: absolute coordinates and multipliers) and
against its own invariants:

- statics: the feet, the centre of mass, the stance forces, the actuator forces and the rowing
  torques agree with the core's on six feet, each tripod, four feet on a tilted box with a box
  force (the legs at unequal rowing angles) to 1e-12 of the scale; a level tripod's vertical
  forces are the barycentric closed form, its horizontal ones zero; a push's rowing torques
  -((p_foot - p_hip) x f)_z; two feet and a tipping push refused by both;
- dynamics: at the statics' forces the robot stays at rest (six feet, a tripod with three legs
  free) and the stuck feet's ground forces are the statics'; in free flight every point falls at
  g, and with forces and spin the centre of mass falls at g and the angular momentum about it
  holds; scenes (a) six feet stuck with +50 N on the right legs' upper actuators, (b) a tripod
  stuck and three legs free: the energy is conserved, Newton's law of the whole robot holds with
  the stuck feet's ground forces, and the trajectory agrees between rtol 1e-12 and 1e-10; at a
  moving state the minimal coordinates' accelerations and ground forces are those of every leg
  free with its foot held by multipliers; the stuck legs' inverse kinematics round-trips;
- the core's forward dynamics (legsim.HexapodSim) on scenes (a) and (b) converges to this
  reference at order 4 (at h = 1 ms within 1e-9 m and rad, ground forces within 1e-6 relative).
"""
from __future__ import annotations

import numpy as np
import pytest

from legsim_bench.reference.hexapod import LEGS, HexapodModel
from legsim_bench.reference.model import NoEquilibriumError

legsim = pytest.importorskip("legsim")

ROW = (0.3, 0.1, -0.2, 0.0, 0.25, -0.15)
T_EVAL = np.linspace(0.0, 0.2, 9)


@pytest.fixture(scope="module")
def ref():
    return HexapodModel.from_toml(legsim.data_path("models/hexapod.toml"))


@pytest.fixture(scope="module")
def core():
    if not legsim.library_available("double"):
        pytest.skip("liblegsim.so is not built (cmake --build build/host --target legsim)")
    return legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))


def tilted(pose):
    q = np.array([1.0, 0.05, -0.03, 0.1])
    return dict(pose, box_quat=list(q / np.linalg.norm(q)), box_m=[0.02, -0.01, 1.0])


CASES = [("six", range(6), None, False), ("tripod 0 2 4", (0, 2, 4), None, False),
         ("tripod 1 3 5 pushed", (1, 3, 5), [20.0, -10.0, 5.0], False),
         ("four, tilted, pushed", (0, 1, 3, 5), [15.0, 30.0, -40.0], True)]


@pytest.mark.parametrize("name,stance,push,tilt", CASES, ids=[c[0] for c in CASES])
def test_statics_against_core(ref, core, name, stance, push, tilt):
    pose = core.stand_pose(1.0, ROW)
    assert np.array_equal(np.array(pose["length_m"]), ref.stand_lengths())
    if tilt:
        pose = tilted(pose)
    c = core.statics(pose, stance=stance, box_force_n=push)
    r = ref.statics(pose, stance=stance, box_force_n=push)
    W = ref.mass * 9.81
    worst = {}
    for key, scale in (("com_m", 1.0), ("foot_m", 1.0), ("foot_force_n", W), ("actuator_force_n", W),
                       ("rowing_torque_nm", W)):
        worst[key] = np.abs(c[key] - r[key]).max() / scale
    print(name, " ".join(f"{k} {v:.1e}" for k, v in worst.items()), "(relative to 1 m, the weight", f"{W:.3f} N)")
    assert max(worst.values()) < 1e-12
    kin = ref.kinematics(pose)
    assert np.abs(kin["foot_m"] - c["foot_m"]).max() < 1e-14
    assert np.abs(kin["length_m"] - np.array(pose["length_m"])).max() < 1e-14
    # the whole robot balances the weight and the push
    push = np.zeros(3) if push is None else np.array(push)
    assert np.abs(r["foot_force_n"].sum(axis=0) + ref.mass * ref.gravity + push).max() < 1e-12 * W


def test_level_tripod_closed_form(ref):
    pose = ref.stand_pose(1.0, ROW)
    for tri in ((0, 2, 4), (1, 3, 5)):
        s = ref.statics(pose, stance=tri)
        f = s["foot_force_n"]
        a, b, c = (s["foot_m"][k][:2] for k in tri)
        x = s["com_m"][:2]
        # barycentric coordinates of the centre of mass in the triangle
        w = np.linalg.solve(np.column_stack([b - a, c - a]), x - a)
        W = ref.mass * 9.81
        expect = np.array([1 - w.sum(), w[0], w[1]]) * W
        print(tri, "vertical", f[list(tri), 2], "closed form", expect)
        assert np.abs(f[list(tri), 2] - expect).max() < 1e-12 * W
        assert np.abs(f[:, :2]).max() < 1e-12 * W
        assert np.all(np.delete(f, tri, axis=0) == 0)
        # each stance leg's rowing torque is -((p_foot - p_hip) x f)_z: zero for a vertical force
        assert np.abs(s["rowing_torque_nm"]).max() < 1e-12 * W


def test_refusals(ref, core):
    """Two feet; a push that tips the tripod (a foot would pull): both refuse."""
    pose = ref.stand_pose(1.0, ROW)
    for stance, push in (((0, 3), None), ((0, 2, 4), [2000.0, 0.0, 0.0])):
        with pytest.raises(NoEquilibriumError):
            ref.statics(pose, stance=stance, box_force_n=push)
        with pytest.raises(legsim.NoEquilibriumError):
            core.statics(pose, stance=stance, box_force_n=push)


def test_push_rowing_torque(ref):
    """A push on the box: each stance leg's rowing torque is -((p_foot - p_hip) x f)_z, the legs'
    own weights having no moment about a vertical axis."""
    pose = ref.stand_pose(1.0, ROW)
    s = ref.statics(pose, stance=range(6), box_force_n=[40.0, -25.0, 0.0])
    hips = np.array([leg.hip for leg in ref.legs]) + np.array(pose["box_m"])
    expect = -np.cross(s["foot_m"] - hips, s["foot_force_n"])[:, 2]
    print("rowing torques under the push", s["rowing_torque_nm"])
    assert np.abs(s["rowing_torque_nm"] - expect).max() < 1e-12
    assert np.abs(s["rowing_torque_nm"]).max() > 1.0


@pytest.mark.parametrize("stance,rowing", [(tuple(range(6)), (0.0,) * 6), ((0, 2, 4), ROW)])
def test_rest_at_statics(ref, stance, rowing):
    pose = ref.stand_pose(1.0, rowing)
    s = ref.statics(pose, stance=stance)
    y0, feet = ref.initial_state(pose, stance)
    o = ref.evaluate(y0, stance, feet, s["actuator_force_n"], s["rowing_torque_nm"], np.zeros(3))
    print(stance, "accelerations at the statics' forces", np.abs(o["ud"]).max(),
          "ground forces off the statics'", np.abs(o["f"] - s["foot_force_n"]).max())
    assert np.abs(o["ud"]).max() < 1e-12
    assert np.abs(o["f"] - s["foot_force_n"]).max() < 1e-11


def test_free_fall(ref):
    pose = ref.stand_pose(1.0, ROW)
    y0, feet = ref.initial_state(pose, ())
    o = ref.evaluate(y0, (), feet, np.zeros((LEGS, 2)), np.zeros(LEGS))
    expect = np.zeros(6 + 3 * LEGS)
    expect[2] = -9.81
    assert np.abs(o["ud"] - expect).max() < 1e-13
    res = ref.simulate(pose, (), np.zeros((LEGS, 2)), np.zeros(LEGS), 0.1, [0.0, 0.05, 0.1])
    drop = res.feet - res.feet[0]
    fall = -0.5 * 9.81 * res.t ** 2
    print(f"free fall: feet off 1/2 g t^2 by {np.abs(drop[:, :, 2] - fall[:, None]).max():.1e} m")
    assert np.abs(drop[:, :, 2] - fall[:, None]).max() < 1e-12
    assert np.abs(drop[:, :, :2]).max() < 1e-12
    assert np.abs(res.box_q[:, 2] - 1.0 - fall).max() < 1e-12
    assert np.abs(res.rowing - ROW).max() < 1e-12 and np.abs(res.lengths - res.lengths[0]).max() < 1e-12


def test_free_flight_momentum(ref):
    """No stance, actuator forces and rowing torques (internal), the box spinning and the legs
    moving: the centre of mass falls at g, the angular momentum about it holds, energy holds."""
    pose = tilted(ref.stand_pose(1.0, ROW))
    rng = np.random.default_rng(7)
    Fa = rng.uniform(-60.0, 60.0, (LEGS, 2)) + ref.statics(ref.stand_pose(1.0, ROW))["actuator_force_n"]
    tau = rng.uniform(-2.0, 2.0, LEGS)
    rates = rng.uniform(-0.5, 0.5, (LEGS, 3))
    res = ref.simulate(pose, (), Fa, tau, 0.05, np.linspace(0, 0.05, 6), box_v0=[0.1, -0.2, 0.3, 0.4, -0.3, 0.5],
                       rates0=rates)
    dH = np.abs(res.angular_momentum - res.angular_momentum[0]).max()
    dE = np.ptp(res.energy)
    print(f"free flight: com accel off g {np.abs(res.com_accel - ref.gravity).max():.1e} m/s^2, "
          f"angular momentum {dH:.1e} of {np.abs(res.angular_momentum[0]).max():.3f} kg m^2/s, energy {dE:.1e} J")
    assert np.abs(res.com_accel - ref.gravity).max() < 1e-12
    assert dH < 1e-10
    assert dE < 1e-9
    assert np.abs(res.rowing[-1] - res.rowing[0]).max() > 1e-3  # the legs did move


def scene_a(ref, **kw):
    """Six feet stuck at the stand, the statics' forces and +50 N on the right legs' uppers."""
    pose = ref.stand_pose(1.0)
    s = ref.statics(pose)
    Fa = s["actuator_force_n"].copy()
    Fa[0:3, 0] += 50.0
    return ref.simulate(pose, range(6), Fa, s["rowing_torque_nm"], 0.2, T_EVAL, **kw)


def lifted(pose, legs=(1, 3, 5), by=0.03):
    """pose with the upper actuators of `legs` shorter by `by` m: their feet 8.6 cm off the ground."""
    lengths = [list(x) for x in pose["length_m"]]
    for k in legs:
        lengths[k][0] -= by
    return dict(pose, length_m=lengths)


def scene_b(ref, **kw):
    """A tripod stuck, the rowing angles unequal, the other three legs free with their feet lifted
    off the ground; the tripod statics' forces and +50 N on the stuck right legs' uppers."""
    pose = lifted(ref.stand_pose(1.0, ROW))
    s = ref.statics(pose, stance=(0, 2, 4))
    Fa = s["actuator_force_n"].copy()
    Fa[[0, 2], 0] += 50.0
    return ref.simulate(pose, (0, 2, 4), Fa, s["rowing_torque_nm"], 0.2, T_EVAL, **kw)


@pytest.mark.parametrize("scene", [scene_a, scene_b], ids=["a_six", "b_tripod"])
def test_scene(ref, scene):
    res = scene(ref)
    loose = scene(ref, rtol=1e-10, atol=1e-10)
    dE = np.ptp(res.energy)
    dr = np.abs(res.box_q[:, :3] - loose.box_q[:, :3]).max()
    dq = np.abs(res.box_q[:, 3:] - loose.box_q[:, 3:]).max()
    dpsi = np.abs(res.rowing - loose.rowing).max()
    dl = np.abs(res.lengths - loose.lengths).max()
    stuck = list(res.stance)
    # Newton's law of the whole robot: M a_com = M g + the stuck feet's ground forces
    newton = np.abs(ref.mass * (res.com_accel - ref.gravity) - res.foot_force.sum(axis=1)).max()
    print(f"{scene.__name__}: {res.nfev} evaluations; energy drift {dE:.1e} J "
          f"(kinetic at the end {res.kinetic[-1]:.4f} J); rtol 1e-12 vs 1e-10: box {dr:.1e} m, quaternion "
          f"{dq:.1e}, rowing {dpsi:.1e} rad, lengths {dl:.1e} m; Newton {newton:.1e} N")
    print("  end: box", res.box_q[-1], "rowing", res.rowing[-1])
    print("  lengths", res.lengths[-1].ravel())
    print("  ground forces", res.foot_force[-1][stuck].ravel())
    assert dE < 1e-9
    assert max(dr, dl) < 1e-8 and max(dq, dpsi) < 1e-8
    assert newton < 1e-9
    assert np.abs(res.feet[:, stuck] - res.feet[0, stuck]).max() < 1e-13
    assert np.all(res.foot_force[:, stuck, 2] > 0)
    assert np.all(res.foot_force[:, [k for k in range(LEGS) if k not in stuck]] == 0)
    assert np.abs(np.linalg.norm(res.box_q[:, 3:], axis=1) - 1).max() < 1e-12
    assert res.kinetic[-1] > 0.1  # it moved


def test_two_formulations(ref):
    """At a moving state of a tripod stand (the box turning, the free legs moving, forces off
    the statics'), the minimal coordinates' accelerations and ground forces against every leg
    free with its stuck foot held by multipliers (the KKT system of the same bodies)."""
    pose = tilted(ref.stand_pose(1.0, ROW))
    stance = (0, 2, 4)
    s = ref.statics(pose, stance=stance)
    rng = np.random.default_rng(3)
    Fa = s["actuator_force_n"] + rng.uniform(-50.0, 50.0, (LEGS, 2))
    tau = rng.uniform(-2.0, 2.0, LEGS)
    rates = rng.uniform(-0.5, 0.5, (LEGS, 3))
    y, feet = ref.initial_state(pose, stance, box_v=[0.05, -0.1, 0.08, 0.3, -0.2, 0.4], rates=rates)
    box_force = np.array([10.0, -5.0, 3.0])
    o = ref.evaluate(y, stance, feet, Fa, tau, box_force)
    ud, f = ref.multiplier_accelerations(y, stance, feet, Fa, tau, box_force)
    d_box = np.abs(ud[:6] - o["ud"][:6]).max()
    d_legs = np.abs(ud[6:].reshape(LEGS, 3) - o["qdd"]).max()
    d_f = np.abs(f - o["f"]).max()
    print(f"minimal vs multipliers: box accelerations {d_box:.1e}, legs' {d_legs:.1e} (of "
          f"{np.abs(o['qdd']).max():.1f}), ground forces {d_f:.1e} N (of {np.abs(f).max():.1f})")
    assert d_box < 1e-11 and d_legs < 1e-10 and d_f < 1e-10
    assert np.abs(o["qdd"]).max() > 1.0


def test_leg_foot_inverse_kinematics(ref):
    """LegModel.theta_from_foot (the stuck legs' planar inverse kinematics) gives back the pose
    of each length pair over a grid inside the strokes, on the stand's branch."""
    leg = ref.legs[0].model
    worst, n = 0.0, 0
    for l0 in np.linspace(0.45, 0.74, 7):
        for l1 in np.linspace(0.40, 0.68, 7):
            th = leg.theta_from_lengths([l0, l1])
            worst = max(worst, np.abs(leg.theta_from_foot(leg.foot(th)) - th).max())
            n += 1
    print(f"theta_from_foot over {n} poses: {worst:.1e} rad")
    assert worst < 1e-12


def core_scene(core, scene, h_s, integrator="rk4"):
    """The core's forward dynamics (legsim.HexapodSim, RK4 or generalized-alpha on the rotation
    group) on scene_a's or scene_b's set-up to 0.2 s at step h_s: its state at the end."""
    if scene is scene_a:
        pose, stance, push = core.stand_pose(1.0), tuple(range(6)), (0, 1, 2)
    else:
        pose, stance, push = lifted(core.stand_pose(1.0, ROW)), (0, 2, 4), (0, 2)
    s = core.statics(pose, stance=stance)
    Fa = np.array(s["actuator_force_n"])
    Fa[list(push), 0] += 50.0
    m = core.sim(pose, stuck=stance, integrator=integrator)
    m.command(Fa, s["rowing_torque_nm"])
    m.step(int(round(0.2 / h_s)), h_s=h_s)
    return m.state()


@pytest.mark.parametrize("scene", [scene_a, scene_b], ids=["a_six", "b_tripod"])
def test_core_motion_against_reference(ref, core, scene):
    """The core's RK4 on the rotation group (absolute coordinates, multipliers, projections)
    against this reference (minimal coordinates, DOP853 at rtol 1e-12) at 0.2 s: the box's place
    and rotation, the rowing angles, the lengths and the stuck feet's ground forces converge at
    order 4 to it over h = 4, 2, 1 ms (the larger of the rotation's and the lengths' errors)."""
    res = scene(ref)
    errors = []
    for h in (4e-3, 2e-3, 1e-3):
        st = core_scene(core, scene, h)
        e = {"box": np.abs(st["box_m"] - res.box_q[-1, :3]).max(),
             "quat": np.abs(st["box_quat"] - res.box_q[-1, 3:]).max(),
             "rowing": np.abs(st["rowing_rad"] - res.rowing[-1]).max(),
             "lengths": np.abs(st["length_m"] - res.lengths[-1]).max(),
             "force": np.abs(st["foot_force_n"] - res.foot_force[-1]).max()}
        errors.append(e)
        print(f"{scene.__name__}, h = {h:.0e} s: " + ", ".join(f"{k} {v:.2e}" for k, v in e.items()))
    # the order on the largest positional errors (the box's place reaches the reference's own
    # accuracy, ~1e-12 m, at 1 ms)
    size = [max(e["quat"], e["lengths"]) for e in errors]
    orders = [np.log2(size[k] / size[k + 1]) for k in range(2)]
    print(f"  orders {orders}")
    assert errors[-1]["box"] < 1e-9 and errors[-1]["lengths"] < 1e-9
    assert errors[-1]["quat"] < 1e-9 and errors[-1]["rowing"] < 1e-9
    assert errors[-1]["force"] < 1e-6 * np.abs(res.foot_force[-1]).max()
    assert min(orders) > 3.5


@pytest.mark.parametrize("scene", [scene_a, scene_b], ids=["a_six", "b_tripod"])
def test_core_galpha_against_reference(ref, core, scene):
    """The core's generalized-alpha on the rotation group against this reference at 0.2 s: the
    box's place and rotation, the rowing angles and the lengths converge at order 2 over h = 4, 2,
    1 ms (each error's order, the larger of the rotation's and the lengths' asserted), the stuck
    feet's ground forces with them."""
    res = scene(ref)
    errors = []
    for h in (4e-3, 2e-3, 1e-3):
        st = core_scene(core, scene, h, integrator="galpha")
        e = {"box": np.abs(st["box_m"] - res.box_q[-1, :3]).max(),
             "quat": np.abs(st["box_quat"] - res.box_q[-1, 3:]).max(),
             "rowing": np.abs(st["rowing_rad"] - res.rowing[-1]).max(),
             "lengths": np.abs(st["length_m"] - res.lengths[-1]).max(),
             "force": np.abs(st["foot_force_n"] - res.foot_force[-1]).max()}
        errors.append(e)
        print(f"galpha {scene.__name__}, h = {h:.0e} s: " + ", ".join(f"{k} {v:.2e}" for k, v in e.items()))
    orders = {k: [np.log2(errors[j][k] / errors[j + 1][k]) for j in range(2)] for k in errors[0]}
    print("  orders " + ", ".join(f"{k} {v[0]:.2f} {v[1]:.2f}" for k, v in orders.items()))
    size = [max(e["quat"], e["lengths"]) for e in errors]
    size_orders = [np.log2(size[k] / size[k + 1]) for k in range(2)]
    assert all(1.8 < o < 2.3 for o in size_orders)
    assert all(1.8 < o < 2.3 for k in ("box", "force") for o in orders[k])
    # at 1 ms: 2.8e-8 m, 9.3e-7, 6.1e-7 m, 2.4e-4 N (a_six); 1.7e-8 m, 5.9e-7, 4.3e-7 m, 3.9e-4 N (b_tripod)
    assert errors[-1]["box"] < 5e-8 and errors[-1]["lengths"] < 1e-6 and errors[-1]["quat"] < 2e-6
    assert errors[-1]["force"] < 1e-3
