"""Scene files: the shipped scenes, the schema's rules and the step-grid arithmetic (no CAN).
legsim_cli is the one reader: the bench's Scene is built from its --check JSON and its
refusals are legsim_cli's words; a scene with its own model file."""
import json
import tomllib
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from built import legsim_cli
from hypothesis import given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.scene import (RootNotFound, SceneError, StrokeCheck, fault_codes, find_root,  # noqa: E402
                                load_scene, parse_scene, resolve_scene, shipped_scenes)

SHIPPED = {"free_fall", "upper_step_50N", "length_sinusoid", "static_hold_300N", "slot_variant",
           "stroke_end", "bad_input", "statics_foot_300N", "builtin_leg_statics", "statics_sweep",
           "inverse_dynamics_sinusoid", "assembly_lengths"}
FIXTURES = ROOT / "tests" / "hil_scenes" / "fixtures"      # a leg with a 2 kg heavier shank
BAD = ROOT / "tests" / "model" / "fixtures" / "scenes"      # legsim_cli's bad scenes

BASE = """
variant = "revolute"
integrator = "rk4"
step_s = 0.001
duration = 0.1
record_every = 10
[[command]]
actuator = "upper"
mode = "force"
value = 0.0
[checks]
position_m = 1e-5
"""


def scene(text=BASE, **kw):
    return parse_scene(text, name="t", root=ROOT, **kw)


def test_root_is_found_from_the_package_and_from_the_env(monkeypatch, tmp_path):
    monkeypatch.delenv("LEGSIM_ROOT", raising=False)
    assert find_root() == ROOT
    monkeypatch.setenv("LEGSIM_ROOT", str(ROOT))
    assert find_root() == ROOT
    monkeypatch.setenv("LEGSIM_ROOT", str(tmp_path))
    with pytest.raises(RootNotFound, match="LEGSIM_ROOT"):
        find_root()
    monkeypatch.delenv("LEGSIM_ROOT")
    with pytest.raises(RootNotFound, match="LEGSIM_ROOT"):
        find_root(tmp_path)


def test_every_shipped_scene_parses_and_one_is_the_demo():
    paths = shipped_scenes(ROOT)
    names = {p.stem for p in paths}
    assert SHIPPED <= names
    scenes = [load_scene(p, ROOT) for p in paths]
    assert len({s.name for s in scenes}) == len(scenes)
    demos = [s.name for s in scenes if s.demo]
    assert demos == ["upper_step_50N"]
    assert resolve_scene("demo", ROOT).stem == "upper_step_50N"
    for s in scenes:
        assert s.description
        assert s.checks.tolerances(), s.name
        # every scene but the sweep checks positions against the reference and the constraints;
        # a robot scene whose feet must slip has no reference (RobotModel's feet are stuck):
        # it checks the constraints and the slips
        if s.checks.slips is not None:
            assert s.robot and s.checks.slips and s.checks.residual, s.name
        elif s.robot and s.analysis == "dynamics" and not s.checks.events and s.checks.position_m is None:
            # the stops and the crouch: the run's own invariants (no reference holds them)
            assert s.checks.in_stroke_m and s.checks.residual, s.name
        elif s.analysis != "statics_sweep":
            assert s.checks.position_m and s.checks.residual, s.name
    assert {s.analysis for s in scenes} == {"dynamics", "statics", "statics_sweep", "inverse_dynamics",
                                             "assembly"}


def test_shipped_scenes_say_what_the_issue_asks():
    sc = {p.stem: load_scene(p, ROOT) for p in shipped_scenes(ROOT)}
    ff = sc["free_fall"]
    assert all(c.mode == "force" and c.schedule.value == 0 for c in ff.commands)
    step = sc["upper_step_50N"].commands[0]
    assert (step.mode, step.schedule.kind, step.schedule.after - step.schedule.before) == ("force", "step", 50.0)
    assert all(c.schedule.kind == "sinusoid" for c in sc["length_sinusoid"].commands)
    hold = sc["static_hold_300N"]
    assert hold.foot_load == (0.0, 300.0)
    assert hold.checks.balance_n and hold.checks.stays_put_m and hold.checks.statics_force_n
    assert sc["slot_variant"].variant == "slot"
    assert sc["stroke_end"].checks.stroke is not None and sc["stroke_end"].checks.compare == "until_stroke"
    bad = sc["bad_input"]
    expects = {i.expect for i in bad.injections}
    assert {"NOT_FINITE", "OUT_OF_RANGE", "STALE_SEQ", "CMD_TIMEOUT"} <= expects
    assert any(i.is_silence for i in bad.injections) and bad.cmd_timeout_ms > 0
    assert any(isinstance(v, float) and math.isnan(v) for i in bad.injections for v in i.signals.values())


