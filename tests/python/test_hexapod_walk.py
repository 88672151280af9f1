"""The hexapod walking (legsim.Hexapod.walk: the tripod gait's set-points through the servos, the
statics of the planned pose as feed-forward; the feet on the ground's cones, events located),
against the gait's own plan and the invariants of contact:

- straight, two periods (RK4 and generalized-alpha): the box advances the gait's distance
  (step_length / duty a period) to 10 %, keeps its height to 2 cm, its heading to 1 degree and
  its tilt under 3 degrees;
- turning on the spot: the box turns by the gait's angle to 10 % and stays within 3 cm of its
  place;
- throughout: no foot below the ground (1e-9 m), every foot on the ground pushes and a stuck one
  stays inside its cone, the two tripods alternate (each foot free in each period, the tripods'
  feet never free together), every touchdown an impact, every contact problem on the cones
  solved to the solver's tolerance (1e-10).

On a slope (Hexapod.on_ground; the gait keeps the box level, box_height_m over the ground below
it):
- the set-points put through the box's planned pose (world, here by numpy): every standing foot
  on the plane (1e-12 m) and held in the world over its stance (1e-12 m), straight and turning;
  a swinging foot over the ground directly below it, by the step height at its swing's middle;
  the box level, box_height_m over the ground below its centre; level ground gives the level
  gait's set-points bit for bit;
- the feed-forward (the statics of the planned pose, taken with the box over the origin) is the
  statics at the planned pose itself, turned and moved (1e-9 of the weight); its feet push into
  the plane inside their cones, and they carry the weight;
- walking 15 degrees up the fall line (box 1.0 m) and across it (0.85 m) for two periods: the
  box advances the plan's distance to 5 % (drifting sideways less than 10 % of it), stays
  within 2 cm of its height over the ground below it, tilts under 3 degrees, every stuck foot
  inside its cone about the plane's normal, the stance's static stability margin (the centre
  of mass projected along gravity) above 8 cm;
- the attitude chosen, measured: the box parallel to the slope (the level ground's set-points,
  the box turned with the ground) tips the tripod over walking up the fall line at 10 and 15
  degrees (the margin negative), the level box keeps it (0.128 m) and reaches 15 degrees up the
  fall line at 1.0 m and across it at 0.85 m (at 1.0 m unreachable);
- a slope its friction cannot hold (0.3 rad, mu 0.2 / 0.15), the servos holding the stand: every
  foot slides, |F_t| = mu_k N about the plane's normal, the friction against each step's slip, and
  the friction's work is the energy lost (kinetic and gravity's, less the servos' work: both by
  the trapezoid rule, to 1e-3).
"""
from __future__ import annotations

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

GAIT = dict(period_s=1.2, duty=0.6, step_height_m=0.05, box_height_m=1.0)


@pytest.fixture(scope="module")
def hexapod():
    return legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))


def yaw_tilt(q):
    w, x, y, z = q.T
    return 2 * np.arctan2(z, w), 2 * np.arcsin(np.clip(np.hypot(x, y), 0, 1))


def split(h, F):
    """Ground forces (..., 3) as N along the plane's normal and |F_t| along it."""
    n = np.array(h.desc.ground_normal[:])
    N = F @ n
    return N, np.linalg.norm(F - N[..., None] * n, axis=-1)


def over_ground(h, x):
    return (x - np.array(h.desc.ground_point_m[:])) @ np.array(h.desc.ground_normal[:])


def below_z(h, xy):
    """The ground's z directly below the points xy (..., 2)."""
    n, p = np.array(h.desc.ground_normal[:]), np.array(h.desc.ground_point_m[:])
    return p[2] - (n[0] * (xy[..., 0] - p[0]) + n[1] * (xy[..., 1] - p[1])) / n[2]


