"""The hexapod through the Python API (legsim.Hexapod: legsim_hexapod_load_toml and
legsim_hexapod_statics), against closed forms and the planar core:

- models/hexapod.toml: six legs of leg.toml, named, each the planar leg bit for bit;
- standing at its stand on a tripod (the box level, the legs at unequal rowing angles): the
  feet's vertical forces are the barycentric closed form of the centre of mass in their triangle
  (to 1e-9 of the weight), their horizontal ones zero, and each leg's actuator forces the planar
  core's statics under its foot's force (Sim.statics with the leg's foot load);
- on six feet the weight is carried; a stance that cannot hold, a pose out of range: refused;
- moving (legsim.HexapodSim): at its statics it stays at rest with the statics' foot forces; pushed,
  the box rises and the stuck feet hold; bad commands and steps refused, the state unchanged.
"""
from __future__ import annotations

import ctypes as C

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

HEXAPOD = legsim.data_path("models/hexapod.toml")
ROWING = (0.3, 0.1, -0.2, 0.0, 0.25, -0.15)


@pytest.fixture(scope="module")
def hexapod():
    return legsim.Hexapod.from_toml(HEXAPOD)


def planar_forces(h, k, fz):
    s = legsim.Sim(h.leg_model(k))
    s.assemble_pose(0)
    s.set_force("foot_load", [0.0, fz])
    return s.statics()


def test_file(hexapod):
    assert hexapod.leg_names == ["right_front", "right_middle", "right_rear", "left_front", "left_middle",
                                 "left_rear"]
    leg = legsim.Model.from_toml(legsim.data_path("models/leg.toml"))
    assert bytes(hexapod.leg_model(0).desc) == bytes(leg.desc)