def test_fault_codes_come_from_the_dbc():
    codes = fault_codes(ROOT / "can" / "legsim.dbc")
    assert codes["NONE"] == 0 and codes["NOT_FINITE"] == 3 and codes["CMD_TIMEOUT"] == 7
    from legsim_bench.hil.can_link import FaultCode
    assert codes == {f.name: int(f) for f in FaultCode}
    # legsim_cli's [[inject]] expect names are the DBC's, in the DBC's order of values
    with pytest.raises(SceneError) as e:
        scene(BASE + '\n[[inject]]\nat = 0.02\nframe = "ACT_CMD"\nexpect = "EXPLODED"\n')
    listed = re.search(r"is not a Fault_Code of the DBC \((.*)\)", str(e.value)).group(1).split(", ")
    assert listed == sorted(codes, key=codes.get)


def test_injected_frames_are_the_dbc_s():
    """The frames an injection may name, and their ids, are the DBC's bench -> hil_sim frames."""
    cantools = pytest.importorskip("cantools")
    db = cantools.database.load_file(str(ROOT / "can" / "legsim.dbc"))
    for name in ("CONTROL", "ACT_CMD", "LOAD_CMD"):
        sc = scene(BASE + f'\n[[inject]]\nat = 0.02\nframe = "{name.lower()}"\nexpect = "NOT_FINITE"\n')
        inj = sc.injections[0]
        assert (inj.frame, inj.frame_id) == (name, db.get_message_by_name(name).frame_id)


def test_defaults_and_grid():
    s = scene()
    assert (s.step_ns, s.n_steps, s.record_every, s.pose, s.init) == (1_000_000, 100, 10, 0, "zero_force")
    d = scene("duration = 0.1\n")
    assert (d.analysis, d.step_ns, d.record_every, d.pose_name, d.init, d.safe_state, d.model) == \
        ("dynamics", 1_000_000, 1, "stand", "zero_force", "zero_force", "builtin:leg")
    assert d.checks.tolerances() == {"position_m": 1e-5, "angle_rad": 1e-5, "reaction_n": 0.01,
                                     "moment_nm": 1e-3, "actuator_force_n": 0.01, "residual": 1e-6}
    assert s.boundaries() == list(range(0, 100, 10))
    assert s.commands[1] is None
    assert s.setpoints(0) == [("force", 0.0), None]
    assert s.cmd_timeout_ms == 0 and s.disable_bits == 0


def test_step_breakpoints_and_injections_become_boundaries():
    text = BASE.replace("value = 0.0", "step = { t0 = 0.025, after = 50.0 }").replace(
        "record_every = 10", "record_every = 10\ncmd_timeout_ms = 20")
    text += """
[[inject]]
at = 0.033
frame = "ACT_CMD"
signals = { Act_Mode_upper = 1, Act_Setpoint_upper = nan }
expect = "NOT_FINITE"
expect_signal = "Act_Setpoint_upper"
[[inject]]
at = 0.05
silence = 0.02
expect = "CMD_TIMEOUT"
"""
    s = scene(text)
    b = s.boundaries()
    assert {25, 33, 50, 70} <= set(b) and b == sorted(b) and b[0] == 0 and b[-1] < s.n_steps
    assert s.setpoints(24)[0] == ("force", 0.0) and s.setpoints(25)[0] == ("force", 50.0)
    assert [i.step for i in s.injections] == [33, 50]
    assert s.injections[0].expect_signal == "Act_Setpoint_upper"
    assert math.isnan(s.injections[0].signals["Act_Setpoint_upper"])
    assert s.silent(50) and s.silent(69) and not s.silent(70) and not s.silent(49)


