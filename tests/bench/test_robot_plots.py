"""Tests of the robot plots (legsim_bench.report.robot_plots).

The drawn artists are read back and compared with what the model files and the
reference say, computed here another way: box corners from the body
convention (xi, eta) = (-y, x) on u(phi), n(phi); legs' ends from leg.toml's
lengths and joint ends; arrows against (T, N) rotated by the slope; the GIF's
frames and size through Pillow.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from legsim_bench.report import robot_plots as rp
from legsim_bench.reference import LengthCommand, n, u
from model_files import DATA, LEG


@pytest.fixture(scope="module")
def run(robot):
    """A short servo-held run from the stand (it sags a little: the stand is not the servo equilibrium)."""
    servo = [LengthCommand(float(x)) for x in robot.stand_lengths()]
    return robot.simulate(0.02, t_eval=np.linspace(0.0, 0.02, 26), actuators=servo)


@pytest.fixture(scope="module")
def traj(robot, run):
    return rp.RobotTrajectory.from_reference(robot, run, title="test")


@pytest.fixture()
def axes():
    plt = rp._plt()
    fig, ax = plt.subplots()
    yield ax
    plt.close(fig)


def tilted(traj, box_phi=0.7, slope=0.3):
    """The same run with the box turned and the ground tilted, feet in every state
    (the drawing does not need a consistent pose: the test needs large angles)."""
    q = traj.q.copy()
    q[:, traj.box, 2] += box_phi
    contact = traj.contact.copy()
    contact[8:, 0] = rp.SLIDING
    contact[16:, 1] = rp.FREE
    return replace(traj, q=q, contact=contact, ground_slope=slope)


# ------------------------------------------------------------ the trajectory
def test_a_can_recording_draws_as_the_run_it_carries(robot, run, traj):
    """from_recording (a robot scene over CAN: flat q, per-foot ST_CONTACT dicts) gives the
    trajectory of the run it carries, with the names, lengths and ground of the model file
    as the core loads it (legsim.Model), which here must equal the reference's."""
    import legsim
    from model_files import ROBOT

    samples = [{"t": float(t), "q": list(map(float, q)),
                "contacts": [{"state": "stuck", "normal": float(N), "tangential": float(T),
                              "x": float(p[0]), "y": float(p[1])}
                             for N, T, p in zip(nk, tk, run.feet)]}
               for t, q, nk, tk in zip(run.t, run.q, run.normal, run.tangential)]
    rec = {"legs": 2, "complete": True, "samples": samples}
    got = rp.RobotTrajectory.from_recording(rec, legsim.Model.from_toml(ROBOT), robot.box_size, "can")
    assert got.body_names == traj.body_names and got.foot_names == traj.foot_names
    assert np.array_equal(got.q, traj.q) and np.array_equal(got.t, traj.t)
    legs = [b for b in range(len(got.body_names)) if b != got.box]  # the box is drawn by its size
    assert np.allclose(got.body_lengths[legs], traj.body_lengths[legs], rtol=0, atol=1e-15)
    assert np.array_equal(got.feet, traj.feet) and np.array_equal(got.normal, traj.normal)
    assert (got.contact == rp.STUCK).all() and got.ground_slope == traj.ground_slope
    # a scene's [ground] (hil_sim --ground) is the one drawn, not the model file's
    steep = {"point": [0.0, -0.5], "slope": 0.3, "mu_static": 0.2, "mu_kinetic": 0.15}
    g2 = rp.RobotTrajectory.from_recording(rec, legsim.Model.from_toml(ROBOT), robot.box_size, "can",
                                           ground=steep)
    assert (g2.ground_slope, g2.mu_static, g2.mu_kinetic) == (0.3, 0.2, 0.15) != (got.ground_slope, got.mu_static,
                                                                                  got.mu_kinetic)
    assert np.array_equal(g2.ground_point, steep["point"])
    with pytest.raises(ValueError, match="ST_CONTACT"):
        rp.RobotTrajectory.from_recording(dict(rec, samples=[dict(samples[0], contacts=[])]),
                                          legsim.Model.from_toml(ROBOT), robot.box_size)


