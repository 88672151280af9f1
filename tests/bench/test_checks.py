"""Checks on synthetic recordings (no CAN): the reference model plays hil_sim through
hil.reference_link.ReferenceLink; a correct recording passes, a perturbed one fails the right check.
Also the bench's own joint equations and free-body balance against the reference model, and
the table and files of the report."""
import copy
import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.verdict.checks  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.hil.reference_link import ReferenceLink  # noqa: E402
from legsim_bench.hil.runner import f32, record  # noqa: E402
from legsim_bench.reference import LegModel, Staircase  # noqa: E402
from legsim_bench.report.tables import format_table, write_outputs  # noqa: E402
from legsim_bench.verdict.checks import _timeline, evaluate  # noqa: E402
from legsim_bench.verdict.leg import Leg, constraint_residual, float32_quantum, static_balance  # noqa: E402
from legsim_bench.scene import load_scene, parse_scene  # noqa: E402

TOML = ROOT / "models" / "leg.toml"

STEP = """
description = "short step (test)"
integrator = "rk4"
step_s = 0.001
duration = 0.04
record_every = 5
[[command]]
actuator = "upper"
mode = "force"
step = { t0 = 0.012, before = -93.9, after = -40.0 }
[[command]]
actuator = "lower"
mode = "length"
value = "initial"
[checks]
position_m = 2e-6
angle_rad = 2e-6
reaction_n = 1e-3
moment_nm = 1e-4
actuator_force_n = 1e-3
residual = 1e-6
"""

HOLD = """
description = "short hold under 300 N (test)"
step_s = 0.001
duration = 0.03
record_every = 10
[forces]
foot_load = [0.0, 300.0]
[[command]]
actuator = "upper"
mode = "length"
value = 0.6964276495820934
[[command]]
actuator = "lower"
mode = "length"
value = 0.6245691301283014
[checks]
position_m = 1e-6
reaction_n = 1e-3
residual = 1e-6
balance_n = 0.01
balance_nm = 1e-3
stays_put_m = 1e-6
statics_force_n = 0.01
statics_reaction_n = 0.01
"""


def rec_of(text, name, **link):
    sc = parse_scene(text, name=name, root=ROOT)
    return sc, record(sc, ReferenceLink(ROOT, **link), progress=False)


@pytest.fixture(scope="module")
def step_rec():
    return rec_of(STEP, "step")


@pytest.fixture(scope="module")
def hold_rec():
    return rec_of(HOLD, "hold")


@pytest.fixture(scope="module")
def bad_rec():
    sc = load_scene("bad_input", ROOT)
    return sc, record(sc, ReferenceLink(ROOT), progress=False)


def failed(ev):
    return {r.name for r in ev.results if not r.passed}


def names(ev):
    return {r.name for r in ev.results}


# ---- the bench's own model of the leg ----------------------------------------------------

@pytest.mark.parametrize("variant", ["revolute", "slot"])
@settings(max_examples=25, deadline=None)
@given(d3=st.floats(-0.3, 0.3), d6=st.floats(-0.6, 0.6), ds=st.floats(-0.05, 0.05))
def test_joint_equations_vanish_on_reference_poses(variant, d3, d6, ds):
    m, leg = LegModel.from_toml(TOML, variant), Leg.from_toml(TOML, variant)
    th = m.stand_theta() + np.array([d3, d6, ds][:m.ndof])
    q = m.absolute_q(th)
    assert leg.n_constraints == (16 if variant == "revolute" else 15)
    assert constraint_residual(leg, q) < 1e-12
    np.testing.assert_allclose(leg.actuator_lengths(q), m.lengths(th), atol=1e-12)


def test_joint_equations_see_a_broken_pose():
    m, leg = LegModel.from_toml(TOML), Leg.from_toml(TOML)
    q = m.absolute_q(m.stand_theta())
    for c in range(18):
        qq = q.copy()
        qq[c] += 1e-4
        assert constraint_residual(leg, qq) > 1e-5, c


@pytest.mark.parametrize("load", [(0.0, 0.0), (0.0, 300.0), (40.0, 120.0)])
def test_free_body_balance_of_the_reference_statics(load):
    m, leg = LegModel.from_toml(TOML), Leg.from_toml(TOML)
    th = m.stand_theta()
    F, R = m.statics(m.lengths(th), foot_load=load)
    q = m.absolute_q(th)
    bf, bm = static_balance(leg, q, R, F, load)
    assert bf < 1e-9 and bm < 1e-9
    bf, _ = static_balance(leg, q, R * 1.001, F, load)
    assert bf > 1e-3