@pytest.mark.parametrize("change, message", [
    (("variant = \"revolute\"", "variant = \"hinge\""), "variant"),
    (("step_s = 0.001", "step_s = 0.0010000001"), "whole number of ns"),
    (("duration = 0.1", "duration = 0.1005"), "not a whole number of steps"),
    (("mode = \"force\"", "mode = \"torque\""), "mode"),
    (("value = 0.0", "value = 2000.0"), "max_force"),
    (("mode = \"force\"\nvalue = 0.0", "mode = \"length\"\nvalue = 0.9"), "stroke"),
    (("value = 0.0", "value = \"initial\""), "initial"),
    (("value = 0.0", "value = 0.0\nstep = { t0 = 0.01, after = 1.0 }"), "exactly one"),
    (("value = 0.0", "step = { t0 = 0.0105, after = 1.0 }"), "step grid"),
    (("record_every = 10", "record_every = 10\ncolour = 3"), "unknown key"),
    (("position_m = 1e-5", "position_mm = 1e-5"), "unknown key"),
    (("position_m = 1e-5", "position_m = -1.0"), "> 0"),
    (("position_m = 1e-5", ""), "nothing to check"),
    (("record_every = 10", "record_every = 10\npose = \"crouch\""), "pose"),
    (("record_every = 10", "record_every = 10\nrho_inf = 0.5"), "RESET carries no solver options"),
    (("record_every = 10", "record_every = 10\ngrid = 5"), "applies to statics_sweep only"),
    (("integrator = \"rk4\"", "analysis = \"statics\""), "'duration' applies to dynamics"),
    (("duration = 0.1", ""), "duration"),
    (("record_every = 10", "record_every = 10\ncmd_timeout_ms = 10"), "command timeout trip"),
])
def test_bad_scenes_are_refused_with_the_key(change, message):
    with pytest.raises(SceneError, match=message):
        scene(BASE.replace(*change, 1))


ROBOT = 'model = "builtin:robot"\nduration = 0.1\nrecord_every = 1\n'


@pytest.mark.parametrize("text, message", [
    # [start]: every number in its documented range (scenes/README.md), its keys, where it applies
    ("[start]\nlift = -0.01\n", "[start] 'lift' must be in [0, 10] m (got -0.01)"),
    ("[start]\nlift = 10.5\n", "[start] 'lift' must be in [0, 10] m (got 10.5)"),
    ("[start]\ntilt = 1.6\n", "[start] 'tilt' must be in [-1.5, 1.5] rad (got 1.6)"),
    ("[start]\ntilt = nan\n", "[start] 'tilt' is not finite"),
    ("[start]\nvelocity = [0.0, 101.0]\n", "[start] 'velocity' must be within +-100 m/s (got 101)"),
    ("[start]\nvelocity = [1.0]\n", "[start] 'velocity' must be [vx, vy] (m/s, world axes)"),
    ("[start]\nspin = -100.5\n", "[start] 'spin' must be within +-100 rad/s (got -100.5)"),
    ("[start]\nheight = 1.0\n", "[start] unknown key 'height' (allowed: lift, spin, tilt, velocity)"),
    ("start = 1.0\n", "'start' must be a table ([start] lift, tilt, velocity, spin)"),
    ('analysis = "inverse_dynamics"\n[start]\nlift = 0.1\n', "'start' applies to dynamics only"),
    # [ground]
    ("[ground]\nslope = 1.51\n", "[ground] 'slope' must be in [-1.5, 1.5] rad (got 1.51)"),
    ("[ground]\nmu_static = -0.1\n", "[ground] 'mu_static' must be in [0, 10] (got -0.1)"),
    ("[ground]\nmu_kinetic = 10.5\n", "[ground] 'mu_kinetic' must be in [0, 10] (got 10.5)"),
    ("[ground]\nmu_static = 0.3\nmu_kinetic = 0.4\n", "[ground] 'mu_kinetic' 0.4 must be at most 'mu_static' 0.3"),
    ("[ground]\nmu_kinetic = 0.7\n", "[ground]: mu_kinetic 0.7 must be at most mu_static 0.6 (with the model's own"),
    ("[ground]\npoint = [0.0, 1.0]\n", "[ground] unknown key 'point' (allowed: mu_kinetic, mu_static, slope)"),
    # a switch on a contact event
    ('[[command]]\nactuator = "right.upper"\nmode = "force"\n'
     'switch = { event = "landing", contact = "right.foot", after = 1.0 }\n',
     "switch: 'event' must be touchdown, liftoff, stick_to_slip, slip_to_stick (got 'landing')"),
    ('[[command]]\nactuator = "right.upper"\nmode = "force"\n'
     'switch = { event = "touchdown", contact = "middle.foot", after = 1.0 }\n',
     "switch: 'contact' must be a contact of the model (right.foot, left.foot; got 'middle.foot')"),
    ('[[command]]\nactuator = "right.upper"\nmode = "force"\n'
     'switch = { event = "touchdown", contact = "right.foot", after = 2000.0 }\n', "exceed max_force 1500 N"),
    ('[[command]]\nactuator = "right.upper"\nmode = "length"\n'
     'switch = { event = "touchdown", contact = "right.foot", before = 0.6, after = 0.3 }\n', "leave the stroke"),
    ('[[command]]\nactuator = "right.upper"\nmode = "force"\n'
     'switch = { event = "touchdown", contact = "right.foot", at = 0.1, after = 1.0 }\n', "switch: unknown key 'at'"),
    ('#\n[[command]]\nactuator = "right.upper"\nmode = "force"\n'
     'switch = { event = "touchdown", contact = "right.foot", after = 1.0 }\n', "'switch' needs record_every = 1"),
    ('[[command]]\nactuator = "right.upper"\nmode = "force"\nvalue = 1.0\n'
     'switch = { event = "touchdown", contact = "right.foot", after = 1.0 }\n',
     "give exactly one of 'value', 'sinusoid', 'step' or 'switch'"),
    # a foot that starts sliding, the checks of a start off the stance
    ('[[contact]]\nname = "right.foot"\nstate = "sliding"\n', "a foot starts sliding only in dynamics with a [start]"),
    ('[[contact]]\nname = "right.foot"\nstate = "rolling"\n', "'state' must be stuck, free or sliding (got 'rolling')"),
    ("[start]\nlift = 0.1\n[checks]\nposition_m = 1e-6\n", "add events = true"),
    ("[checks]\nevents = false\nresidual = 1e-8\n", "[checks] 'events' must be true"),
    ("[checks]\nevents = true\nslips = [\"left.foot\"]\n", "events compare with RobotModel's stance on stuck feet, which 'slips' leaves"),
    ("[checks]\nevents = true\nstays_put_m = 1e-3\n", "stays_put_m do not go with 'events'"),
    ('[[command]]\nactuator = "right.upper"\nmode = "force"\nstep = { t0 = 0.05, after = 1.0 }\n'
     "[checks]\nevents = true\n", "changes with time; the event-locating reference takes constant commands"),
    ("[checks]\nin_stroke_m = 0.0\n", "[checks] 'in_stroke_m' must be > 0 (got 0)"),
])
def test_robot_start_ground_and_switch_keys_are_refused_with_their_range(text, message):
    """The keys of a robot scene's start, ground and event switches: every value out of its
    documented range refused by the one reader (legsim_cli), the message naming key, value
    and range."""
    with pytest.raises(SceneError) as e:
        scene((ROBOT + text).replace("record_every = 1\n#\n", "record_every = 2\n"))   # '#': every 2 steps
    assert message in str(e.value)


