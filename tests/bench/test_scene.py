"""Scene files: the shipped scenes, the schema's rules and the step-grid arithmetic (no CAN);
the one schema from both sides (legsim_cli --check and the bench's reader agree on every file
of scenes/, refuse the same files with the same words), a scene with its own model file."""
import json
import tomllib
import math
import os
import re
import subprocess
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
    text = BASE.replace("step_s = 0.001", f"step_s = {h_us * 1e-6!r}").replace(
        "duration = 0.1", f"duration = {n * h_us * 1e-6!r}").replace("record_every = 10", f"record_every = {every}")
    s = scene(text)
    b = s.boundaries()
    assert s.n_steps == n and b[0] == 0 and all(0 < b2 - b1 <= every for b1, b2 in zip(b, b[1:]))
    assert 0 < n - b[-1] <= every


# ---- the one schema, from both sides -------------------------------------------------------

def _cli():
    from legsim_bench.scene import cli_path
    p = cli_path(ROOT)
    if not p.is_file():
        pytest.skip(f"{p} not built (cmake --build --preset host --target legsim_cli, or LEGSIM_CLI)")
    return p


def _cli_check(path):
    r = subprocess.run([str(_cli()), str(path), "--check"], capture_output=True, text=True, timeout=60)
    return r.returncode, (json.loads(r.stdout) if r.returncode == 0 else None), r.stderr


SCENE_FILES = sorted(ROOT.glob("scenes/*.toml")) + sorted(FIXTURES.glob("*.toml"))


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.stem)
def test_both_readers_resolve_every_scene_the_same(path):
    """Step size, duration (steps), record interval, pose, loads, commands, options: legsim_cli
    --check and the bench's reader give the same values for the same file."""
    rc, cli, err = _cli_check(path)
    assert rc == 0, err
    bench = load_scene(path, ROOT).resolved()
    for r in (cli, bench):
        r["model_path"] = os.path.realpath(r["model_path"]) if r["model_path"] else ""
    cli.pop("scene")
    assert cli == bench


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.stem)
def test_check_carries_the_bench_sections(path):
    """legsim_cli --check prints [checks] and [[inject]] as the file writes them (null and []
    when absent), so that the resolved scene is the whole scene."""
    rc, cli, err = _cli_check(path)
    assert rc == 0, err
    d = tomllib.loads(path.read_text())
    assert cli["checks"] == d.get("checks")
    inject = d.get("inject", [])
    for x in inject:   # JSON has no nan or inf: --check writes them as strings
        if "signals" in x:
            x["signals"] = {k: (str(v) if isinstance(v, float) and not math.isfinite(v) else v)
                            for k, v in x["signals"].items()}
    assert cli["inject"] == inject


def test_check_writes_non_finite_injections_as_strings():
    rc, cli, err = _cli_check(ROOT / "scenes" / "bad_input.toml")
    assert rc == 0, err
    signals = [x["signals"] for x in cli["inject"] if "signals" in x]
    assert signals[0]["Act_Setpoint_upper"] == "nan" and signals[1]["Load_Value2"] == "inf"


def _expected_messages():
    rows = [line.rstrip("\n").split("\t") for line in (BAD / "expected.tsv").read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    return [(name, texts[0]) for name, code, *texts in rows
            if name.startswith(("old_", "duration_", "step_", "limit_", "robot_"))]


@pytest.mark.parametrize("name, text", _expected_messages(), ids=lambda v: str(v)[:40])
def test_both_readers_refuse_old_keys_and_off_grid_times_with_the_same_words(name, text):
    """Old keys and values name the new key; duration = 0.0505 (50.5 steps) is refused, never
    rounded: the bench says what legsim_cli says (tests/model/fixtures/scenes/expected.tsv)."""
    with pytest.raises(SceneError) as e:
        load_scene(BAD / name, ROOT)
    assert text in str(e.value)
    rc, _, err = _cli_check(BAD / name)
    assert rc == 2 and text in err


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
    r = subprocess.run([str(_cli()), str(path)], capture_output=True, text=True, timeout=60)
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
    _cli()
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