def test_from_reference_round_trips_shapes_and_names(robot, run, traj):
    N = len(run.t)
    assert traj.body_names == robot.body_names and len(traj.body_names) == 13
    assert traj.body_names[traj.box] == DATA["box"]["name"]
    assert traj.foot_names == ["right.foot", "left.foot"]
    assert traj.q.shape == (N, 13, 3) and np.array_equal(traj.q.reshape(N, -1), run.q)
    assert np.array_equal(traj.t, run.t)
    assert traj.feet.shape == (N, 2, 2) and np.array_equal(traj.feet[-1], run.feet)
    assert np.array_equal(traj.normal, run.normal) and np.array_equal(traj.tangential, run.tangential)
    assert traj.contact.shape == (N, 2) and np.all(traj.contact == rp.STUCK)
    assert tuple(traj.box_size) == tuple(DATA["box"]["size"])
    assert traj.mu_static == DATA["ground"]["mu_static"]
    assert traj.mu_kinetic == DATA["ground"]["mu_kinetic"]
    lengths = {b["name"]: b["length"] for b in LEG["body"]}
    for b, name in enumerate(traj.body_names):
        if b != traj.box:
            assert traj.body_lengths[b] == lengths[name.split(".", 1)[1]]
    # contact states by name, as a CLI's output gives them
    named = replace(traj, contact=np.full(traj.contact.shape, "sliding"))
    assert np.all(named.contact == rp.SLIDING)


@pytest.mark.parametrize("change,match", [
    ({"q": np.zeros((26, 12, 3))}, "q: shape"),
    ({"contact": np.full((26, 2), "rolling")}, "unknown state"),
    ({"contact": np.full((26, 2), 3)}, "states are"),
    ({"normal": np.full((26, 2), np.nan)}, "normal: not finite"),
    ({"t": np.zeros(26)}, "increase"),
    ({"mu_kinetic": 0.9}, "mu_kinetic"),
])
def test_bad_trajectories_are_refused(traj, change, match):
    with pytest.raises(ValueError, match=match):
        replace(traj, **change)


def test_drawn_legs_join_at_their_joints_and_hips_sit_on_the_box(traj):
    """The segments (each body between its ends) meet where leg.toml's joints say."""
    names = traj.body_names
    for k in (0, len(traj.t) - 1):
        seg = traj.segments(k)
        x, y, phi = traj.q[k, traj.box]
        for leg in DATA["leg"]:
            p = leg["name"] + "."
            end = {name[len(p):]: seg[b] for b, name in enumerate(names) if name.startswith(p)}
            C = end["thigh"][1]
            assert np.max(np.abs(end["upper_rod"][1] - C)) < 1e-12
            assert np.max(np.abs(end["shank"][0] - C)) < 1e-12
            # the pivots at the box points of robot.toml (box frame -> world: (xi, eta) = (-y, x))
            A, B = (np.array([x, y]) + (-py) * u(phi) + px * n(phi)
                    for px, py in (leg["attach"]["A"], leg["attach"]["B"]))
            assert np.max(np.abs(end["upper_cylinder"][0] - A)) < 1e-12
            assert np.max(np.abs(end["thigh"][0] - B)) < 1e-12
            assert np.max(np.abs(end["lower_cylinder"][0] - B)) < 1e-12
            # D: the lower rod's distal end on the shank, leg.toml's 'at' from the shank's centre
            D_at = next(j["at"][0] for j in LEG["joint"] if j["name"] == "D")
            shank_c = 0.5 * (end["shank"][0] + end["shank"][1])
            axis = (end["shank"][1] - end["shank"][0]) / np.linalg.norm(end["shank"][1] - end["shank"][0])
            assert np.max(np.abs(end["lower_rod"][1] - (shank_c + D_at * axis))) < 1e-12


# ------------------------------------------------------------ the drawing
@pytest.mark.parametrize("k", [0, 25])
def test_drawn_box_corners_are_the_box_pose_of_the_box_size(traj, axes, k):
    tr = tilted(traj)
    art = rp.RobotArtists(axes, tr, k, n_per_m=500.0)
    drawn = np.asarray(art.box.get_xy())[:4]            # the patch closes on its first corner
    x, y, phi = tr.q[k, tr.box]
    w, h = DATA["box"]["size"]
    want = [np.array([x, y]) + (-cy) * u(phi) + cx * n(phi)
            for cx, cy in ((-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2))]
    assert np.max(np.abs(drawn - np.array(want))) < 1e-12
    # the sides keep the box's size (equal scale, no shear)
    assert abs(np.linalg.norm(drawn[1] - drawn[0]) - w) < 1e-12
    assert abs(np.linalg.norm(drawn[2] - drawn[1]) - h) < 1e-12
    # and update() moves it to another sample
    other = 0 if k else 25
    art.update(other)
    assert np.max(np.abs(np.asarray(art.box.get_xy())[:4] - tr.box_corners(other))) < 1e-15