@pytest.mark.parametrize("text, message", [
    ("[start]\nlift = 0.1\n", "[start] applies to a model with contacts only (the robot's box)"),
    ("[ground]\nslope = 0.1\n", "[ground] applies to a model with contacts only (the robot's ground)"),
])
def test_start_and_ground_are_the_robot_s(text, message):
    with pytest.raises(SceneError) as e:
        scene(BASE.replace("[[command]]", text + "[[command]]", 1).replace("[checks]\nposition_m = 1e-5", ""))
    assert message in str(e.value)


def test_start_ground_and_switch_reach_the_bench_as_written():
    sc = scene(ROBOT + "[start]\nlift = 0.02\ntilt = 0.1\nvelocity = [1.0, -0.5]\nspin = 2.0\n"
               "[ground]\nslope = 0.2\nmu_static = 0.7\n"
               '[[contact]]\nname = "left.foot"\nstate = "free"\n'
               '[[command]]\nactuator = "right.upper"\nmode = "force"\n'
               'switch = { event = "touchdown", contact = "right.foot", before = 5.0, after = 50.0 }\n'
               "[checks]\nevents = true\nin_stroke_m = 1e-9\n")
    assert sc.start == {"lift": 0.02, "tilt": 0.1, "velocity": [1.0, -0.5], "spin": 2.0}
    assert sc.ground == {"point": [0, 0], "slope": 0.2, "mu_static": 0.7, "mu_kinetic": 0.5} and sc.ground_given
    assert sc.hil_args() == ["--robot", "--ground", "0.2,0.7,0.5"]
    assert sc.contacts == {"left.foot": "free"} and sc.checks.events and sc.checks.in_stroke_m == 1e-9
    c = sc.commands[0]
    assert (c.schedule.kind, c.schedule.event, c.schedule.contact) == ("switch", "touchdown", "right.foot")
    assert sc.setpoints(3)[0] == ("force", 5.0)
    assert sc.setpoints(3, fired={("right.foot", "touchdown")})[0] == ("force", 50.0)
    assert sc.setpoints(3, fired={("left.foot", "touchdown")})[0] == ("force", 5.0)
    plain = scene(ROBOT)
    assert plain.start is None and not plain.ground_given and plain.hil_args() == ["--robot"]


