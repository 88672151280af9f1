"""The hexapod's inverse dynamics along the tripod gait through the Python API
(legsim.Hexapod.inverse_dynamics, legsim_hexapod_inverse_dynamics):

- a gait that does not move (no step, no rise, no turn) is statics: the forces equal
  Hexapod.statics' at the set-points' pose on the same stance, to round-off;
- a swinging foot's velocity and acceleration (five-point differences of its curve) against the
  curve's exact derivatives, written here from the gait's form (docs/design/spatial.md: a cubic
  Hermite curve in the box's frame from lift-off to touchdown, rising by a cosine), carried by the
  box's twist;
- the box's Newton-Euler balance from the reported hip reactions and rowing torques, with the
  plan's accelerations (Hexapod.gait_state);
- the cone ratios are |F_t| / N of the reported ground forces, zero off the stance, and the
  straight walk of scenes/hexapod_walk.toml needs less friction than the file's ground has.
"""
from __future__ import annotations

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

HEXAPOD = legsim.data_path("models/hexapod.toml")
GAIT = dict(period_s=1.2, duty=0.6, step_length_m=0.12, step_height_m=0.05, turn_rad=0.1, box_height_m=1.0)


@pytest.fixture(scope="module")
def hexapod():
    return legsim.Hexapod.from_toml(HEXAPOD)


def test_a_gait_at_rest_is_statics(hexapod):
    still = dict(GAIT, step_length_m=0.0, step_height_m=0.0, turn_rad=0.0)
    # on six feet (t = 0.05) nothing is differenced: statics to round-off; on a tripod the swinging
    # feet's five-point second differences of a curve that stands still leave about eps |p| / h^2
    # (h = 3e-4 periods)
    for t, tol in ((0.05, 1e-13), (0.3, 1e-10), (0.9, 1e-10)):
        r = hexapod.inverse_dynamics(t, **still)
        sp = hexapod.gait_setpoints(t, **still)
        pose = {"box_m": [0.0, 0.0, 1.0], "box_quat": [1.0, 0.0, 0.0, 0.0], "rowing_rad": list(sp["rowing_rad"]),
                "length_m": sp["length_m"].tolist()}
        s = hexapod.statics(pose, stance=[k for k in range(6) if sp["stance"][k]])
        weight = np.abs(s["foot_force_n"]).sum()
        err = max(np.abs(r["foot_force_n"][0] - s["foot_force_n"]).max(),
                  np.abs(r["actuator_force_n"][0] - s["actuator_force_n"]).max(),
                  np.abs(r["rowing_torque_nm"][0] - s["rowing_torque_nm"]).max())
        print(f"t = {t}: inverse dynamics at rest against statics {err:.1e} (N, N m; weight {weight:.0f} N)")
        assert err < tol * weight


def _stance_point(p_mid, v, w, sigma):
    """A world-fixed point seen from the box sigma after the stance's middle, and its velocity
    (box frame)."""
    th = w * sigma
    c, s = np.cos(th), np.sin(th)
    dx, dy = (v * sigma, v * sigma * th / 2) if abs(th) < 1e-8 else (v / w * s, v / w * (1 - c))
    x, y = p_mid[0] - dx, p_mid[1] - dy
    p = np.array([c * x + s * y, -s * x + c * y, p_mid[2]])
    return p, np.array([-v + w * p[1], -w * p[0], 0.0])


def _hermite(p0, d0, p1, d1, s):
    """The cubic Hermite curve's value, first and second derivatives in s."""
    h = [2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2]
    h1 = [6 * s**2 - 6 * s, 3 * s**2 - 4 * s + 1, -6 * s**2 + 6 * s, 3 * s**2 - 2 * s]
    h2 = [12 * s - 6, 6 * s - 4, -12 * s + 6, 6 * s - 2]
    return [k[0] * p0 + k[1] * d0 + k[2] * p1 + k[3] * d1 for k in (h, h1, h2)]