def test_free_body_balance_with_accelerations_of_a_reference_run():
    from legsim_bench.reference import ForceCommand
    m, leg = LegModel.from_toml(TOML), Leg.from_toml(TOML)
    r = m.simulate(0.05, t_eval=[0.05], actuators=[ForceCommand(30.0), ForceCommand(-10.0)], foot_load=(5, 20))
    res = leg.balance(r.q[-1], r.reactions[-1], r.actuator_forces[-1], (5, 20), qdd=r.qdd[-1])
    assert np.max(np.abs(res)) < 1e-9


def test_staircase_is_what_a_sample_sees():
    s = Staircase([0.0, 0.01, 0.02], [1.0, 2.0, 3.0])
    assert s.breakpoints == (0.01, 0.02)
    assert [s(t) for t in (0.0, 0.005, 0.01, 0.0100001, 0.02, 0.5)] == [1.0, 1.0, 1.0, 2.0, 2.0, 3.0]


def test_float32_quantum():
    assert float32_quantum([0.5]) == pytest.approx(2 ** -24)
    assert float32_quantum([700.0]) == pytest.approx(2 ** -14)
    assert f32(0.1) != 0.1 and abs(f32(0.1) - 0.1) < 1e-8


# ---- correct recordings pass -------------------------------------------------------------

def test_a_correct_recording_passes(step_rec):
    sc, rec = step_rec
    assert rec["complete"] and not rec["errors"]
    assert len(rec["samples"]) == len(sc.boundaries()) + 1
    # the command log: float32 setpoints, the step at its step
    steps = [c["step"] for c in rec["commands"]]
    assert 12 in steps and rec["commands"][0]["upper"] == ["force", f32(-93.9)]
    assert rec["commands"][-1]["upper"] == ["force", -40.0]
    assert rec["commands"][0]["lower"][0] == "length"
    ev = evaluate(rec, ROOT)
    assert ev.passed, format_table(ev)
    assert {"positions x, y vs reference", "reaction forces vs reference (Newton-Euler)",
            "actuator forces vs reference"} <= names(ev)
    assert np.nanmax(np.abs(ev.data["q"] - ev.ref["q"])) < 1e-7


def test_static_hold_passes_balance_and_statics(hold_rec):
    sc, rec = hold_rec
    ev = evaluate(rec, ROOT)
    assert ev.passed, format_table(ev)
    assert {"static balance, forces (received data)", "stays put (drift from the first sample)",
            "actuator forces vs reference statics", "reactions vs reference statics"} <= names(ev)


def test_bad_input_faults_are_matched(bad_rec):
    sc, rec = bad_rec
    ev = evaluate(rec, ROOT)
    assert ev.passed, format_table(ev)
    rows = [r for r in ev.results if r.name.startswith("fault ")]
    assert len(rows) == len(sc.injections)
    assert all(r.got == r.want for r in rows)


def test_a_fault_label_is_printed_once_per_line(bad_rec):
    # it used to read "NaN force setpoint: NaN force setpoint: frame 0x100 ..."
    sc, rec = bad_rec
    text = format_table(evaluate(rec, ROOT), details=True)
    labels = {inj.label for inj in sc.injections}
    assert "NaN force setpoint" in labels
    for label in labels:
        lines = [l for l in text.splitlines() if label in l]
        assert len(lines) == 2, (label, lines)   # the table row and its detail line
        assert all(l.count(label) == 1 for l in lines), lines
    detail = next(l for l in text.splitlines() if "NaN force setpoint: frame 0x" in l)
    assert detail.strip().startswith("fault NOT_FINITE: NaN force setpoint: frame 0x100 len 64")


# ---- perturbed recordings fail the right check --------------------------------------------

def perturbed(rec, fn):
    r = copy.deepcopy(rec)
    fn(r)
    return r


def test_a_moved_body_fails_positions_and_residual(step_rec):
    _, rec = step_rec

    def shift(r):
        r["samples"][4]["q"][6] += 1e-4          # thigh x

    ev = evaluate(perturbed(rec, shift), ROOT)
    assert {"positions x, y vs reference"} <= failed(ev)
    assert any(n.startswith("constraint residual") for n in failed(ev))
    row = next(r for r in ev.results if r.name == "positions x, y vs reference")
    assert row.error == pytest.approx(1e-4, rel=1e-3) and "thigh.x" in row.where


def test_a_rigidly_moved_leg_fails_positions_but_not_the_residual(step_rec):
    m = LegModel.from_toml(TOML)
    _, rec = step_rec

    def rotate(r):  # a pose of the mechanism, but not the one the dynamics gives
        th = m.stand_theta() + [0.001, -0.002]
        r["samples"][-1]["q"] = list(m.absolute_q(th))

    ev = evaluate(perturbed(rec, rotate), ROOT)
    assert "positions x, y vs reference" in failed(ev)
    assert not any(n.startswith("constraint residual") for n in failed(ev))