def test_foot_markers_sit_at_the_feet_in_their_state(traj, axes):
    tr = tilted(traj)
    art = rp.RobotArtists(axes, tr, 0, n_per_m=500.0)
    for k in range(len(tr.t)):
        art.update(k)
        for s in (rp.FREE, rp.STUCK, rp.SLIDING):
            x, y = (np.asarray(v, float) for v in art.feet[s].get_data())
            on = tr.contact[k] == s
            assert np.array_equal(x, tr.feet[k, on, 0]) and np.array_equal(y, tr.feet[k, on, 1])
        # the feet themselves: the shanks' distal ends (leg.toml's [foot]) of the drawn segments
        seg = tr.segments(k)
        for f, name in enumerate(tr.foot_names):
            shank = tr.body_names.index(name.replace("foot", "shank"))
            assert np.max(np.abs(seg[shank, 1] - tr.feet[k, f])) < 1e-11
    # three distinct marker shapes, named in the legend
    assert len({art.feet[s].get_marker() for s in art.feet}) == 3
    labels = [h.get_label() for h in rp._legend_handles(tr, 500.0)]
    assert {"foot free", "foot stuck", "foot sliding"} <= set(labels)
    assert "ground force (500 N per m)" in labels


@pytest.mark.parametrize("slope", [0.0, 0.3, -0.5])
def test_arrows_are_T_N_rotated_by_the_slope(traj, axes, slope):
    tr = tilted(traj, slope=slope)
    n_per_m = 400.0
    art = rp.RobotArtists(axes, tr, 0, n_per_m=n_per_m)
    c, s = math.cos(slope), math.sin(slope)
    R = np.array([[c, -s], [s, c]])
    for k in (1, 25):
        art.update(k)
        UV = np.column_stack([art.arrows.U, art.arrows.V])
        want = (R @ np.vstack([tr.tangential[k], tr.normal[k]])).T / n_per_m
        assert np.max(np.abs(UV - want)) < 1e-15
        assert np.max(np.abs(np.asarray(art.arrows.get_offsets()) - tr.feet[k])) < 1e-15
        # data units: length = |force| / (N per m)
        assert np.allclose(np.hypot(*UV.T), np.hypot(tr.normal[k], tr.tangential[k]) / n_per_m,
                           rtol=1e-14)
    assert art.arrows.scale == 1.0 and art.arrows.scale_units == "xy" and art.arrows.angles == "xy"


def test_force_scale_is_a_round_number_fitting_the_largest_force(traj):
    s = rp.nice_force_scale(traj, arrow_m=0.4)
    fmax = np.max(np.hypot(traj.normal, traj.tangential))
    assert fmax / s <= 0.4 and fmax / s > 0.4 / 10
    assert s / 10 ** math.floor(math.log10(s)) in (1.0, 2.0, 5.0)


def test_pngs_are_written(traj, tmp_path):
    path, drawn = rp.plot_snapshots(traj, tmp_path / "s.png", times=[0.0, 0.01, 0.02])
    assert path.stat().st_size > 10_000 and len(drawn) == 3
    assert rp.plot_time_series(tilted(traj), tmp_path / "ts.png").stat().st_size > 10_000
    with pytest.raises(ValueError, match="outside the run"):
        rp.plot_snapshots(traj, tmp_path / "x.png", times=[0.5])


# ------------------------------------------------------------ the animation
def test_gif_has_its_frames_and_stays_in_budget(traj, tmp_path):
    from PIL import Image
    tr = tilted(traj)
    fps, speed = 25.0, 0.02                   # 0.02 s of motion played over 1 s: 26 frames
    frames = rp.animation_frames(tr, fps, speed)
    assert np.array_equal(frames, np.arange(26))
    # frames between samples show the nearest sample
    slow = rp.animation_frames(tr, 25.0, 0.004)      # a frame every 0.16 ms, samples every 0.8 ms
    assert np.array_equal(slow, np.rint(np.arange(126) * 0.2).astype(int))
    path = rp.write_robot_animation(tr, tmp_path / "robot.gif", fps=fps, speed=speed)
    with Image.open(path) as im:
        assert im.format == "GIF" and im.size == (400, 300)
        assert im.n_frames == 26
        assert abs(im.info["duration"] - 1000 / fps) <= 1
    assert path.stat().st_size < 2 * 1024 * 1024


def test_animation_refuses_bad_requests(traj, tmp_path):
    with pytest.raises(ValueError, match="gif or .mp4"):
        rp.write_robot_animation(traj, tmp_path / "robot.avi")
    with pytest.raises(ValueError, match="positive"):
        rp.write_robot_animation(traj, tmp_path / "robot.gif", fps=0.0)
    assert not (tmp_path / "robot.gif").exists()