def test_swinging_feet_against_the_exact_curve(hexapod):
    T, duty, H = GAIT["period_s"], GAIT["duty"], GAIT["step_height_m"]
    Ts, Tw = duty * T, (1 - duty) * T
    v, w = GAIT["step_length_m"] / Ts, GAIT["turn_rad"] / Ts
    # each foot's neutral point: its target at its stance's middle
    neutral = [hexapod.gait_setpoints((l % 2) * T / 2 + Ts / 2, **GAIT)["foot_box_m"][l] for l in range(6)]
    ts = np.concatenate([np.linspace(0.0, T, 25), [0.72, 0.7201, 1.1999, 0.12, 0.1201]])
    r = hexapod.inverse_dynamics(ts, **GAIT)
    err_v = err_a = 0.0
    n = 0
    for i, t in enumerate(ts):
        th = w * t
        Rz = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
        wz = np.array([0, 0, w])
        vb, ab = v * np.array([np.cos(th), np.sin(th), 0]), v * w * np.array([-np.sin(th), np.cos(th), 0])
        for l in range(6):
            tau = (t - (l % 2) * T / 2) % T
            if r["stance"][i][l]:
                assert tau < Ts
                assert not r["foot_velocity_mps"][i][l].any() and not r["foot_acceleration_mps2"][i][l].any()
                continue
            s = (tau - Ts) / Tw
            p0, d0 = _stance_point(neutral[l], v, w, Ts / 2)
            p1, d1 = _stance_point(neutral[l], v, w, -Ts / 2)
            x = [_hermite(p0[k], Tw * d0[k], p1[k], Tw * d1[k], s) for k in range(2)]
            pb = np.array([x[0][0], x[1][0], neutral[l][2] + H * (1 - np.cos(2 * np.pi * s)) / 2])
            pb1 = np.array([x[0][1] / Tw, x[1][1] / Tw, H * np.pi * np.sin(2 * np.pi * s) / Tw])
            pb2 = np.array([x[0][2] / Tw**2, x[1][2] / Tw**2, 2 * np.pi**2 * H * np.cos(2 * np.pi * s) / Tw**2])
            assert np.abs(pb - np.asarray(hexapod.gait_setpoints(t, **GAIT)["foot_box_m"][l])).max() < 1e-14
            p, p1_, p2_ = Rz @ pb, Rz @ pb1, Rz @ pb2
            vel = vb + np.cross(wz, p) + p1_
            acc = ab + np.cross(wz, np.cross(wz, p)) + 2 * np.cross(wz, p1_) + p2_
            err_v = max(err_v, np.abs(r["foot_velocity_mps"][i][l] - vel).max())
            err_a = max(err_a, np.abs(r["foot_acceleration_mps2"][i][l] - acc).max())
            n += 1
    print(f"{n} swinging feet: five-point differences against the exact curve: velocity {err_v:.1e} m/s, "
          f"acceleration {err_a:.1e} m/s^2")
    assert n > 40
    assert err_v < 1e-10 and err_a < 1e-7