def test_wrong_reactions_and_forces_fail(step_rec):
    _, rec = step_rec

    def scale(r):
        r["samples"][5]["reactions"] = [v * 1.01 for v in r["samples"][5]["reactions"]]
        r["samples"][6]["forces"][1] += 0.01

    f = failed(evaluate(perturbed(rec, scale), ROOT))
    assert {"reaction forces vs reference (Newton-Euler)", "actuator forces vs reference"} <= f
    assert "positions x, y vs reference" not in f


def test_a_setpoint_that_was_not_sent_fails(step_rec):
    _, rec = step_rec

    def lie(r):  # the log claims the step came 5 ms later than it did
        for c in r["commands"]:
            if c["step"] in (12, 15):
                c["upper"] = ["force", f32(-93.9)]

    assert "positions x, y vs reference" in failed(evaluate(perturbed(rec, lie), ROOT))


def test_unbalanced_or_drifting_hold_fails(hold_rec):
    _, rec = hold_rec

    def unbalance(r):
        r["samples"][2]["reactions"][0] += 0.5     # A.fx

    f = failed(evaluate(perturbed(rec, unbalance), ROOT))
    assert {"static balance, forces (received data)", "reactions vs reference statics"} <= f

    def drift(r):
        r["samples"][-1]["q"] = [v + 2e-6 for v in r["samples"][-1]["q"]]

    assert "stays put (drift from the first sample)" in failed(evaluate(perturbed(rec, drift), ROOT))


def test_missing_and_unexpected_faults_fail(bad_rec):
    _, rec = bad_rec

    def drop_nan(r):
        for s in r["samples"]:
            s["faults"] = [f for f in s["faults"] if f["code"] != "NOT_FINITE" or f["frame_id"] != 0x100]

    f = failed(evaluate(perturbed(rec, drop_nan), ROOT))
    assert f == {"fault NOT_FINITE: NaN force setpoint"}

    def extra(r):
        r["samples"][3]["faults"].append({"code": "SOLVER", "frame_id": 0, "frame_len": 0, "seq": 0,
                                          "detail": 3, "value": 0.0, "step": 30, "count": 99, "signal": None})

    assert "no unexpected faults" in failed(evaluate(perturbed(rec, extra), ROOT))

    def wrong_signal(r):
        for s in r["samples"]:
            for x in s["faults"]:
                if x["signal"] == "Act_Setpoint_upper" and x["code"] == "NOT_FINITE":
                    x["signal"] = "Act_Setpoint_lower"

    assert "fault NOT_FINITE: NaN force setpoint" in failed(evaluate(perturbed(rec, wrong_signal), ROOT))

    def late_trip(r):
        for s in r["samples"]:
            for x in s["faults"]:
                if x["code"] == "CMD_TIMEOUT":
                    x["step"] += 1

    f = failed(evaluate(perturbed(rec, late_trip), ROOT))
    assert "fault CMD_TIMEOUT: silence 0.1 s (no ACT_CMD)" in f


def test_safe_state_must_show(bad_rec):
    _, rec = bad_rec
    trip = next(f["step"] for s in rec["samples"] for f in s["faults"] if f["code"] == "CMD_TIMEOUT")

    def no_safe(r):
        for s in r["samples"]:
            if s["step"] > trip:
                s["status"] &= ~(1 << 2)

    row = "fault CMD_TIMEOUT: silence 0.1 s (no ACT_CMD)"
    ev = evaluate(perturbed(rec, no_safe), ROOT)
    assert row in failed(ev)
    assert "SAFE_STATE missing" in next(r.detail for r in ev.results if r.name == row)


def test_the_timeline_replays_the_safe_state(bad_rec):
    sc, rec = bad_rec
    faults = [f for s in rec["samples"] for f in s["faults"]]
    tl = _timeline(sc, rec, faults)
    trip = next(f["step"] for f in faults if f["code"] == "CMD_TIMEOUT")
    at = dict(tl)
    assert at[trip] == [("force", 0.0), ("force", 0.0)]
    after = [k for k, _ in tl if k > trip]
    assert after and at[after[0]][0][0] == "length"


def test_an_incomplete_run_fails(step_rec):
    _, rec = step_rec

    def cut(r):
        del r["samples"][5:]
        r["complete"] = False
        r["errors"].append({"step": 20, "error": "no answer to STEP (seq 9) from hil_sim within 5 s"})

    ev = evaluate(perturbed(rec, cut), ROOT)
    assert "run: all exchanges answered" in failed(ev)
    assert "no answer" in next(r.detail for r in ev.results if r.name.startswith("run"))