def test_a_second_command_for_an_actuator_is_refused():
    text = BASE.replace("[checks]", "[[command]]\nactuator = \"upper\"\nmode = \"force\"\nvalue = 1.0\n[checks]")
    with pytest.raises(SceneError, match="second command"):
        scene(text)


@pytest.mark.parametrize("inject, message", [
    ('at = 0.02\nframe = "ACT_CMD"\nexpect = "EXPLODED"', "inject #1: 'expect' = 'EXPLODED' is not a Fault_Code "
                                                          "of the DBC (NONE, UNKNOWN_ID, "),
    ('at = 0.02\nframe = "NOPE"\nexpect = "UNKNOWN_ID"', "inject #1: 'frame' must be CONTROL, ACT_CMD, LOAD_CMD "
                                                        "or an 11-bit id (got 'NOPE')"),
    ('at = 0.02\nframe = 0x800\nexpect = "UNKNOWN_ID"', "'frame' must be a DBC message name"),
    ('at = 0.5\nframe = "ACT_CMD"\nexpect = "NOT_FINITE"', "inject #1: 'at' = 0.5 s is outside the run (0 .. 0.1 s)"),
    ('at = 0.0205\nframe = "ACT_CMD"\nexpect = "NOT_FINITE"', "'at' = 0.0205 s is not on the step grid"),
    ('at = 0.02\nsilence = 0.01\nexpect = "CMD_TIMEOUT"', "inject #1: a silence needs cmd_timeout_ms > 0"),
    ('at = 0.02\nsilence = -0.01\nexpect = "CMD_TIMEOUT"', "'silence' must be > 0 (s; got -0.01)"),
    ('at = 0.02\nsilence = 0.01\nframe = "ACT_CMD"\nexpect = "CMD_TIMEOUT"', "give 'frame' or 'silence', not both"),
    ('at = 0.02\nframe = "ACT_CMD"\nlength = 33\nexpect = "BAD_LENGTH"',
     "'length' must be a CAN FD payload length (0..8, 12, 16, 20, 24, 32, 48 or 64; got 33)"),
    ('at = 0.02\nframe = "ACT_CMD"\nlength = 65\nexpect = "BAD_LENGTH"', "'length' must be in 0..64 (got 65)"),
    ('at = 0.02\nframe = 0x123\nseq = "stale"\nexpect = "UNKNOWN_ID"', 'seq = "stale" needs a DBC frame'),
    ('at = 0.02\nframe = "ACT_CMD"\nseq = "old"\nexpect = "STALE_SEQ"', "'seq' must be \"next\", \"stale\" or a 32-bit"),
    ('at = 0.02\nframe = "ACT_CMD"\nsignals = { Act_Mode_upper = "x" }\nexpect = "OUT_OF_RANGE"',
     "signal 'Act_Mode_upper' must be a number (nan and inf allowed)"),
    ('at = 0.02\nframe = "ACT_CMD"\ncolour = 1\nexpect = "OUT_OF_RANGE"', "inject #1: unknown key 'colour'"),
    ('at = 0.02\nframe = "ACT_CMD"', "inject #1: needs 'at' (s) and 'expect' (a Fault_Code name)"),
])
def test_bad_injections_are_refused(inject, message):
    with pytest.raises(SceneError) as e:
        scene(BASE + "\n[[inject]]\n" + inject + "\n")
    assert message in str(e.value)


@pytest.mark.parametrize("checks, message", [
    ("position_m = -1.0", "t: [checks] 'position_m' must be > 0 (got -1)"),
    ("position_m = nan", "[checks] 'position_m' is not finite"),
    ('position_m = "small"', "[checks] 'position_m' must be a number"),
    ("resolution_ratio = 0.0\nposition_m = 1e-5", "[checks] 'resolution_ratio' must be > 0 (got 0)"),
    ('compare = "some"\nposition_m = 1e-5', "'compare' must be all or until_stroke (got 'some')"),
    ('stroke = { actuator = "upper", end = "middle" }', "[checks.stroke] 'end' must be min or max (got 'middle')"),
    ('stroke = { actuator = "knee", end = "max" }',
     "[checks.stroke] 'actuator' must be an actuator of the model (upper, lower; got 'knee')"),
    ('stroke = { actuator = "upper", end = "max", tolerance_m = 0.0 }', "'tolerance_m' must be > 0 (got 0)"),
    ('stroke = { actuator = "upper", end = "max", colour = 1 }', "[checks.stroke] unknown key 'colour'"),
    ("ground_force_n = 1.0", "[checks] (dynamics): unknown key 'ground_force_n' (allowed: actuator_force_n, "),
    ("", "t: [checks] names nothing to check"),
])
def test_bad_checks_are_refused(checks, message):
    with pytest.raises(SceneError) as e:
        scene(BASE.replace("position_m = 1e-5", checks))
    assert message in str(e.value)


