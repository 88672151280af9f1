"""A robot's stroke stop arrivals against the event-locating reference, in both sources of a
run: legsim_cli's samples (each names the kinds of the arrivals since the previous one) and a
CAN recording (St_StrokeMask: which actuators arrived; St_Status STROKE_MIN / STROKE_MAX: the
kinds). scenes/robot_fold_stop.toml is the run: the left lower actuator, pulled at -500 N with
its foot free, arrives at its stroke minimum at 84.07 ms (the step that ends at 85 ms). Its CAN
recording here is the CLI's run put in the shape legsim_bench.hil.runner records (the bus's
own run: tests/hil_scenes, tests/hil_verdicts), then one arrival is dropped, moved, or given
to another actuator, or an arrival is added: the check must say which.
"""
from __future__ import annotations

import copy
import math

import pytest

from legsim_bench.hil.cli_run import record_analysis
from legsim_bench.scene import load_scene
from legsim_bench.verdict.analyses import CONTACT_EVENTS, evaluate_analysis
from legsim_bench.verdict.robot_can import evaluate_robot_can

from test_robot_scenes import ROOT, _cli

SCENE = "robot_fold_stop"
CHECK = "stroke stop arrivals in the step that holds the reference's"
LEFT_LOWER = 3          # the robot's actuators: right upper, right lower, left upper, left lower
STROKE_MIN, STROKE_MAX = 1 << 3, 1 << 4    # St_Status bits (can/README.md)
ASSEMBLED = 1 << 0


def _num(v):
    return math.nan if v is None else float(v)


def can_recording(sc, out: dict) -> dict:
    """legsim_cli's robot run as hil_sim's recording (legsim_bench.hil.runner._state_dict):
    per sample the 39 coordinates, the actuators and joints in the core's order, the feet in
    leg order, and the stroke mask of the actuators that reached a stroke end since the previous
    sample, the kinds in the status bits from the sample's events (the core's
    legsim_stroke_event_mask and report bits, which hil_sim sends)."""
    ends = [a[1] for a in sc.model_info.actuators]
    acts, samples = out["actuators"], []
    at_end = [False] * len(acts)
    for s in out["samples"]:
        L = [s["actuators"][a]["length"] for a in acts]
        now = [min(abs(x - lo), abs(x - hi)) < 1e-9 for x, (lo, hi) in zip(L, ends)]
        mask = sum(1 << a for a in range(len(acts)) if now[a] and not at_end[a])
        at_end = now
        ev = set(s["events"])
        assert not ev & set(CONTACT_EVENTS), "this conversion gives the feet no events of their own"
        samples.append({
            "legs": 2, "t": s["t"], "step": round(s["t"] / sc.step_s),
            "q": [s["q"][b][c] for b in out["bodies"] for c in ("x", "y", "phi")],
            "lengths": L, "forces": [_num(s["actuators"][a]["force"]) for a in acts],
            "reactions": [_num(s["reactions"][j][k]) if s["reactions"] else math.nan
                          for j in out["joints"] for k in ("fx", "fy", "moment")],
            "residual": s["residual"], "state": "LOCKSTEP", "legsim_status": 0, "faults": [],
            "status": ASSEMBLED | (STROKE_MIN if "stroke_min" in ev else 0) | (STROKE_MAX if "stroke_max" in ev else 0),
            "stroke_mask": mask,
            "contacts": [{"state": c["state"], "events": [], "normal": _num(c["normal"]),
                          "tangential": _num(c["tangential"]), "x": c["x"], "y": c["y"],
                          "impulse_n": c["impulse_n"], "impulse_t": c["impulse_t"]}
                         for c in (s["contacts"][f] for f in out["contacts"])]})
    return {"samples": samples, "errors": [], "complete": True, "commands": [], "loads": [],
            "wall_time_s": 0.0}


@pytest.fixture(scope="module")
def run():
    _cli()
    sc = load_scene(SCENE, ROOT)
    rec = record_analysis(sc, root=ROOT)
    assert not rec["errors"], rec["errors"]
    return sc, rec, can_recording(sc, rec["cli_output"])


