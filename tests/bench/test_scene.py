"""Scene files: the shipped scenes, the schema's rules and the step-grid arithmetic (no CAN)."""
import math
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.scene import (RootNotFound, SceneError, fault_codes, find_root,  # noqa: E402
                                load_scene, parse_scene, resolve_scene, shipped_scenes)

SHIPPED = {"free_fall", "upper_step_50N", "length_sinusoid", "static_hold_300N", "slot_variant",
           "stroke_end", "bad_input"}

BASE = """
variant = "revolute"
integrator = "rk4"
step = 0.001
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
        # every scene checks positions against the reference and the constraints
        assert s.checks.position_m and s.checks.residual, s.name


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
    from legsim_bench.can_link import FaultCode
    assert codes == {f.name: int(f) for f in FaultCode}


def test_defaults_and_grid():
    s = scene()
    assert (s.step_ns, s.n_steps, s.record_every, s.pose, s.init) == (1_000_000, 100, 10, 0, "force_zero")
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
    (("step = 0.001", "step = 0.0010000001"), "whole number of ns"),
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
    (("duration = 0.1", ""), "duration"),
    (("record_every = 10", "record_every = 10\ncmd_timeout_ms = 10"), "command timeout trip"),
])
def test_bad_scenes_are_refused_with_the_key(change, message):
    with pytest.raises(SceneError, match=message):
        scene(BASE.replace(*change, 1))


def test_a_second_command_for_an_actuator_is_refused():
    text = BASE.replace("[checks]", "[[command]]\nactuator = \"upper\"\nmode = \"force\"\nvalue = 1.0\n[checks]")
    with pytest.raises(SceneError, match="second command"):
        scene(text)


@pytest.mark.parametrize("inject, message", [
    ('at = 0.02\nframe = "ACT_CMD"\nexpect = "EXPLODED"', "not a Fault_Code"),
    ('at = 0.02\nframe = "NOPE"\nexpect = "UNKNOWN_ID"', "frame must be"),
    ('at = 0.5\nframe = "ACT_CMD"\nexpect = "NOT_FINITE"', "outside the run"),
    ('at = 0.02\nsilence = 0.01\nexpect = "CMD_TIMEOUT"', "cmd_timeout_ms"),
    ('at = 0.02\nframe = "ACT_CMD"\nlength = 33\nexpect = "BAD_LENGTH"', "payload length"),
    ('at = 0.02\nframe = 0x123\nseq = "stale"\nexpect = "UNKNOWN_ID"', "stale"),
    ('at = 0.02\nframe = "ACT_CMD"', "expect"),
])
def test_bad_injections_are_refused(inject, message):
    with pytest.raises(SceneError, match=message):
        scene(BASE + "\n[[inject]]\n" + inject + "\n")


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
    with pytest.raises(SceneError, match="not valid TOML"):
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
    text = BASE.replace("step = 0.001", f"step = {h_us * 1e-6!r}").replace(
        "duration = 0.1", f"duration = {n * h_us * 1e-6!r}").replace("record_every = 10", f"record_every = {every}")
    s = scene(text)
    b = s.boundaries()
    assert s.n_steps == n and b[0] == 0 and all(0 < b2 - b1 <= every for b1, b2 in zip(b, b[1:]))
    assert 0 < n - b[-1] <= every