def contact_invariants(h, w):
    mu_s = h.desc.mu_static
    assert over_ground(h, w["foot_m"]).min() > -1e-9
    on = w["foot_state"] > 0
    N, Ft = split(h, w["foot_force_n"])
    assert np.all(N[on] > -1e-6)
    stuck = w["foot_state"] == 1
    assert np.all(Ft[stuck] <= mu_s * N[stuck] + 1e-6)
    free = w["foot_state"] == 0
    # the tripods alternate: legs 0, 2, 4 and 1, 3, 5 never all free at once, each foot swings
    assert not np.any(free[:, [0, 2, 4]].all(axis=1) & free[:, [1, 3, 5]].all(axis=1))
    assert np.all(free.any(axis=0))


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_walks_straight(hexapod, integrator):
    w = hexapod.walk(**GAIT, step_length_m=0.12, t_end_s=2.4, integrator=integrator)
    yaw, tilt = yaw_tilt(w["box_quat"])
    planned = 2 * 0.12 / GAIT["duty"]
    x, y, z = w["box_m"][-1]
    print(f"straight ({integrator}): box at ({x:.4f}, {y:.4f}, {z:.4f}) m (planned x {planned:.3f}), heading "
          f"{np.degrees(np.abs(yaw).max()):.2f} deg, tilt {np.degrees(tilt.max()):.2f} deg, height "
          f"{w['box_m'][:, 2].min():.4f} .. {w['box_m'][:, 2].max():.4f} m, {w['impacts'][-1]} impacts, "
          f"{w['events'].sum()} events")
    assert abs(x - planned) < 0.1 * planned and abs(y) < 0.02
    assert np.abs(w["box_m"][:, 2] - GAIT["box_height_m"]).max() < 0.02
    assert np.degrees(np.abs(yaw).max()) < 1 and np.degrees(tilt.max()) < 3
    assert w["impacts"][-1] >= 6  # at least one touchdown per swing
    contact_invariants(hexapod, w)
    cone = w["cone"]
    print(f"  the contact problems on the cones: {cone}")
    assert cone["solved"] >= w["impacts"][-1] and cone["max_residual"] <= 1e-10


def test_turns_on_the_spot(hexapod):
    w = hexapod.walk(**GAIT, step_length_m=0.0, turn_rad=0.15, t_end_s=2.4)
    yaw, tilt = yaw_tilt(w["box_quat"])
    planned = 2 * 0.15 / GAIT["duty"]
    print(f"turning: yaw {yaw[-1]:.4f} rad (planned {planned:.3f}), box moved "
          f"{np.hypot(*w['box_m'][-1, :2]):.4f} m, tilt {np.degrees(tilt.max()):.2f} deg, {w['impacts'][-1]} impacts")
    assert abs(yaw[-1] - planned) < 0.1 * planned
    assert np.hypot(*w["box_m"][-1, :2]) < 0.03 and np.degrees(tilt.max()) < 3
    contact_invariants(hexapod, w)


def test_bench_command_writes_its_checks_and_animation(tmp_path):
    """`legsim-bench hexapod` (the demo's last part): its checks pass and it writes the walk's
    plot and its 3D animation (a GIF of about one frame per 0.1 s: Pillow merges equal ones)."""
    from PIL import Image

    from legsim_bench.hexapod_walk import run_walk
    from legsim_bench.scene import find_root

    ok, rows, files = run_walk(find_root(None), tmp_path, periods=1)
    assert ok, rows
    names = sorted(p.name for p in files)
    assert names == ["hexapod_walk.gif", "hexapod_walk.png"]
    with Image.open(tmp_path / "hexapod_walk.gif") as im:
        assert 10 <= im.n_frames <= 13  # 1.2 s at 10 frames a second, both ends


def rotz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


SLOPE = np.radians(15)