def test_stroke_checks():
    text = STEP.replace("[checks]", "[checks]\ncompare = \"until_stroke\"\n"
                        "stroke = { actuator = \"lower\", end = \"min\", tolerance_m = 1e-6 }")
    sc, rec = rec_of(text, "stroke")
    ev = evaluate(rec, ROOT)
    assert "stroke event: lower reaches its min end" in failed(ev)     # never got there

    def hit(r):
        for s in r["samples"][6:]:
            s["stroke_mask"] = 2
            s["status"] |= 1 << 3
        r["samples"][-1]["lengths"][1] = 0.35 - 1e-5

    ev = evaluate(perturbed(rec, hit), ROOT)
    f = failed(ev)
    assert "stroke event: lower reaches its min end" not in f
    assert "lower length never passes 0.35 m" in f
    row = next(r for r in ev.results if r.name == "positions x, y vs reference")
    assert "6/" in row.detail   # compared up to the first event only


def test_resolution_row_names_the_limiting_signal(step_rec):
    sc, rec = step_rec
    ev = evaluate(rec, ROOT)
    row = next(r for r in ev.results if r.name.startswith("DBC float32 resolution"))
    assert row.passed and "position_m" in row.detail and "reaction_n" in row.detail
    tight = parse_scene(STEP.replace("residual = 1e-6", "residual = 1e-7"), name="step", root=ROOT)
    ev = evaluate(rec, ROOT, scene=tight)
    row = next(r for r in ev.results if r.name.startswith("DBC float32 resolution"))
    assert not row.passed and row.where == "residual"


# ---- the report ---------------------------------------------------------------------------

def test_table_is_aligned_and_says_pass_or_fail(step_rec):
    _, rec = step_rec
    ev = evaluate(rec, ROOT)
    text = format_table(ev)
    lines = text.splitlines()
    seps = [i for i, l in enumerate(lines) if l.startswith("---")]
    assert len(seps) == 2
    body = lines[seps[0] - 1:seps[1]]
    col = lines[seps[0] - 1].index("result")
    for l in body[2:]:
        assert l[col:col + 4] in ("PASS", "FAIL"), l
    assert lines[-1] == "step: PASS (%d checks)" % len(ev.results)
    assert "2.00e-06 m" in text   # the tolerance is in the table

    bad = evaluate(perturbed(rec, lambda r: r["samples"][3]["q"].__setitem__(0, 1.0)), ROOT)
    text = format_table(bad, details=False)
    assert "FAIL" in text and text.splitlines()[-1].startswith("step: FAIL (")
    assert "  FAIL positions x, y vs reference" in text


def test_outputs_csv_and_json(step_rec, tmp_path):
    _, rec = step_rec
    ev = evaluate(rec, ROOT)
    files = write_outputs(ev, tmp_path)
    with open(files["samples"]) as fh:
        rows = list(csv.reader(fh))
    assert rows[0][:5] == ["t", "step", "upper_cylinder.x", "upper_cylinder.y", "upper_cylinder.phi"]
    assert "D.fx" in rows[0] and "lower.force" in rows[0]
    assert len(rows) == len(rec["samples"]) + 1
    assert float(rows[1 + 4][2]) == rec["samples"][4]["q"][0]
    ref = list(csv.reader(open(files["reference"])))
    assert len(ref) == len(rows)
    run = json.loads(files["checks_json"].read_text())
    assert run["passed"] is True and run["n_failed"] == 0
    assert run["tolerances"]["position_m"] == 2e-6
    assert {c["check"] for c in run["checks"]} == names(ev)
    chk = list(csv.reader(open(files["checks_csv"])))
    assert chk[0][:4] == ["check", "result", "error", "tolerance"] and len(chk) == len(ev.results) + 1


def test_plots_are_written(step_rec, tmp_path):
    from legsim_bench.report.plots import write_plots
    _, rec = step_rec
    files = write_plots(evaluate(rec, ROOT), tmp_path)
    assert set(files) == {"motion", "actuators", "reactions", "errors"}
    for p in files.values():
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000


def test_nan_in_the_received_data_fails(step_rec):
    _, rec = step_rec

    def nan(r):
        r["samples"][3]["q"][7] = float("nan")
        r["samples"][4]["reactions"][2] = float("nan")

    f = failed(evaluate(perturbed(rec, nan), ROOT))
    assert {"positions x, y vs reference", "reaction moments vs reference"} <= f
    assert any(n.startswith("constraint residual") for n in f)
