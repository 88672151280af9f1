"""What a person reads: the pass/fail table, and the run as CSV and JSON files.

    print(format_table(evaluation))
    files = write_outputs(evaluation, out_dir)     # samples.csv, reference.csv, checks.json, ...
"""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from ..scene import ACTUATORS
from ..verdict.result import CheckResult, Evaluation

__all__ = ["format_table", "format_value", "write_outputs", "summary_line", "scene_table"]


def format_value(v: float | None, unit: str = "") -> str:
    if v is None:
        return "-"
    if isinstance(v, float) and not math.isfinite(v):
        s = str(v)
    elif v == 0:
        s = "0"
    elif float(v).is_integer() and abs(v) < 1e6 and unit in ("samples", "faults", ""):
        s = f"{int(v)}"
    elif 1e-3 <= abs(v) < 1e4:
        s = f"{v:.4g}"
    else:
        s = f"{v:.2e}"
    return f"{s} {unit}".strip() if unit else s


def _rows(results: list[CheckResult]) -> list[list[str]]:
    rows = []
    for r in results:
        err = r.got if r.error is None and r.got is not None else format_value(r.error, r.unit)
        tol = r.want if r.tolerance is None and r.want is not None else format_value(r.tolerance, r.unit)
        rows.append([r.name, err, tol, r.where or "", r.verdict])
    return rows


def format_table(ev: Evaluation, *, details: bool = True, width: int | None = None) -> str:
    """Aligned plain-text table: check | error | tolerance | where | result, then the
    failing rows' details (all details with details=True)."""
    sc = ev.scene
    head = ["check", "error / got", "tolerance / expected", "where", "result"]
    rows = _rows(ev.results)
    widths = [max(len(head[i]), *(len(r[i]) for r in rows)) if rows else len(head[i]) for i in range(5)]
    if width:
        widths[0] = min(widths[0], max(20, width - sum(widths[1:]) - 8))
    lines = [f"scene {sc.name}: {sc.description}" if sc.description else f"scene {sc.name}",
             f"  {sc.summary()}"]
    if ev.rec.get("dry_run"):
        lines.append("  DRY RUN: the reference model played hil_sim (no bus, says nothing about the core)")
    for c in sc.commands:
        if c is not None:
            lines.append(f"  {c.describe()}")
    if sc.foot_load:
        lines.append(f"  foot load ({sc.foot_load[0]:g}, {sc.foot_load[1]:g}) N")
    lines.append("")

    def fmt(r):
        return "  ".join([r[0].ljust(widths[0])[:widths[0]], r[1].rjust(widths[1]), r[2].rjust(widths[2]),
                          r[3].ljust(widths[3]), r[4]])

    lines.append(fmt(head))
    lines.append("  ".join("-" * w for w in widths))
    for r in rows:
        lines.append(fmt(r))
    lines.append("  ".join("-" * w for w in widths))
    notes = [(r, r.detail) for r in ev.results if r.detail and (details or not r.passed)]
    if notes:
        lines.append("")
        for r, det in notes:
            mark = "FAIL " if not r.passed else ""
            lines.append(f"  {mark}{r.name}: {det}")
    lines.append("")
    lines.append(summary_line(ev))
    return "\n".join(lines)


def summary_line(ev: Evaluation) -> str:
    n = len(ev.results)
    if ev.passed:
        return f"{ev.scene.name}: PASS ({n} checks)"
    return f"{ev.scene.name}: FAIL ({ev.n_failed} of {n} checks failed)"


def scene_table(rows: list[tuple[str, str, str]]) -> str:
    """name | demo | description, aligned."""
    w = [max(len(r[i]) for r in rows) for i in range(2)] if rows else [4, 4]
    return "\n".join(f"{r[0].ljust(w[0])}  {r[1].ljust(w[1])}  {r[2]}" for r in rows)


# ---- files ---------------------------------------------------------------------------------

def _columns(leg) -> list[str]:
    cols = ["t", "step"]
    for b in leg.body_names:
        cols += [f"{b}.x", f"{b}.y", f"{b}.phi"]
    for a in ACTUATORS:
        cols += [f"{a}.length", f"{a}.rate", f"{a}.force"]
    for j in leg.joint_names:
        cols += [f"{j}.fx", f"{j}.fy", f"{j}.m"]
    return cols


def _write_csv(path: Path, cols: list[str], rows) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in rows:
            w.writerow([repr(float(x)) if isinstance(x, (float, np.floating)) else x for x in r])