@pytest.mark.parametrize("uphill, turn", [(0.0, 0.0), (np.pi / 2, 0.0), (0.7, 0.15)])
def test_slope_setpoints_stand_on_the_plane(hexapod, uphill, turn):
    """The gait's set-points on a 15 degree slope, put into the world through the box's planned
    pose: the standing feet on the plane and held, the swinging ones over the ground below them."""
    h = hexapod.on_ground(slope_rad=SLOPE, uphill_rad=uphill)
    g = dict(GAIT, box_height_m=0.85, step_length_m=0.12 if turn == 0 else 0.06, turn_rad=turn)
    dt, worst_plane, worst_hold, worst_box, peak = 0.005, 0.0, 0.0, 0.0, 0.0
    held = [None] * 6
    for t in np.arange(0, 2 * GAIT["period_s"] + dt / 2, dt):
        sp = h.gait_setpoints(t, **g)
        w, x, y, z = sp["box_quat"]
        assert x == 0 and y == 0  # level
        R = rotz(2 * np.arctan2(z, w))
        feet = sp["box_m"] + sp["foot_box_m"] @ R.T
        worst_box = max(worst_box, abs(sp["box_m"][2] - below_z(h, sp["box_m"][:2]) - g["box_height_m"]))
        for k in range(6):
            if sp["stance"][k]:
                worst_plane = max(worst_plane, abs(over_ground(h, feet[k])))
                if held[k] is None:
                    held[k] = feet[k]
                worst_hold = max(worst_hold, np.linalg.norm(feet[k] - held[k]))
            else:
                held[k] = None
                rise = feet[k][2] - below_z(h, feet[k][:2])
                assert -1e-12 <= rise <= g["step_height_m"] + 1e-12
                peak = max(peak, rise)
    print(f"slope 15 deg, uphill {uphill:.2f} rad, turn {turn}: standing feet off the plane {worst_plane:.1e} m, "
          f"held to {worst_hold:.1e} m; box off its height {worst_box:.1e} m; swing peak {peak:.6f} m")
    assert worst_plane < 1e-12 and worst_hold < 1e-12 and worst_box < 1e-12
    assert abs(peak - g["step_height_m"]) < 1e-4  # sampled every 5 ms near the cosine's top


def test_level_ground_given_is_the_level_gait(hexapod):
    g = dict(GAIT, step_length_m=0.12, turn_rad=0.1)
    flat = hexapod.on_ground(slope_rad=0.0)
    for t in (0.0, 0.3, 0.71, 1.9):
        a, b = hexapod.gait_setpoints(t, **g), flat.gait_setpoints(t, **g)
        for k in a:
            assert np.array_equal(a[k], b[k]), k


def test_feedforward_is_the_statics_on_the_slope(hexapod):
    """The walk's feed-forward takes the planned pose's statics with the box over the origin,
    heading along x: gravity is along the level box's z wherever it is, so they are the statics at
    the planned pose itself (here turned by 0.21 rad and moved)."""
    h = hexapod.on_ground(slope_rad=SLOPE, uphill_rad=0.3)
    g = dict(GAIT, step_length_m=0.06, turn_rad=0.15)
    sp = h.gait_setpoints(1.0, **g)
    stance = [k for k in range(6) if sp["stance"][k]]
    base = {"box_quat": [1.0, 0.0, 0.0, 0.0], "rowing_rad": sp["rowing_rad"], "length_m": sp["length_m"]}
    a = h.statics(dict(base, box_m=[0.0, 0.0, 1.0]), stance=stance)
    b = h.statics(dict(base, box_m=sp["box_m"], box_quat=sp["box_quat"]), stance=stance)
    yaw = 2 * np.arctan2(sp["box_quat"][3], sp["box_quat"][0])
    weight = -a["foot_force_n"][:, 2].sum()
    assert abs(yaw - 0.15 / (0.6 * 1.2)) < 1e-12  # turn / stance time, 1 s on
    assert np.abs(b["foot_force_n"] - a["foot_force_n"] @ rotz(yaw).T).max() < 1e-9 * abs(weight)
    assert np.abs(b["actuator_force_n"] - a["actuator_force_n"]).max() < 1e-9 * abs(weight)
    assert abs(a["margin_m"] - b["margin_m"]) < 1e-12
    # the feet of the planned pose on the plane, pushing into it inside their cones
    N, Ft = split(h, b["foot_force_n"][stance])
    assert np.abs(over_ground(h, b["foot_m"][stance])).max() < 1e-12
    print(f"the tripod on the slope: N {np.round(N, 1)} N, |F_t| / N {np.round(Ft / N, 3)}")
    assert np.all(N > 0) and np.all(Ft < h.desc.mu_static * N)