def _arrival_check(ev):
    hits = [r for r in ev.results if r.name == CHECK]
    assert len(hits) == 1, [r.name for r in ev.results]
    return hits[0]


def _at(samples, t):
    i = next(i for i, s in enumerate(samples) if abs(s["t"] - t) < 1e-9)
    return samples[i]


def test_the_scene_arrives_at_a_stop_in_both_sources_and_passes(run):
    """One arrival: the left lower at its minimum in the step 84 .. 85 ms, in the CLI's events and
    as the CAN recording's St_StrokeMask bit 3 with STROKE_MIN; every check passes on both."""
    sc, rec, can = run
    assert sc.checks.events and sc.model_info.actuators[LEFT_LOWER][1][0] == 0.35
    assert [s["t"] for s in rec["cli_output"]["samples"] if "stroke_min" in s["events"]] == [0.085]
    assert [(s["t"], s["stroke_mask"]) for s in can["samples"] if s["stroke_mask"]] == [(0.085, 1 << LEFT_LOWER)]
    for ev in (evaluate_analysis(rec, sc, ROOT), evaluate_robot_can(can, sc, ROOT)):
        assert ev.passed, [(r.name, r.error, r.detail) for r in ev.results if not r.passed]
        arrived = [e for e in ev.reference_run.events if e.kind == "stroke_min"]
        assert [e.actuator for e in arrived] == [LEFT_LOWER] and 0.084 < arrived[0].t < 0.085
        assert _arrival_check(ev).detail == f"1 arrivals: left.lower stroke_min at {arrived[0].t:.6f} s"


def _drop(samples):
    s = _at(samples, 0.085)
    s["stroke_mask"], s["status"] = 0, ASSEMBLED


def _late(samples):
    _drop(samples)
    _at(samples, 0.086).update(stroke_mask=1 << LEFT_LOWER, status=ASSEMBLED | STROKE_MIN)


def _other_actuator(samples):
    _at(samples, 0.085)["stroke_mask"] = 1 << 2


def _extra(samples):
    _at(samples, 0.05).update(stroke_mask=1 << 0, status=ASSEMBLED | STROKE_MAX)


@pytest.mark.parametrize("tamper, want", [
    (_drop, ["left.lower stroke_min at 0.0840* s not in the sample at 0.085 s"]),
    (_late, ["left.lower stroke_min at 0.0840* s not in the sample at 0.085 s",
             "stroke_min at t = 0.086 s (not in the reference)", "left.lower at t = 0.086 s (not in the reference)"]),
    (_other_actuator, ["left.lower stroke_min at 0.0840* s not in the sample at 0.085 s",
                       "left.upper at t = 0.085 s (not in the reference)"]),
    (_extra, ["stroke_max at t = 0.05 s (not in the reference)", "right.upper at t = 0.05 s (not in the reference)"]),
])
def test_a_can_recording_s_missing_or_extra_arrival_fails(run, tamper, want):
    sc, _, can = run
    bad = copy.deepcopy(can)
    tamper(bad["samples"])
    check = _arrival_check(evaluate_robot_can(bad, sc, ROOT))
    assert not check.passed and check.error == len(want)
    parts = check.detail.split("; ")
    assert len(parts) == len(want)
    for got, w in zip(parts, want):
        head, _, tail = w.partition("*")
        assert got.startswith(head) and got.endswith(tail), (got, w)


@pytest.mark.parametrize("t, kind, drop, want", [
    (0.085, "stroke_min", True, "left.lower stroke_min at 0.0840"),
    (0.05, "stroke_max", False, "stroke_max at t = 0.05 s (not in the reference)"),
])
def test_a_cli_run_s_missing_or_extra_arrival_fails(run, t, kind, drop, want):
    """The same check on legsim_cli's samples, which name the kinds only."""
    sc, rec, _ = run
    bad = copy.deepcopy(rec)
    s = _at(bad["cli_output"]["samples"], t)
    s["events"] = [e for e in s["events"] if e != kind] if drop else s["events"] + [kind]
    check = _arrival_check(evaluate_analysis(bad, sc, ROOT))
    assert not check.passed and check.error == 1 and check.detail.startswith(want)