def test_a_stroke_check_or_an_injection_is_something_to_check():
    sc = scene(BASE.replace("position_m = 1e-5", 'stroke = { actuator = "lower", end = "min" }'))
    assert sc.checks.stroke == StrokeCheck(1, "min", 1e-6) and not sc.checks.tolerances()
    sc = scene(BASE.replace("position_m = 1e-5", "") + '[[inject]]\nat = 0.02\nframe = "ACT_CMD"\nexpect = "not_finite"\n')
    assert [(i.step, i.expect, i.frame, i.frame_id, i.seq, i.length) for i in sc.injections] == \
        [(20, "NOT_FINITE", "ACT_CMD", 0x100, "next", 64)]


def test_scene_names_resolve_and_unknown_ones_say_what_exists(tmp_path):
    assert resolve_scene("free_fall", ROOT).name == "free_fall.toml"
    assert resolve_scene("FREE_FALL", ROOT).name == "free_fall.toml"
    p = tmp_path / "mine.toml"
    p.write_text(BASE)
    assert load_scene(p, ROOT).name == "mine"
    with pytest.raises(SceneError, match="free_fall"):
        resolve_scene("no_such_scene", ROOT)
    with pytest.raises(SceneError, match="no such scene file"):
        resolve_scene(tmp_path / "missing.toml", ROOT)
    bad = tmp_path / "bad.toml"
    bad.write_text("duration = [")
    with pytest.raises(SceneError, match="bad.toml: TOML syntax error"):
        load_scene(bad, ROOT)


@settings(max_examples=50, deadline=None)
@given(t=st.floats(0, 2), offset=st.floats(0.45, 0.75), amp=st.floats(0, 0.04),
       f=st.floats(0.1, 10), phase=st.floats(-3.2, 3.2))
def test_sinusoid_schedule(t, offset, amp, f, phase):
    s = scene(BASE.replace("mode = \"force\"\nvalue = 0.0",
                           f"mode = \"length\"\nsinusoid = {{ offset = {offset!r}, amplitude = {amp!r}, "
                           f"frequency = {f!r}, phase = {phase!r} }}"))
    sch = s.commands[0].schedule
    assert sch(t) == pytest.approx(offset + amp * math.sin(2 * math.pi * f * t + phase), abs=1e-12)
    lo, hi = sch.extremes()
    assert lo - 1e-12 <= sch(t) <= hi + 1e-12


@settings(max_examples=50, deadline=None)
@given(h_us=st.integers(10, 5000), n=st.integers(1, 3000), every=st.integers(1, 200))
def test_boundaries_cover_the_run(h_us, n, every):
    text = BASE.replace("step_s = 0.001", f"step_s = {h_us * 1e-6!r}").replace(
        "duration = 0.1", f"duration = {n * h_us * 1e-6!r}").replace("record_every = 10", f"record_every = {every}")
    s = scene(text)
    b = s.boundaries()
    assert s.n_steps == n and b[0] == 0 and all(0 < b2 - b1 <= every for b1, b2 in zip(b, b[1:]))
    assert 0 < n - b[-1] <= every


# ---- the one schema, from both sides -------------------------------------------------------


def _cli_check(path):
    r = subprocess.run([str(legsim_cli()), str(path), "--check"], capture_output=True, text=True, timeout=60)
    return r.returncode, (json.loads(r.stdout) if r.returncode == 0 else None), r.stderr


# the bench's scenes: a hexapod's are legsim_cli's only (tests/bench/test_hexapod_scenes.py)
SCENE_FILES = shipped_scenes(ROOT) + sorted(FIXTURES.glob("*.toml"))


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.stem)
def test_the_scene_is_built_from_legsim_cli_s_resolved_scene(path):
    """Every scene file: the bench's Scene holds the values legsim_cli --check printed (step,
    duration in steps, record interval, pose, commands, options), and [checks] as written."""
    rc, cli, err = _cli_check(path)
    assert rc == 0, err
    sc = load_scene(path, ROOT)
    assert sc.resolved() == cli
    assert (sc.name, sc.analysis, sc.variant, sc.integrator, sc.step_ns, sc.n_steps, sc.record_every) == \
        (cli["name"], cli["analysis"], cli["variant"], cli["integrator"], cli["step_ns"], cli["n_steps"],
         cli["record_every"])
    assert sc.pose_name == cli["pose"] and sc.model_info.poses[sc.pose] == cli["pose"]
    assert {c.name: c.mode for c in sc.commands if c is not None} == {k: v["mode"] for k, v in cli["commands"].items()}
    assert (sc.rho_inf, sc.max_newton_iter, sc.newton_tol, sc.disable_bits) == \
        (cli["rho_inf"], cli["max_newton_iter"], cli["newton_tol"], cli["disable"])
    assert cli["checks"] == tomllib.loads(path.read_text()).get("checks")
    assert len(sc.injections) == len(cli["inject"])