def test_tripod(hexapod):
    pose = hexapod.stand_pose(1.0, ROWING)
    s = hexapod.statics(pose, stance=(0, 2, 4))
    f = s["foot_force_n"]
    W = f[:, 2].sum()  # the weight, checked against the masses below
    a, b, c = (s["foot_m"][k] for k in (0, 2, 4))
    com = s["com_m"]
    det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
    wb = ((com[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (com[1] - a[1])) / det
    wc = ((b[0] - a[0]) * (com[1] - a[1]) - (com[0] - a[0]) * (b[1] - a[1])) / det
    expect = np.array([1 - wb - wc, wb, wc]) * W
    print("tripod: vertical forces", f[[0, 2, 4], 2], "closed form", expect, "margin", s["margin_m"])
    assert np.allclose(f[[0, 2, 4], 2], expect, rtol=0, atol=1e-9 * W)
    assert np.abs(f[:, :2]).max() < 1e-9 * W
    assert np.all(f[[1, 3, 5]] == 0)
    assert s["margin_m"] > 0
    # the weight: the masses of the box, the yokes and the legs
    d = hexapod.desc
    m = d.box_mass_kg + 6 * d.yoke_mass_kg + 6 * sum(d.leg[0].leg.body[b].mass_kg for b in range(6))
    assert abs(W - 9.81 * m) < 1e-9 * W
    for k in range(6):
        planar = planar_forces(hexapod, k, f[k, 2])
        assert np.allclose(s["actuator_force_n"][k], planar, rtol=1e-9, atol=1e-9)
    assert np.abs(s["rowing_torque_nm"]).max() < 1e-9 * W


def test_six_feet_and_refusals(hexapod):
    pose = hexapod.stand_pose(1.0, ROWING)
    s = hexapod.statics(pose)
    W = 9.81 * (hexapod.desc.box_mass_kg + 6 * hexapod.desc.yoke_mass_kg
                + 6 * sum(hexapod.desc.leg[0].leg.body[b].mass_kg for b in range(6)))
    assert abs(s["foot_force_n"][:, 2].sum() - W) < 1e-9 * W
    with pytest.raises(legsim.NoEquilibriumError):
        hexapod.statics(pose, stance=(0, 3))
    bad = dict(pose, box_quat=[1.0, 0.1, 0.0, 0.0])
    with pytest.raises(legsim.BadInputError):
        hexapod.statics(bad)
    bad = dict(pose, rowing_rad=[1.0] + list(ROWING[1:]))  # past the 0.6 rad stroke
    with pytest.raises(legsim.BadInputError):
        hexapod.statics(bad)
    bad = dict(pose, length_m=[[0.2, 0.62]] + pose["length_m"][1:])  # below the upper stroke
    with pytest.raises(legsim.OutOfStrokeError):
        hexapod.statics(bad)


GAIT = dict(period_s=1.2, duty=0.6, step_length_m=0.12, step_height_m=0.05, box_height_m=1.0)


def test_gait_setpoints_walk(hexapod):
    """The tripod gait's set-points, put back through the robot's kinematics (statics' feet:
    another path, the legs assembled at the set lengths and turned by the set rowing angles)
    with the box carried along at the gait's speed: every standing foot holds its place on the
    ground in the world, a swinging foot is off it by the planned rise, the stance balances
    the weight with a positive margin at every time."""
    T, duty = GAIT["period_s"], GAIT["duty"]
    v = GAIT["step_length_m"] / (duty * T)
    held = {}
    worst_hold = worst_ground = worst_rise = 0.0
    margins = []
    for k in range(49):                      # two periods
        t = k * T / 24
        sp = hexapod.gait_setpoints(t, **GAIT)
        pose = {"box_m": [v * t, 0.0, GAIT["box_height_m"]], "box_quat": [1.0, 0.0, 0.0, 0.0],
                "rowing_rad": list(sp["rowing_rad"]), "length_m": [list(x) for x in sp["length_m"]]}
        stance = [l for l in range(6) if sp["stance"][l]]
        assert len(stance) >= 3
        s = hexapod.statics(pose, stance=stance)
        margins.append(s["margin_m"])
        for l in range(6):
            foot = s["foot_m"][l]
            if sp["stance"][l]:
                worst_ground = max(worst_ground, abs(foot[2]))
                if l in held and held[l][0] == k - 1:  # the same stance as the last sample
                    worst_hold = max(worst_hold, float(np.hypot(*(foot[:2] - held[l][1]))))
                held[l] = (k, foot[:2].copy())
            else:
                held.pop(l, None)
                rise = sp["foot_box_m"][l][2] + GAIT["box_height_m"]
                worst_rise = max(worst_rise, abs(foot[2] - rise))
        assert np.all(s["foot_force_n"][stance, 2] > 0)
    print(f"stance feet held to {worst_hold:.2e} m, on the ground to {worst_ground:.2e} m; swing feet "
          f"at their rise to {worst_rise:.2e} m; margin {min(margins):.4f} .. {max(margins):.4f} m")
    assert worst_hold < 1e-9 and worst_ground < 1e-9 and worst_rise < 1e-9
    assert min(margins) > 0.05


def test_gait_out_of_reach(hexapod):
    with pytest.raises(legsim.LegsimError):
        hexapod.gait_setpoints(0.0, **dict(GAIT, step_length_m=2.0))  # far past the rowing stroke
    with pytest.raises(legsim.BadInputError):
        hexapod.gait_setpoints(0.0, **dict(GAIT, duty=0.3))


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_sim_stands_on_its_statics(hexapod, integrator):
    """Moving (legsim.HexapodSim, either integrator): on a tripod's statics the robot stays at
    rest, the stuck feet's ground forces the statics' (another solve: the whole robot's balance,
    then each leg's), its lengths and rowing angles the pose's; with 20 N more on every upper
    actuator the box rises while the stuck feet keep their places, and the swinging legs' lengths
    change."""
    pose = hexapod.stand_pose(1.0, ROWING)
    tripod = (0, 2, 4)
    s = hexapod.statics(pose, stance=tripod)
    m = hexapod.sim(pose, stuck=tripod, integrator=integrator)
    m.command(s["actuator_force_n"], s["rowing_torque_nm"])
    m.step(200, h_s=1e-3)
    st = m.state()
    W = np.linalg.norm(s["foot_force_n"][:, 2].sum())
    assert st["t_s"] == pytest.approx(0.2, abs=1e-12)
    assert np.abs(st["box_m"] - pose["box_m"]).max() < 1e-12
    assert np.abs(st["foot_force_n"] - s["foot_force_n"]).max() < 1e-10 * W
    assert np.abs(st["length_m"] - np.array(pose["length_m"])).max() < 1e-12
    assert np.abs(st["rowing_rad"] - np.array(ROWING)).max() < 1e-12
    assert st["foot_state"] == ["stuck", "free"] * 3
    assert st["kinetic_energy_j"] < 1e-20

    m = hexapod.sim(pose, stuck=tripod, integrator=integrator)
    forces = np.array(s["actuator_force_n"])
    forces[:, 0] += 20.0
    m.command(forces, s["rowing_torque_nm"])
    feet0 = m.state()["foot_m"]
    m.step(100, h_s=1e-3)
    st = m.state()
    assert st["box_m"][2] - pose["box_m"][2] > 1e-3
    assert np.abs(st["foot_m"][list(tripod)] - feet0[list(tripod)]).max() < 1e-12
    assert np.abs(st["length_m"][[1, 3, 5]] - np.array(pose["length_m"])[[1, 3, 5]]).max() > 1e-3
    assert st["kinetic_energy_j"] > 0


def test_sim_refuses(hexapod):
    pose = hexapod.stand_pose(1.0, ROWING)
    m = hexapod.sim(pose, stuck=range(6))
    before = m.state()
    with pytest.raises(legsim.BadInputError):
        m.command([[float("nan"), 0.0]] + [[0.0, 0.0]] * 5, [0.0] * 6)
    with pytest.raises(legsim.BadInputError):
        m.step(1, h_s=0.0)
    with pytest.raises(ValueError):
        hexapod.sim(pose, stuck=(6,))
    with pytest.raises(ValueError):  # five legs' forces: not filled with zeros
        m.command([[0.0, 0.0]] * 5, [0.0] * 6)
    with pytest.raises(ValueError):
        m.set_integrator("euler")
    with pytest.raises(legsim.BadInputError):  # the C call's own check
        m.library.check(m.library.cdll.legsim_hexapod_set_integrator(m._sim, 2), "legsim_hexapod_set_integrator")
    after = m.state()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in before)


def test_command_each_mixes_force_and_servo(hexapod):
    """legsim_hexapod_command_each: the right legs by force, the left ones by servo, leg 5's rowing
    kept: at rest each force slot is its value, each servo slot ff + kp (set-point - position) at
    the file's gains, the kept slot its earlier command; its rates are the finite difference of
    its lengths and angles over a small step; a bad slot changes nothing."""
    pose = hexapod.stand_pose(1.0, ROWING)
    m = hexapod.sim(pose, stuck=range(6))
    m.command(np.full((6, 2), 10.0), np.full(6, 0.5))
    st0 = m.state()
    d = hexapod.desc
    mode = [["force"] * 3] * 3 + [["servo"] * 3] * 2 + [["servo", "servo", "keep"]]
    value = np.array([[100.0, -50.0, 1.5]] * 3 + [[L[0] + 0.01, L[1] - 0.02, r + 0.005]
                                                  for L, r in zip(st0["length_m"][3:], st0["rowing_rad"][3:])])
    ff = np.array([[0.0, 0.0, 0.0]] * 3 + [[30.0, -20.0, 2.0]] * 3)
    m.command_each(mode, value, ff)
    st = m.state()
    for k in range(6):
        for j in range(3):
            got = st["actuator_force_n"][k][j] if j < 2 else st["rowing_torque_nm"][k]
            if mode[k][j] == "force":
                want = value[k][j]
            elif mode[k][j] == "keep":
                want = 0.5
            elif j < 2:
                want = ff[k][j] + d.leg[k].leg.actuator[j].servo_kp_n_per_m * (value[k][j] - st0["length_m"][k][j])
            else:
                want = ff[k][j] + d.rowing_servo_kp_nm_per_rad * (value[k][j] - st0["rowing_rad"][k])
            assert got == pytest.approx(want, rel=1e-12, abs=1e-9), (k, j)
    # the rates: the state's against its positions' difference over 1e-5 s (their curvature's error)
    m2 = hexapod.sim(pose, stuck=(0, 2, 4))
    m2.command_each(mode, value, ff)
    m2.step(20, h_s=1e-3)
    a = m2.state()
    m2.step(1, h_s=1e-5)
    b = m2.state()
    assert np.abs(a["length_rate_mps"]).max() > 1e-3
    assert np.abs((b["length_m"] - a["length_m"]) / 1e-5 - (a["length_rate_mps"] + b["length_rate_mps"]) / 2).max() < 1e-6
    assert np.abs((b["rowing_rad"] - a["rowing_rad"]) / 1e-5 - (a["rowing_rate_radps"] + b["rowing_rate_radps"]) / 2).max() < 1e-6
    # all or nothing
    before = m.state()
    bad_mode = [row[:] for row in mode]
    bad_mode[0][0] = "push"
    with pytest.raises(ValueError):
        m.command_each(bad_mode, value, ff)
    far = value.copy()
    far[4][1] = 5.0  # past the lower actuator's stroke
    with pytest.raises(legsim.OutOfStrokeError):
        m.command_each(mode, far, ff)
    big = value.copy()
    big[0][0] = 1e9  # past the actuator's max_force
    with pytest.raises(legsim.BadInputError):
        m.command_each(mode, big, ff)
    with pytest.raises(legsim.BadInputError):  # the C call's own check of a mode
        c = m.library.HexapodCommands()
        c.mode[2][1] = 7
        m.library.check(m.library.cdll.legsim_hexapod_command_each(m._sim, C.byref(c)), "legsim_hexapod_command_each")
    after = m.state()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in before)


@pytest.mark.parametrize("field,value", [("ground_normal", (0.0, 0.0, 0.0)), ("ground_normal", (0.0, 0.0, 2.0)),
                                         ("mu_kinetic", -0.1), ("mu_static", 0.1),  # below mu_kinetic 0.5
                                         ("box_mass_kg", float("nan")), ("yoke_mass_kg", 0.0),
                                         ("rowing_servo_kd_nms_per_rad", -1.0), ("ground_point_m", (0.0, 0.0, float("inf")))])
def test_a_description_out_of_range_is_refused(field, value):
    """A description changed past its documented ranges (legsim/hexapod.h) is refused by every
    call that takes it, not only by the loader."""
    h = legsim.Hexapod.from_toml(HEXAPOD)
    pose = h.stand_pose(1.0, ROWING)
    if isinstance(value, tuple):
        arr = getattr(h.desc, field)
        for i, x in enumerate(value):
            arr[i] = x
    else:
        setattr(h.desc, field, value)
    with pytest.raises(legsim.BadInputError):
        h.sim(pose, stuck=range(6))
    with pytest.raises(legsim.BadInputError):
        h.statics(pose)