def write_robot_tables(traj, out: str | Path, reference=None) -> dict[str, Path]:
    """A robot run's samples.csv (report.robot_plots.RobotTrajectory: every plotted sample) and,
    given the reference's trajectory, reference.csv. Columns with their units: t (s); per body
    x, y (m), phi (rad); per foot its state, N and T (N, the ground's force on it along the
    ground's normal and tangent), its x, y (m); the sample's contact events (';'-separated)."""
    from .robot_plots import STATE_NAMES

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)

    def table(tr, path, events: bool):
        cols = ["t_s"] + [f"{b}.{c}" for b in tr.body_names for c in ("x_m", "y_m", "phi_rad")]
        for f in tr.foot_names:
            cols += [f"{f}.state", f"{f}.N_N", f"{f}.T_N", f"{f}.x_m", f"{f}.y_m"]
        rows = []
        for k in range(len(tr.t)):
            r = [tr.t[k], *tr.q[k].reshape(-1)]
            for j in range(len(tr.foot_names)):
                r += [STATE_NAMES[tr.contact[k, j]], tr.normal[k, j], tr.tangential[k, j], *tr.feet[k, j]]
            rows.append(r + [";".join(tr.events[k])] if events else r)
        _write_csv(path, cols + (["events"] if events else []), rows)
        return path

    files = {"samples": table(traj, out / "samples.csv", True)}
    if reference is not None:
        files["reference"] = table(reference, out / "reference.csv", False)
    return files


def write_outputs(ev: Evaluation, out: str | Path) -> dict[str, Path]:
    """samples.csv (every received sample), reference.csv (the reference at the same
    times), checks.csv (the table) and checks.json (the table, tolerances, set-up, faults, summary)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files: dict[str, Path] = {}
    d, leg = ev.data, ev.leg
    if d and leg is not None:
        cols = _columns(leg) + ["residual", "condition", "status", "stroke_mask", "faults"]
        rows = []
        for i, s in enumerate(ev.rec["samples"]):
            r = [d["t"][i], int(d["step"][i]), *d["q"][i]]
            for a in range(2):
                r += [d["lengths"][i, a], d["rates"][i, a], d["forces"][i, a]]
            r += list(d["reactions"][i].reshape(-1))
            r += [d["residual"][i], d["condition"][i], "|".join(s["status_names"]),
                  int(d["stroke_mask"][i]), "|".join(f["code"] for f in s["faults"])]
            rows.append(r)
        files["samples"] = out / "samples.csv"
        _write_csv(files["samples"], cols, rows)
    if ev.ref is not None and leg is not None:
        ref = ev.ref
        cols = ["t", "step"] + [c for c in _columns(leg)[2:] if not c.endswith(".rate")]
        rows = []
        for i in range(len(ref["t"])):
            r = [ref["t"][i], int(d["step"][i]), *ref["q"][i]]
            for a in range(2):
                r += [ref["lengths"][i, a], ref["forces"][i, a]]
            r += list(ref["reactions"][i].reshape(-1))
            rows.append(r)
        files["reference"] = out / "reference.csv"
        _write_csv(files["reference"], cols, rows)
    files["checks_csv"] = out / "checks.csv"
    with open(files["checks_csv"], "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["check", "result", "error", "tolerance", "unit", "where", "detail"])
        for r in ev.results:
            w.writerow([r.name, r.verdict, "" if r.error is None else repr(r.error),
                        "" if r.tolerance is None else repr(r.tolerance), r.unit, r.where, r.detail])
    sc = ev.scene
    run = {
        "scene": sc.name, "description": sc.description, "scene_path": ev.rec.get("scene_path"),
        "passed": ev.passed, "n_checks": len(ev.results), "n_failed": ev.n_failed,
        "checks": [r.as_dict() for r in ev.results],
        "tolerances": sc.checks.tolerances(),
        "setup": {"variant": sc.variant, "integrator": sc.integrator, "step_s": sc.step_s,
                  "duration_s": sc.duration, "record_every": sc.record_every,
                  "commands": [c.describe() for c in sc.commands if c is not None],
                  "foot_load": sc.foot_load, "cmd_timeout_ms": sc.cmd_timeout_ms},
        "recording": {k: ev.rec.get(k) for k in ("started", "host", "bus", "heartbeat", "complete",
                                                 "errors", "wall_time_s")},
        "n_samples": len(ev.rec["samples"]),
        "faults": [f for s in ev.rec["samples"] for f in s["faults"]] + ev.rec.get("late_faults", []),
        "injections": ev.rec["injections"],
        "reference_nfev": None if ev.ref is None else ev.ref.get("nfev"),
    }
    files["checks_json"] = out / "checks.json"
    files["checks_json"].write_text(json.dumps(run, indent=1, default=_json_default))
    return files


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))