def test_check_resolves_the_injections():
    """bad_input's [[inject]]: steps, frame ids of the DBC, fault names, and non-finite values
    as strings (JSON has neither nan nor inf), read back as floats."""
    rc, cli, err = _cli_check(ROOT / "scenes" / "bad_input.toml")
    assert rc == 0, err
    signals = [x["signals"] for x in cli["inject"] if "signals" in x]
    assert signals[0]["Act_Setpoint_upper"] == "nan" and signals[1]["Load_Value2"] == "inf"
    assert [x["step"] for x in cli["inject"]] == sorted(x["step"] for x in cli["inject"])
    first = cli["inject"][0]
    assert (first["step"], first["frame"], first["frame_id"], first["expect"], first["length"]) == \
        (20, "ACT_CMD", 0x100, "NOT_FINITE", 64)
    silence = next(x for x in cli["inject"] if "silence_steps" in x)
    assert (silence["step"], silence["silence_steps"], silence["expect"]) == (200, 100, "CMD_TIMEOUT")
    sc = load_scene(ROOT / "scenes" / "bad_input.toml", ROOT)
    assert math.isnan(sc.injections[0].signals["Act_Setpoint_upper"])
    assert sc.injections[1].signals["Load_Value2"] == math.inf


def _expected_messages():
    rows = [line.rstrip("\n").split("\t") for line in (BAD / "expected.tsv").read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    return [(name, texts[0]) for name, code, *texts in rows if code == "2"]


@pytest.mark.parametrize("name, text", _expected_messages(), ids=lambda v: str(v)[:40])
def test_the_bench_refuses_a_bad_scene_in_legsim_cli_s_words(name, text):
    """Every bad scene legsim_cli refuses (tests/model/fixtures/scenes/expected.tsv: old keys
    naming the new one, off-grid times, limits, bad checks and injections) is the bench's
    SceneError with legsim_cli's message."""
    with pytest.raises(SceneError) as e:
        load_scene(BAD / name, ROOT)
    assert text in str(e.value)


def test_a_scene_read_from_text_is_read_as_its_file():
    """parse_scene hands legsim_cli the text as if it were the file: its name, its folder for a
    relative model path, the messages naming it."""
    text = (FIXTURES / "heavy_shank_statics.toml").read_text()
    sc = parse_scene(text, FIXTURES / "copy.toml", root=ROOT)
    assert sc.model_path == FIXTURES / "models" / "heavy_shank.toml" and sc.source == text
    assert sc.resolved() == dict(load_scene(FIXTURES / "heavy_shank_statics.toml", ROOT).resolved(),
                                 scene=str(FIXTURES / "copy.toml"), name=sc.name)
    with pytest.raises(SceneError, match=re.escape("copy.toml: 'analysis' must be")):
        parse_scene('analysis = "kinematics"\n', FIXTURES / "copy.toml", root=ROOT)
    with pytest.raises(SceneError, match="TOML input refused"):
        parse_scene("# " + "x" * (1 << 20) + "\n", name="big", root=ROOT)


def test_recordings_carry_the_resolved_scene(tmp_path):
    """A recording's scene comes back from its resolved JSON, without the TOML; an old one
    (no scene_resolved) has its TOML read by legsim_cli; one with neither says so."""
    from legsim_bench.recording import RecordingError, load_recording, save_recording, scene_of
    sc = load_scene("bad_input", ROOT)
    rec = {"format": "legsim-bench-recording/1", "scene_name": sc.name, "scene_path": str(sc.path),
           "scene_source": sc.source, "scene_resolved": sc.resolved()}
    back = scene_of(load_recording(save_recording(rec, tmp_path / "r.json")), ROOT)
    assert back.resolved() == sc.resolved() and back.checks == sc.checks
    assert [repr(i) for i in back.injections] == [repr(i) for i in sc.injections]   # nan != nan
    # the TOML is not read again: a recording whose text was lost still gives its scene
    assert scene_of(dict(rec, scene_source="not toml at all ["), ROOT).boundaries() == sc.boundaries()
    old = {k: v for k, v in rec.items() if k != "scene_resolved"}
    assert scene_of(old, ROOT).resolved() == sc.resolved()
    with pytest.raises(RecordingError, match="carries no scene"):
        scene_of({"format": "legsim-bench-recording/1"}, ROOT)
    with pytest.raises(RecordingError, match="scene_resolved"):
        scene_of(dict(rec, scene_resolved={"name": "x"}), ROOT)


def test_old_keys_name_the_new_one():
    for old, new in (("output_every = 5", "record_every"), ("decimation = 5", "record_every"),
                     ("step = 0.001", "step_s"), ("foot_load = [0.0, 1.0]", "[forces] foot_load")):
        with pytest.raises(SceneError, match=re.escape(new)):
            scene("duration = 0.1\n" + old + "\n")
    with pytest.raises(SceneError, match='init = "zero_force"'):
        scene('duration = 0.1\ninit = "force_zero"\n')
    with pytest.raises(SceneError, match='safe_state = "hold_length"'):
        scene('duration = 0.1\nsafe_state = "hold-length"\n')


def test_checks_that_do_not_apply_to_the_analysis_are_refused():
    with pytest.raises(SceneError, match="unknown key.*stays_put_m"):
        scene('analysis = "statics"\n[checks]\nstays_put_m = 1e-6\n')
    with pytest.raises(SceneError, match="revolute knee only"):
        scene('analysis = "statics"\nvariant = "slot"\n')


def test_a_scene_with_its_own_model_file_resolves_it_next_to_the_scene():
    sc = load_scene(FIXTURES / "heavy_shank_free_fall.toml", ROOT)
    assert sc.model_path == FIXTURES / "models" / "heavy_shank.toml" and not sc.builtin_model
    assert sc.hil_args() == ["--model", str(FIXTURES / "models" / "heavy_shank.toml")]
    assert load_scene("free_fall", ROOT).hil_args() == []
    with pytest.raises(SceneError, match="cannot read"):
        parse_scene('model = "nowhere.toml"\nduration = 0.1\n', FIXTURES / "x.toml", root=ROOT)


def _cli_json(path):
    r = subprocess.run([str(legsim_cli()), str(path)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_the_heavy_shank_changes_statics_as_its_weight_on_the_foot_line_says(tmp_path):
    """In the stand pose the shank hangs vertical: its 2 kg extra weight acts on the foot's
    vertical line, so the heavy-shank leg's statics equal the stock leg's with 19.62 N down on
    the foot; and they differ from the stock leg's without it by that load's share."""
    heavy = _cli_json(FIXTURES / "heavy_shank_statics.toml")["samples"][0]
    loaded = _cli_json(FIXTURES / "stock_leg_foot_load_19N.toml")["samples"][0]
    for a in ("upper", "lower"):
        assert heavy["actuators"][a]["force"] == pytest.approx(loaded["actuators"][a]["force"], abs=1e-9)
    for j, r in heavy["reactions"].items():
        for k in ("fx", "fy", "moment"):
            assert r[k] == pytest.approx(loaded["reactions"][j][k], abs=1e-9)
    p = tmp_path / "stock_statics.toml"
    p.write_text('analysis = "statics"\n')
    plain = _cli_json(p)["samples"][0]
    du = heavy["actuators"]["upper"]["force"] - plain["actuators"]["upper"]["force"]
    assert du < -1.0   # the heavier shank pulls the thigh down: the upper actuator pulls harder


def test_the_bench_runs_a_statics_scene_of_its_own_model_in_legsim_cli_and_checks_it():
    from legsim_bench.verdict.checks import evaluate
    from legsim_bench.hil.runner import record
    legsim_cli()
    sc = load_scene(FIXTURES / "heavy_shank_statics.toml", ROOT)
    assert not sc.over_can
    rec = record(sc, link=None)
    assert rec["complete"] and rec["runner"] == "legsim_cli", rec["errors"]
    ev = evaluate(rec, ROOT)
    assert ev.passed, [(r.name, r.error, r.detail) for r in ev.results]
    names = {r.name for r in ev.results}
    assert "actuator forces vs reference statics" in names and "reactions vs reference statics" in names
    # against the stock leg's reference the same numbers fail: the check sees the model
    stock = parse_scene(sc.source.replace('model = "models/heavy_shank.toml"\n', ""), FIXTURES / "x.toml", root=ROOT)
    ev2 = evaluate(rec, ROOT, scene=stock)
    assert not ev2.passed
