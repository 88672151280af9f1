"""The robot's scenes (scenes/robot_*.toml) through legsim_cli, against the bench's independent
reference (legsim_bench.reference.robot.RobotModel): the bench's Scene holds what legsim_cli
resolved, the Fig. 7 scene matches the reference, the constant-force stand drifts away at the linearized
modes' rates, the servo stand stays put, and the CLI's output draws (robot_plots)."""
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from built import legsim_cli

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.verdict.analyses import robot_arrays, robot_growth, robot_reference  # noqa: E402
from legsim_bench.scene import SceneError, load_scene, parse_scene  # noqa: E402

ROBOT_SCENES = ["robot_stand_servo", "robot_stand_constant_force", "robot_fig7", "robot_both_upper",
                "robot_stand_statics", "robot_slope_stand", "robot_slope_slide", "robot_sliding",
                "robot_sliding_paper"]


def _cli():
    p = legsim_cli()
    r = subprocess.run([str(p), str(ROOT / "scenes" / "robot_fig7.toml"), "--check"], capture_output=True,
                       text=True, timeout=60)
    if r.returncode != 0 and "capacity" in r.stderr.lower():
        pytest.skip(f"{p}: this build's capacities do not hold the robot")
    return p


def _run(name):
    r = subprocess.run([str(_cli()), str(ROOT / "scenes" / f"{name}.toml")], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.fixture(scope="module")
def fig7():
    sc = load_scene("robot_fig7", ROOT)
    out = _run("robot_fig7")
    d = robot_arrays(out)
    model, ref = robot_reference(sc, d["t"], ROOT)
    return sc, out, d, model, ref


@pytest.mark.parametrize("name", ROBOT_SCENES)
def test_robot_scenes_resolve_to_the_robot_s_names(name):
    sc = load_scene(ROOT / "scenes" / f"{name}.toml", ROOT)
    assert sc.robot and sc.legs == 2 and sc.over_can == (sc.analysis == "dynamics" and sc.can_refusal is None)
    assert sc.actuator_names == ("right.upper", "right.lower", "left.upper", "left.lower")
    assert sc.model_info.contacts == ("right.foot", "left.foot")
    assert sc.model_info.forces == (("right.foot_load", "point"), ("left.foot_load", "point"))
    assert set(sc.resolved()["commands"]) <= set(sc.actuator_names)
    assert [c.name for c in sc.commands if c is not None] == list(sc.resolved()["commands"])


def test_robot_keys_are_refused_or_checked_by_the_reader():
    base = 'model = "builtin:robot"\nduration = 0.01\n'
    sc = parse_scene(base + '[[contact]]\nname = "left.foot"\nstate = "free"\n', name="t", root=ROOT)
    assert sc.contacts == {"left.foot": "free"} and sc.model_info.contacts == ("right.foot", "left.foot")
    sc = parse_scene(base + 'contact_law = "paper"\n', name="t", root=ROOT)
    assert sc.contact_law == "paper" and sc.resolved()["contact_law"] == "paper"
    assert parse_scene(base, name="t", root=ROOT).contact_law == "lcp"
    for text, words in [("contact_law = \"coulomb\"\n", "'contact_law' must be lcp or paper (got 'coulomb')"),
                        ("[[command]]\nactuator = \"upper\"\nmode = \"force\"\nvalue = 1.0\n",
                         "command 'upper': the model has no actuator 'upper'"),
                        ("[[contact]]\nname = \"right.foot\"\nstate = \"sliding\"\n",
                         "a foot starts sliding only in dynamics with a")]:
        with pytest.raises(SceneError, match=words.replace("(", r"\(").replace(")", r"\)")):
            parse_scene(base + text, name="t", root=ROOT)
    with pytest.raises(SceneError, match="statics_sweep of a model with contacts is not in this core yet"):
        parse_scene('model = "builtin:robot"\nanalysis = "statics_sweep"\n', name="t", root=ROOT)
    sc = parse_scene('model = "builtin:robot"\nanalysis = "inverse_dynamics"\nduration = 0.01\n'
                     'box_load = [1.0, -2.0, 3.0]\n', name="t", root=ROOT)
    assert sc.box_load == (1.0, -2.0, 3.0) and sc.resolved()["box_load"] == [1.0, -2.0, 3.0]
    sc = parse_scene('model = "builtin:robot"\nanalysis = "statics"\nstatics_rule = "min_tangential"\n',
                     name="t", root=ROOT)
    assert sc.statics_rule == "min_tangential" and sc.resolved()["statics_rule"] == "min_tangential"
    for text, words in [('analysis = "statics"\nstatics_rule = "paper"\n',
                         "'statics_rule' must be equal_friction or min_tangential (got 'paper')"),
                        ('duration = 0.01\nstatics_rule = "min_tangential"\n', "'statics_rule' applies to statics and inverse_dynamics only")]:
        with pytest.raises(SceneError, match=re.escape(words)):
            parse_scene('model = "builtin:robot"\n' + text, name="t", root=ROOT)
    with pytest.raises(SceneError, match=re.escape("'statics_rule' applies to a model with contacts only")):
        parse_scene('analysis = "statics"\nstatics_rule = "equal_friction"\n', name="t", root=ROOT)


def test_builtin_robot_and_the_robot_file_give_the_same_run(tmp_path):
    """The compiled-in robot (builtin:robot) and models/robot.toml loaded at run time are one
    model: the same scene gives the same samples, bit for bit."""
    text = (ROOT / "scenes" / "robot_fig7.toml").read_text()
    p = tmp_path / "fig7_builtin.toml"
    p.write_text(text.replace('model = "../models/robot.toml"', 'model = "builtin:robot"'))
    r = subprocess.run([str(_cli()), str(p)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["samples"] == _run("robot_fig7")["samples"]


def test_fig7_through_legsim_cli_matches_robot_model(fig7):
    """Design section 7, Scene A, RK4 at h = 1 ms against the reference's DOP853 (rtol 1e-11):
    RK4's global error over 0.1 s of a 4 mm motion is ~1e-10 (m, rad); forces ~1e-6 N."""
    sc, out, d, model, ref = fig7
    dq = d["q"] - ref.q
    assert np.max(np.abs(dq)) < 1e-9
    solved = slice(1, None)   # the first sample's forces are not solved yet (null)
    assert np.max(np.abs(d["normal"][solved] - ref.normal[solved])) < 1e-5
    assert np.max(np.abs(d["tangential"][solved] - ref.tangential[solved])) < 1e-5
    assert np.max(np.abs(d["forces"][solved] - ref.actuator_forces[solved])) < 1e-5
    assert np.all(d["state"] == "stuck")
    # Table II the paper's way: the right leg's phi3 (thigh) and phi6 (shank) at 0.1 s
    assert out["bodies"][3] == "right.thigh" and out["bodies"][6] == "right.shank"
    phi3, phi6 = d["q"][-1, 3 * 3 + 2], d["q"][-1, 3 * 6 + 2]
    assert abs(phi3 - 1.07133) < 1e-5 and abs(phi6 + 0.01484) < 1e-5
    assert math.degrees(phi3) == pytest.approx(61.383, abs=1e-3)
    # the ground forces of design section 7: right (148.18, -20.95) N, left (163.65, +29.10) N
    assert d["normal"][-1] == pytest.approx([148.18, 163.65], abs=0.01)
    assert d["tangential"][-1] == pytest.approx([-20.95, 29.10], abs=0.01)
    # the feet do not move while stuck
    assert np.max(np.abs(d["feet"] - d["feet"][0])) < 1e-12


def test_constant_force_stand_drifts_away_at_the_linearized_rates():
    """The equal_friction statics forces hold the stand in an unstable equilibrium; 0.01 N more
    on the right upper sets it drifting. Fitted from the CLI's box motion over 2 s: the sway
    (box x) at RobotModel's 4.0998 /s within 0.1 % (measured 4.1002), the heave (box y, the
    sway's square fitted with it) at 0.8243 /s within 1 % (measured 0.8287: the heave's own
    second-order terms); and the run itself matches the reference's to 1e-8."""
    sc = load_scene("robot_stand_constant_force", ROOT)
    d = robot_arrays(_run("robot_stand_constant_force"))
    model, ref = robot_reference(sc, d["t"], ROOT)
    g = robot_growth(model, d)
    (ps, ph), (ms, mh) = g["predicted"], g["measured"]
    assert ps == pytest.approx(4.100, abs=1e-3) and ph == pytest.approx(0.824, abs=1e-3)
    assert abs(ms - ps) / ps < 1e-3
    assert abs(mh - ph) / ph < 1e-2
    assert np.max(np.abs(d["q"] - ref.q)) < 1e-8
    # it does drift: the box has moved 0.6 mm sideways at 2 s, about e^(4.1 x 2) times its start
    assert abs(d["q"][-1, 0] - d["q"][0, 0]) > 5e-4


def test_servo_stand_stays_put_and_both_uppers_raise_the_box():
    d = robot_arrays(_run("robot_stand_servo"))
    assert np.max(np.abs(d["q"] - d["q"][0])) < 1e-9           # generalized-alpha, 1 s at rest
    assert d["normal"][-1] == pytest.approx([158.922, 158.922], abs=1e-3)   # half the weight each
    b = robot_arrays(_run("robot_both_upper"))
    rise = b["q"][:, 1] - b["q"][0, 1]
    # the box rises while the set-points step (10 mm longer uppers) and the servos then hold it
    # up, swinging about its new height in the servo stand's 7.5 rad/s mode (which decays at
    # only 0.71 /s): 8.6 .. 16.0 mm after 0.15 s, level (symmetric push: no sway, no pitch)
    late = b["t"] > 0.15
    assert 0.008 < np.min(rise[late]) and np.max(rise[late]) < 0.017
    assert np.max(np.abs(b["q"][:, 0] - b["q"][0, 0])) < 1e-9 and np.max(np.abs(b["q"][:, 2])) < 1e-9


def test_a_robot_trajectory_from_the_cli_output_draws(fig7, tmp_path):
    pytest.importorskip("matplotlib")
    from legsim_bench.report.robot_plots import RobotTrajectory, plot_snapshots, write_robot_animation
    sc, out, d, model, ref = fig7
    traj = RobotTrajectory.from_cli_json(out, model.box_size, title="Fig. 7 (legsim_cli)")
    assert len(traj.t) == len(d["t"]) - 1                     # the first sample has no forces yet
    assert traj.foot_names == ["right.foot", "left.foot"] and np.all(traj.contact == 1)
    assert np.allclose(traj.q[-1].reshape(-1), ref.q[-1], atol=1e-9)
    png = plot_snapshots(traj, tmp_path / "snap.png", n=3)[0]
    gif = write_robot_animation(traj, tmp_path / "fig7.gif", fps=10, speed=0.05)
    assert Path(png).stat().st_size > 5000 and Path(gif).stat().st_size > 5000
    with pytest.raises(ValueError, match="no sample with solved ground forces"):
        RobotTrajectory.from_cli_json(dict(out, samples=out["samples"][:1]), model.box_size)


def test_the_bench_and_the_core_name_the_same_events():
    """legsim_bench.verdict.analyses.EVENT_NAMES is legsim.h's bit order, as the Python binding names
    the bits (python/legsim/sim.py EVENTS, bit k is 1 << k) and legsim_cli writes them."""
    from legsim_bench.verdict.analyses import CONTACT_EVENTS, EVENT_NAMES
    text = (ROOT / "python" / "legsim" / "sim.py").read_text()
    block = text[text.index("EVENTS = {"):]
    block = block[:block.index("}")]
    bits = {m.group(1): int(m.group(2)) for m in re.finditer(r'"(\w+)": 1 << (\d+)', block)}
    assert bits == {n: k for k, n in enumerate(EVENT_NAMES)}
    assert set(CONTACT_EVENTS) == {"liftoff", "touchdown", "stick_to_slip", "slip_to_stick",
                                   "contact_inconsistent", "contact_ambiguous"}
    cpp = (ROOT / "firmware_core" / "host" / "scene_write.cpp").read_text()
    for n in EVENT_NAMES:
        assert f'"{n}"}}' in cpp, n


@pytest.mark.parametrize("rule", ["equal_friction", "min_tangential"])
def test_stand_statics_through_legsim_cli_matches_robot_model(rule, tmp_path):
    """The stand's statics on both stuck feet (legsim_statics with the scene's statics_rule)
    against RobotModel.statics: the bench's checks pass, and the numbers are the stand's:
    326.539 N upper, 1.387 N lower per leg, N = 158.922 N per foot (half the weight), T = 0 by
    symmetry under either rule, both feet held by their cones."""
    from legsim_bench.verdict.checks import evaluate
    from legsim_bench.hil.runner import record
    _cli()
    text = (ROOT / "scenes" / "robot_stand_statics.toml").read_text()
    p = tmp_path / f"stand_{rule}.toml"
    p.write_text(text.replace('model = "../models/robot.toml"', f'model = "{ROOT / "models" / "robot.toml"}"')
                 .replace('statics_rule = "equal_friction"', f'statics_rule = "{rule}"'))
    sc = load_scene(p, ROOT)
    assert sc.robot and sc.analysis == "statics" and sc.statics_rule == rule
    rec = record(sc, link=None)
    assert rec["complete"] and rec["runner"] == "legsim_cli", rec["errors"]
    ev = evaluate(rec, ROOT)
    assert ev.passed, [(r.name, r.value, r.detail) for r in ev.results if not r.passed]
    names = {r.name for r in ev.results}
    assert {"actuator forces vs RobotModel.statics", "ground forces N, T per foot vs RobotModel.statics",
            "joint reaction forces vs RobotModel.statics"} <= names
    out = rec["cli_output"]
    d = robot_arrays(out)
    assert d["forces"][0] == pytest.approx([326.539, 1.387, 326.539, 1.387], abs=1e-3)
    assert d["normal"][0] == pytest.approx([158.922, 158.922], abs=1e-3)
    assert np.max(np.abs(d["tangential"][0])) < 1e-9
    assert [out["samples"][0]["contacts"][f]["holds"] for f in out["contacts"]] == [True, True]
    assert list(d["state"][0]) == ["stuck", "stuck"]


def test_the_two_rules_differ_on_a_slope(tmp_path):
    """On flat ground under gravity alone the feet carry no net tangential load and both rules
    give T = 0; on a slope (scenes/models/robot_slope_stand.toml, 0.15 rad) the weight's
    component along the line, W sin(slope), is shared by the indeterminate pair: equal_friction
    gives T_R/N_R = T_L/N_L, min_tangential T_R = T_L. legsim_cli matches RobotModel under each,
    the two differ, and N does not depend on the rule."""
    from legsim_bench.verdict.analyses import robot_statics_reference
    _cli()
    model = ROOT / "scenes" / "models" / "robot_slope_stand.toml"
    got = {}
    for rule in ("equal_friction", "min_tangential"):
        p = tmp_path / f"{rule}.toml"
        p.write_text(f'model = "{model}"\nanalysis = "statics"\nstatics_rule = "{rule}"\n')
        r = subprocess.run([str(_cli()), str(p)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        d = robot_arrays(json.loads(r.stdout))
        _, st = robot_statics_reference(load_scene(p, ROOT))
        assert d["normal"][0] == pytest.approx(st.normal, abs=1e-6)
        assert d["tangential"][0] == pytest.approx(st.tangential, abs=1e-6)
        assert d["forces"][0] == pytest.approx(st.actuator_forces, abs=1e-6)
        got[rule] = d
    ef, mt = got["equal_friction"], got["min_tangential"]
    W = 2 * 158.922   # the robot's weight (N)
    for d in (ef, mt):   # the line's balance: the feet carry the weight's components
        assert np.sum(d["normal"][0]) == pytest.approx(W * math.cos(0.15), rel=1e-9)
        assert abs(np.sum(d["tangential"][0])) == pytest.approx(W * math.sin(0.15), rel=1e-9)
    assert ef["tangential"][0, 0] / ef["normal"][0, 0] == pytest.approx(ef["tangential"][0, 1] / ef["normal"][0, 1])
    assert mt["tangential"][0, 0] == pytest.approx(mt["tangential"][0, 1])
    assert abs(ef["tangential"][0, 0] - mt["tangential"][0, 0]) > 1e-2
    assert ef["normal"][0] == pytest.approx(mt["normal"][0], abs=1e-9)


def _bench(name):
    from legsim_bench.verdict.checks import evaluate
    from legsim_bench.hil.runner import record
    _cli()
    sc = load_scene(name, ROOT)
    rec = record(sc, link=None)
    assert rec["complete"], rec["errors"]
    return sc, rec["cli_output"], evaluate(rec, ROOT)


def test_on_a_slope_the_feet_hold_where_mu_static_exceeds_its_tangent():
    """0.15 rad, mu_static 0.6 > tan 0.15: both feet stay stuck for 0.5 s, no contact event,
    while the box leans 41 mm downhill; the run matches RobotModel on the same slope (1e-9)."""
    sc, out, ev = _bench("robot_slope_stand")
    assert ev.passed, [(r.name, r.error, r.detail) for r in ev.results if not r.passed]
    assert out["ground"]["slope"] == 0.15 and out["ground"]["mu_static"] == 0.6
    d = robot_arrays(out)
    assert np.all(d["state"] == "stuck") and not any(d["events"])
    assert np.max(np.abs(d["feet"] - d["feet"][0])) < 1e-12
    use = np.abs(d["tangential"][1:]) / d["normal"][1:]
    assert 0.151 < np.max(use) < 0.6                      # more than the slope's tangent, held
    assert d["q"][-1, 0] - d["q"][0, 0] < -0.03


def test_on_a_slope_the_feet_slide_where_mu_static_is_below_its_tangent():
    """0.15 rad, mu_static 0.12 < tan 0.15: both feet go from stuck to sliding with the core's
    stick_to_slip (the bench's 'slips' check); while sliding |T| = mu_kinetic N against the
    slip; a scene whose feet are listed in 'slips' but stay stuck fails the check."""
    sc, out, ev = _bench("robot_slope_slide")
    assert sc.checks.slips == ("right.foot", "left.foot")
    assert ev.passed, [(r.name, r.error, r.detail) for r in ev.results if not r.passed]
    d = robot_arrays(out)
    from legsim_bench.verdict.analyses import robot_slip_starts
    assert robot_slip_starts(d, 0) and robot_slip_starts(d, 1)
    assert any("stick_to_slip" in e for e in d["events"])
    # sliding from t = 0 (the cone cannot hold the start); the first sample has no forces
    sliding = (d["state"] == "sliding") & np.isfinite(d["normal"])
    slip = np.array([[s["contacts"][c]["slip"] for c in out["contacts"]] for s in out["samples"]])
    T, N = d["tangential"][sliding], d["normal"][sliding]
    assert T == pytest.approx(-0.10 * N * np.sign(slip[sliding]), rel=1e-9)
    # the same checks on the stand's run (feet stuck) fail: the check sees the states
    from legsim_bench.verdict.analyses import _robot_slip_checks
    from legsim_bench.verdict.result import Evaluation
    stand = robot_arrays(_bench("robot_slope_stand")[1])
    ev2 = _robot_slip_checks(Evaluation(sc, {}, []), sc.checks.slips, stand, out["contacts"])
    assert not any(r.passed for r in ev2.results)


def test_slips_leaves_the_stuck_reference_and_is_checked_by_the_reader():
    base = ('model = "builtin:robot"\nduration = 0.01\n[checks]\nresidual = 1e-8\n')
    assert parse_scene(base + 'slips = ["left.foot"]\n', name="t", root=ROOT).checks.slips == ("left.foot",)
    with pytest.raises(SceneError, match="'slips' must be a list of the model's contacts"):
        parse_scene(base + 'slips = ["middle.foot"]\n', name="t", root=ROOT)
    with pytest.raises(SceneError, match="position_m compare with RobotModel's stance"):
        parse_scene(base + 'slips = ["left.foot"]\nposition_m = 1e-6\n', name="t", root=ROOT)
    with pytest.raises(SceneError, match=re.escape("'slip_onset_steps' needs 'slips' (the foot that slips first)")):
        parse_scene(base + 'slip_onset_steps = 1\n', name="t", root=ROOT)
    onset = parse_scene(base + 'slips = ["left.foot"]\nslip_onset_steps = 1\nposition_m = 1e-6\n', name="t", root=ROOT)
    assert onset.checks.slip_onset_steps == 1 and onset.checks.position_m == 1e-6
    with pytest.raises(SceneError, match=re.escape("[checks] (robot dynamics): unknown key 'moment_nm'")):
        parse_scene(base + 'moment_nm = 1e-6\n', name="t", root=ROOT)
    with pytest.raises(SceneError, match=re.escape("[checks]: lifts compare with RobotModel's stance on stuck "
                                                   "feet, which 'slips' leaves")):
        parse_scene(base + 'slips = ["left.foot"]\nlifts = ["left.foot"]\n', name="t", root=ROOT)
    assert parse_scene(base + 'lifts = ["left.foot"]\n', name="t", root=ROOT).checks.lifts == ("left.foot",)


@pytest.mark.parametrize("name, law, foot", [("robot_sliding", "lcp", "left.foot"),
                                             ("robot_sliding_paper", "paper", "right.foot")])
def test_sliding_configuration_slides_the_law_s_foot(name, law, foot):
    """Uppers held (the right one 20 mm longer), both lowers ramped out together: under the
    Coulomb law the left foot, whose |T|/N reaches mu_static first, slides; under the paper's
    rule the right one, which has the smaller |T|; both at t = 0.344 s, within one step after
    RobotModel's stuck-stuck |T|/N reaches mu_static (0.34338 s), the run before it on the
    reference to 1e-8 m; the states change with their events."""
    from legsim_bench.verdict.analyses import robot_slip_onset
    sc, out, ev = _bench(name)
    assert sc.contact_law == law and sc.checks.slips == (foot,) and sc.checks.slip_onset_steps == 1
    assert ev.passed, [(r.name, r.error, r.detail) for r in ev.results if not r.passed]
    by = {r.name: r for r in ev.results}
    assert by["positions x, y vs RobotModel before the slip"].error < 1e-8
    assert by["ground forces N, T per foot vs RobotModel before the slip"].error < 1e-5
    d = robot_arrays(out)
    o = robot_slip_onset(sc, d, ROOT)
    assert o["event_t"] == pytest.approx(0.344, abs=1e-9)
    assert o["crossing_t"] == pytest.approx(0.34338, abs=1e-5) and o["crossing_foot"] == 1
    assert o["smaller_T_foot"] == 0
    assert [out["contacts"][k] for k in o["released"]] == [foot]
    # a run whose released foot is not the law's fails the check: the other law's output
    other = load_scene("robot_sliding_paper" if law == "lcp" else "robot_sliding", ROOT)
    o2 = robot_slip_onset(other, d, ROOT)
    assert o2["expected"] not in o["released"]


# ---- scenes that start off the stance, set their ground, switch on an event (issue 22 section 3) ----
@pytest.mark.parametrize("name", ["robot_drop_1cm", "robot_throw", "robot_land_switch", "robot_slope_steep",
                                  "robot_fold_stop"])
def test_event_scenes_meet_their_checks_in_legsim_cli(name):
    sc, out, ev = _bench(name)
    assert ev.passed, [(r.name, r.error, r.detail) for r in ev.results if not r.passed]


@pytest.mark.parametrize("name, events", [
    ("robot_drop_1cm", [("right.foot", "touchdown", 0.045152364), ("left.foot", "touchdown", 0.045152364)]),
    ("robot_throw", [("right.foot", "touchdown", 0.164068), ("left.foot", "touchdown", 0.164068),
                     ("left.foot", "stick_to_slip", 0.275231)])])
def test_drops_and_throws_take_each_event_in_the_step_that_holds_it(name, events):
    """What holds today: the start is the reference's (lifted, moving, feet free), every contact
    state and event agrees with the event-locating reference sample by sample, each event in the
    step that holds its exact time (a 1 cm drop lands at sqrt(2 d / g) = 45.152 ms)."""
    from legsim_bench.verdict.analyses import robot_events_reference
    sc, out, ev = _bench(name)
    by = {r.name: r for r in ev.results}
    assert by["contact states vs the event-locating reference, every sample"].passed
    assert by["contact events in the step that holds the reference's"].passed
    d = robot_arrays(out)
    _, r, _ = robot_events_reference(sc, d["t"])
    got = [(sc.model_info.contacts[e.foot], e.kind, e.t) for e in r.events]
    assert [g[:2] for g in got] == [e[:2] for e in events]
    assert [g[2] for g in got] == pytest.approx([e[2] for e in events], abs=1e-6)
    # the start: the stance lifted by [start] lift, both feet free, moving with the box
    assert d["q"][0, 1] - 1.0 == pytest.approx(sc.start["lift"], abs=1e-9)
    assert list(d["state"][0]) == ["free", "free"]
    assert np.max(np.abs(d["q"][0] - r.q[0])) < 1e-9


def test_a_switch_on_a_touchdown_is_the_step_at_its_step(tmp_path):
    """robot_land_switch switches the right upper's set-point when the right foot lands: the
    same run as a step signal at the end of the step whose events hold the touchdown (the switch
    applies from the next step on), to the last bit."""
    out = _run("robot_land_switch")
    d = robot_arrays(out)
    i = next(i for i, e in enumerate(d["events"]) if "touchdown" in e)
    t_td = float(d["t"][i])
    assert t_td == pytest.approx(0.046, abs=1e-12)
    text = (ROOT / "scenes" / "robot_land_switch.toml").read_text()
    text = text.replace('switch = { event = "touchdown", contact = "right.foot", before',
                        f'step = {{ t0 = {t_td!r}, before')
    text = text.split("[checks]")[0] + "[checks]\nresidual = 1e-8\n"
    text = text.replace('model = "../models/robot.toml"', f'model = "{ROOT / "models" / "robot.toml"}"')
    p = tmp_path / "step.toml"
    p.write_text(text)
    r = subprocess.run([str(_cli()), str(p)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    step = robot_arrays(json.loads(r.stdout))
    assert np.array_equal(step["q"], d["q"]) and np.array_equal(step["lengths"], d["lengths"])
    # the switch changed the run from the next step on: robot_drop_1cm is the same drop without it
    drop = robot_arrays(_run("robot_drop_1cm"))
    # (its servo holds the assembled length, the switch's 'before' is that length as written: 1e-11 apart)
    assert np.max(np.abs(drop["q"][:i + 1] - d["q"][:i + 1])) < 1e-9
    assert d["lengths"][-1, 0] - drop["lengths"][-1, 0] > 2e-3


@pytest.mark.parametrize("start, message", [
    ("tilt = 0.2\n", "[start]: contact 'left.foot' would start 0.1058"),
    ("lift = 0.1\n[[contact]]\nname = \"right.foot\"\nstate = \"stuck\"\n",
     "[start]: contact 'right.foot' cannot start stuck: it is 0.1 m above the ground"),
    ("velocity = [0.5, 0.0]\n", "[start]: contact 'right.foot' is on the ground and moving at 0.5 m/s at t = 0: "
                                "give its [[contact]] state (free or sliding)"),
    ("velocity = [0.5, 0.0]\n[[contact]]\nname = \"right.foot\"\nstate = \"stuck\"\n",
     "[start]: contact 'right.foot' cannot start stuck: the start moves it at 0.5 m/s"),
    ("velocity = [0.0, 0.5]\n[[contact]]\nname = \"right.foot\"\nstate = \"sliding\"\n",
     "[start]: contact 'right.foot' cannot start sliding: the start moves it off the line at 0.5 m/s"),
])
def test_a_start_that_cannot_be_honoured_is_refused_not_adjusted(tmp_path, start, message):
    p = tmp_path / "s.toml"
    p.write_text('model = "builtin:robot"\nduration = 0.01\ninit = "hold_length"\n[start]\n' + start)
    r = subprocess.run([str(_cli()), str(p)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and message in r.stderr, r.stderr


def test_feet_start_sliding_along_the_ground_with_the_box():
    """Both feet sliding at t = 0, the robot moving 0.5 m/s along the level ground: the feet
    slide against the motion (|T| = mu_kinetic N) and stick again as it stops."""
    text = ('model = "builtin:robot"\nduration = 0.05\nrecord_every = 1\ninit = "hold_length"\n'
            '[start]\nvelocity = [0.5, 0.0]\n[[contact]]\nname = "right.foot"\nstate = "sliding"\n'
            '[[contact]]\nname = "left.foot"\nstate = "sliding"\n[checks]\nresidual = 1e-8\n')
    r = subprocess.run([str(_cli()), "-", "--as", str(ROOT / "scenes" / "t.toml")], input=text,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    d = robot_arrays(out)
    assert list(d["state"][0]) == ["sliding", "sliding"] and list(d["state"][-1]) == ["stuck", "stuck"]
    slide = (d["state"] == "sliding")
    slide[0] = False   # the first sample's forces are not solved yet
    assert np.abs(d["tangential"][slide]) == pytest.approx(0.5 * d["normal"][slide], rel=1e-9)
    assert np.all(d["tangential"][slide] < 0)   # against the forward slip


def test_a_scene_s_ground_replaces_the_robot_file_s():
    out = _run("robot_slope_steep")
    assert out["ground"] == {"point": [0, 0], "slope": 0.3, "mu_static": 0.2, "mu_kinetic": 0.15}
    sc = load_scene("robot_slope_steep", ROOT)
    assert sc.ground_given and sc.hil_args()[-2:] == ["--ground", "0.3,0.2,0.15"]
    d = robot_arrays(out)
    assert d["q"][0, 2] == pytest.approx(0.3, abs=1e-9) or abs(d["q"][0, 2]) < 1.0   # the stance on the slope
    assert np.all(d["state"][-1] != "free")