# across at 0.9 m: a step from 1.809 s failed (LEGSIM_ERR_CONTACT: two slow slips' reversals
# located at one jump of the friction's direction; docs/design/spatial.md)
@pytest.mark.parametrize("uphill, height", [(0.0, 1.0), (np.pi / 2, 0.85), (np.pi / 2, 0.9)],
                         ids=["up", "across", "across_0.9m"])
def test_walks_on_a_slope(hexapod, uphill, height):
    ground = dict(slope_rad=SLOPE, uphill_rad=uphill)
    h = hexapod.on_ground(**ground)
    w = hexapod.walk(**dict(GAIT, box_height_m=height), step_length_m=0.12, t_end_s=2.4, ground=ground)
    yaw, tilt = yaw_tilt(w["box_quat"])
    box = w["box_m"]
    off = np.abs(box[:, 2] - below_z(h, box[:, :2]) - height)
    stuck = w["foot_state"] == 1
    N, Ft = split(h, w["foot_force_n"])
    print(f"slope 15 deg, uphill {uphill:.2f}: box at {np.round(box[-1], 4)} "
          f"(planned {np.round(w['set_box_m'][-1], 4)}), "
          f"height off {off.max():.4f} m, tilt {np.degrees(tilt.max()):.2f} deg, "
          f"heading {np.degrees(yaw[-1]):.2f} deg, "
          f"|F_t|/N stuck {(Ft[stuck] / N[stuck]).max():.3f}, margin {w['margin_m'].min():.4f} m "
          f"(planned {w['plan_margin_m'].min():.4f}), {w['impacts'][-1]} impacts")
    assert np.abs(w["set_box_m"][-1] - [0.4, 0, height + 0.4 * np.tan(SLOPE) * np.cos(uphill)]).max() < 1e-12
    assert abs(box[-1, 0] - w["set_box_m"][-1, 0]) < 0.05 * 0.4 and abs(box[-1, 1]) < 0.1 * 0.4  # across: downhill
    assert off.max() < 0.02 and np.degrees(tilt.max()) < 3 and np.degrees(np.abs(yaw).max()) < 1
    assert w["margin_m"].min() > 0.08 and w["plan_margin_m"].min() > 0.08
    contact_invariants(h, w)


def test_feet_slip_on_a_slope_too_steep(hexapod):
    """The stand on a 0.3 rad slope, mu_static 0.2 < tan 0.3: the servos hold the stand's lengths
    and rowing angles with its statics as feed-forward, and every foot slides."""
    h = hexapod.on_ground(slope_rad=0.3, uphill_rad=0.0, mu_static=0.2, mu_kinetic=0.15)
    pose = h.ground_stand_pose(1.0)
    s = h.statics(pose)
    m = h.sim(pose)
    m.command_pose(pose["length_m"], pose["rowing_rad"], s["actuator_force_n"], s["rowing_torque_nm"])
    masses = h.body_masses()
    n = np.array(h.desc.ground_normal[:])
    g = np.array(h.desc.gravity_mps2[:])
    hs = 1e-3

    def energy(st):  # kinetic and gravity's
        com = masses @ m.body_poses()[:, :3] / masses.sum()
        return st["kinetic_energy_j"] - masses.sum() * g @ com

    a = m.state()
    E0, servos, work, mu_off, angle, fast = energy(a), 0.0, 0.0, 0.0, 0.0, np.zeros(6)
    for _ in range(200):
        m.step(1, h_s=hs)
        b = m.state()
        servos += ((a["actuator_force_n"] + b["actuator_force_n"]) / 2 * (b["length_m"] - a["length_m"])).sum()
        servos += ((a["rowing_torque_nm"] + b["rowing_torque_nm"]) / 2 * (b["rowing_rad"] - a["rowing_rad"])).sum()
        dx = b["foot_m"] - a["foot_m"]
        f = (a["foot_force_n"] + b["foot_force_n"]) / 2
        work += (f * dx).sum()
        for k in range(6):
            assert b["foot_state"][k] == "sliding"
            N, Ft = split(h, b["foot_force_n"][k])
            mu_off = max(mu_off, abs(Ft - 0.15 * N) / N)
            fast[k] = fast[k] + 1 if np.linalg.norm(dx[k]) > 1e-4 * hs else 0
            if fast[k] >= 4:  # the slip's direction settled (as check_cli_output.py's)
                ft = f[k] - (f[k] @ n) * n
                angle = max(angle, np.arccos(np.clip(-ft @ dx[k] / np.linalg.norm(ft) / np.linalg.norm(dx[k]), -1, 1)))
        a = b
    lost = energy(a) - E0 - servos
    print(f"slipping: box at {np.round(a['box_m'], 4)}, |F_t| off mu_k N {mu_off:.1e} of N, friction off the slip "
          f"{angle:.1e} rad, the friction's work {work:.4f} J, the energy's change {lost:.4f} J "
          f"(off by {abs(lost - work) / abs(work):.1e})")
    assert a["box_m"][0] < -0.005  # downhill
    assert mu_off < 1e-9 and angle < 1e-3 and work < 0
    assert abs(lost - work) < 1e-3 * abs(work)