def _rot(qt):
    w, x, y, z = qt
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_box_newton_euler_and_cone_ratios(hexapod):
    d = hexapod.desc
    m0, I0 = d.box_mass_kg, np.array(d.box_inertia_kgm2[:])
    g = np.array(d.gravity_mps2[:])
    ts = np.linspace(0.0, GAIT["period_s"], 13)
    r = hexapod.inverse_dynamics(ts, **GAIT)
    worst_f = worst_m = 0.0
    for i, t in enumerate(ts):
        st = hexapod.gait_state(t, **GAIT)
        rb, R = st["q"][0][:3], _rot(st["q"][0][3:])
        w, al = st["v"][0][3:], st["a"][0][3:]
        F, M = m0 * g, np.zeros(3)
        for l in range(6):
            hip = rb + R @ np.array(d.leg[l].hip_m[:])
            f, m = -r["joint_force_n"][i][l][0], -r["joint_moment_nm"][i][l][0]  # on the box
            F = F + f
            M = M + m + np.cross(hip - rb, f) - r["rowing_torque_nm"][i][l] * R[:, 2]
        worst_f = max(worst_f, np.abs(m0 * st["a"][0][:3] - F).max())
        worst_m = max(worst_m, np.abs(R @ (I0 * al + np.cross(w, I0 * w)) - M).max())
    print(f"the box's Newton-Euler: force {worst_f:.1e} N, moment {worst_m:.1e} N m")
    assert worst_f < 1e-9 and worst_m < 1e-9
    # the cone ratios: the ground's normal is the file's (z on level ground)
    n = np.array(d.ground_normal[:])
    F = r["foot_force_n"]
    N = F @ n
    Ft = np.linalg.norm(F - N[..., None] * n, axis=-1)
    on = r["stance"]
    assert (N[on] > 0).all()
    assert np.allclose(r["cone_ratio"][on], Ft[on] / N[on], rtol=1e-12, atol=1e-15)
    assert not r["cone_ratio"][~on].any() and not F[~on].any()
    print(f"largest cone ratio {r['cone_ratio'].max():.4f} (the ground's mu_static {d.mu_static})")
    assert 0 < r["cone_ratio"].max() < d.mu_static
    assert r["n_joints"].tolist() == [9] * 6


def test_up_a_slope_the_plan_climbs_and_the_robot_balances(hexapod):
    """Walking up a 10 degree slope (the gait's box level, its height over the ground below it):
    the plan's box climbs at the grade (its velocity the difference of its positions), and the
    ground forces with the weight give every body's momentum rate (the whole robot's Newton's law)."""
    slope = np.radians(10.0)
    up = hexapod.on_ground(slope_rad=slope)
    gait = dict(GAIT, turn_rad=0.0)
    masses = up.body_masses()
    g = np.array(up.desc.gravity_mps2[:])
    ts = np.linspace(0.05, 1.15, 12)
    r = up.inverse_dynamics(ts, **gait)
    worst, worst_v = 0.0, 0.0
    dt = 1e-6
    for i, t in enumerate(ts):
        st = up.gait_state(t, **gait)
        before, after = up.gait_state(t - dt, **gait), up.gait_state(t + dt, **gait)
        v_box = (after["q"][0][:3] - before["q"][0][:3]) / (2 * dt)
        worst_v = max(worst_v, np.abs(v_box - st["v"][0][:3]).max())
        assert abs(st["v"][0][2] - np.tan(slope) * st["v"][0][0]) < 1e-12  # climbing at the grade
        rate = (masses[:, None] * st["a"][:, :3]).sum(axis=0)
        F = r["foot_force_n"][i].sum(axis=0) + masses.sum() * g
        worst = max(worst, np.abs(rate - F).max())
    print(f"up 10 deg: the box's planned velocity against its positions' difference {worst_v:.1e} m/s; "
          f"Newton's law of the whole robot {worst:.1e} N")
    assert worst_v < 1e-6
    assert worst < 1e-8 * masses.sum() * np.linalg.norm(g)


def test_a_plan_that_needs_the_ground_to_pull_is_refused(hexapod):
    """Up 10 degrees with the box 0.8 m up and a fast gait (0.6 s), just after a touchdown a stance
    foot's force would point into the slope (its normal force negative: the ground pulling) though
    still up against gravity: refused (NoEquilibriumError), never reported with a negative cone
    ratio; every time that is answered has every stance foot pushing along the ground's normal."""
    up = hexapod.on_ground(slope_rad=np.radians(10.0))
    fast = dict(period_s=0.6, duty=0.6, step_length_m=0.1, step_height_m=0.05, box_height_m=0.8)
    n = np.array(up.desc.ground_normal[:])
    refused = 0
    for t in np.linspace(0.0, 0.6, 31):
        try:
            r = up.inverse_dynamics([t], **fast)
        except legsim.NoEquilibriumError:
            refused += 1
            continue
        on = r["stance"][0]
        assert (r["foot_force_n"][0][on] @ n > 0).all() and (r["cone_ratio"][0] >= 0).all()
    assert refused >= 1