def test_the_level_box_against_the_box_parallel_to_the_slope(hexapod):
    """The box's planned attitude on a slope, measured over one period of the straight gait (every
    10 ms): level (this gait: its set-points through the legs' inverse kinematics, which refuse a
    target past a stroke or the reach), or parallel to the slope (the level ground's set-points,
    reachable wherever those are, the box turned with the ground, its centre box_height_m along
    the normal): the least static stability margin of the stance about the centre of mass
    projected along gravity. Parallel leans the centre of mass downhill by about its height times
    the slope's sine and loses the tripod walking up the fall line at 10 degrees; level keeps the
    margin and reaches 15 degrees up the fall line at 1.0 m, across it at 0.85 m."""
    ts = np.arange(0, GAIT["period_s"], 0.01)
    flat = [hexapod.gait_setpoints(t, **GAIT, step_length_m=0.12) for t in ts]
    rows = {}
    for deg in (10, 15):
        s = np.radians(deg)
        for name, uphill in (("up", 0.0), ("across", np.pi / 2)):
            h = hexapod.on_ground(slope_rad=s, uphill_rad=uphill)
            level = {}
            for height in (1.0, 0.85):
                try:
                    sps = [h.gait_setpoints(t, **dict(GAIT, box_height_m=height), step_length_m=0.12) for t in ts]
                except legsim.UnreachableError:
                    level[height] = None
                    continue
                level[height] = min(h.statics({"box_m": sp["box_m"], "box_quat": [1, 0, 0, 0],
                                               "rowing_rad": sp["rowing_rad"], "length_m": sp["length_m"]},
                                              stance=np.flatnonzero(sp["stance"]))["margin_m"] for sp in sps)
            # parallel: the box's z along the ground's normal (a turn about its x or y by the slope)
            n = np.array(h.desc.ground_normal[:])
            q = [np.cos(s / 2), 0, -np.sin(s / 2), 0] if uphill == 0 else [np.cos(s / 2), np.sin(s / 2), 0, 0]
            parallel = np.inf
            for sp in flat:
                pose = {"box_m": GAIT["box_height_m"] * n, "box_quat": q, "rowing_rad": sp["rowing_rad"],
                        "length_m": sp["length_m"]}
                six = h.statics(pose)  # the centre of mass and the feet, on all six
                on = np.flatnonzero(sp["stance"])
                assert np.abs(over_ground(h, six["foot_m"][on])).max() < 1e-9  # the legs' inverse kinematics
                parallel = min(parallel, h.support_margin(six["foot_m"][on], six["com_m"]))
            rows[deg, name] = (level[1.0], level[0.85], parallel)
            fmt = lambda m: "unreachable" if m is None else f"{m:.4f} m"  # noqa: E731
            print(f"{deg} deg {name:6s}: level box at 1.0 m {fmt(level[1.0])}, at 0.85 m {fmt(level[0.85])}; "
                  f"parallel at 1.0 m {parallel:.4f} m")
    assert rows[10, "up"][2] < 0 and rows[15, "up"][2] < 0  # parallel tips the tripod over
    assert all(r[1] > 0.1 for r in rows.values())            # level at 0.85 m reaches all and keeps its margin
    assert rows[15, "up"][0] > 0.1 and rows[15, "across"][0] is None
