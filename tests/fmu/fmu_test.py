#!/usr/bin/env python3
"""The FMUs (fmu/) in FMPy, their real client, against the CLI (tests/fmu/CMakeLists.txt).

    fmu_test.py --fmu FMU --cli LEGSIM_CLI --scene SCENE.toml --work DIR [--tol 1e-12]

1. ``fmpy.validate`` (what ``fmpy validate FMU`` runs) finds no problem in the FMU;
2. the CLI runs the scene (``legsim_cli SCENE --out DIR/cli.csv``);
3. FMPy simulates the FMU with the scene's settings as start values (integrator, step,
   each actuator's mode, command and start length; communication step = record_every
   steps), and every body coordinate, actuator length and force, joint reaction and foot
   force of every sample after t = 0 equals the CLI's to --tol (absolute, and relative to
   the value's magnitude above 1).
The scene must be a dynamics scene whose commands are constant (value = ...), on the FMU's
model (the leg's revolute variant or models/robot.toml). Prints the largest difference.
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

INTEGRATORS = {"rk4": 0, "generalized_alpha": 1, "galpha": 1}


def fail(msg: str) -> None:
    print(f"FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--fmu", required=True, type=Path)
    ap.add_argument("--cli", required=True, type=Path)
    ap.add_argument("--scene", required=True, type=Path)
    ap.add_argument("--work", required=True, type=Path)
    ap.add_argument("--tol", type=float, default=1e-12)
    a = ap.parse_args()
    a.work.mkdir(parents=True, exist_ok=True)

    problems = validate_fmu(str(a.fmu))
    if problems:
        fail(f"fmpy validate {a.fmu.name}:\n" + "\n".join(problems))
    print(f"fmpy validate {a.fmu.name}: no problems")

    out = a.work / "cli.csv"
    r = subprocess.run([str(a.cli), str(a.scene), "--out", str(out)], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"legsim_cli {a.scene}: exit {r.returncode}\n{r.stderr}")
    with out.open() as f:
        rows = list(csv.DictReader(f))

    scene = tomllib.loads(a.scene.read_text())
    if scene.get("analysis", "dynamics") != "dynamics":
        fail(f"{a.scene}: not a dynamics scene")
    h = float(scene.get("step_s", 1e-3))
    every = int(scene.get("record_every", 1))
    md = read_model_description(str(a.fmu))
    names = {v.name for v in md.modelVariables}
    start = {"step_s": h, "integrator": INTEGRATORS[scene.get("integrator", "rk4")]}
    if "lengths" in scene:
        acts = [v.name[:-len(".length0_m")] for v in md.modelVariables if v.name.endswith(".length0_m")]
        for act, length in zip(acts, scene["lengths"]):
            start[f"{act}.length0_m"] = float(length)
    if scene.get("init", "zero_force") != "zero_force":
        fail(f"{a.scene}: init {scene['init']!r}: the FMU starts its actuators at zero force")
    for c in scene.get("command", []):
        if "value" not in c:
            fail(f"{a.scene}: command of {c['actuator']} is not constant (value = ...)")
        mode = c.get("mode", "force")
        start[f"{c['actuator']}.mode"] = 1 if mode == "length" else 0
        start[f"{c['actuator']}.{'length_m' if mode == 'length' else 'force_n'}"] = float(c["value"])
    unknown = sorted(set(start) - names)
    if unknown:
        fail(f"{a.fmu.name} has no variables {unknown}")

    # the CLI's columns and the FMU's outputs they are
    pairs = []
    for v in md.modelVariables:
        if v.causality != "output":
            continue
        n = v.name
        for fmu_suffix, csv_suffix in ((".x_m", ".x_m"), (".y_m", ".y_m"), (".phi_rad", ".phi_rad"),
                                       (".length_out_m", ".length_m"), (".force_out_n", ".force_n"),
                                       (".fx_n", ".fx_n"), (".fy_n", ".fy_n"), (".moment_nm", ".moment_nm"),
                                       (".normal_n", ".normal_n"), (".tangential_n", ".tangential_n")):
            if n.endswith(fmu_suffix):
                col = n[:-len(fmu_suffix)].removeprefix("joint_") + csv_suffix
                if col in rows[0]:
                    pairs.append((n, col))
    if len(pairs) < 10:
        fail(f"only {len(pairs)} FMU outputs found among the CLI's columns: {pairs}")

    duration = float(scene["duration"])
    res = simulate_fmu(str(a.fmu), start_time=0.0, stop_time=duration, output_interval=every * h,
                       start_values=start, output=[p[0] for p in pairs], fmi_type="CoSimulation",
                       validate=False)
    times = res["time"]
    worst, where, compared = 0.0, "", 0
    by_t = {round(float(row["t_s"]) / h): row for row in rows}
    for i, t in enumerate(times):
        k = round(t / h)
        if k == 0 or k not in by_t:
            continue
        row = by_t[k]
        if abs(float(row["t_s"]) - t) > 1e-9 * max(1.0, t):
            fail(f"sample times differ: CLI {row['t']}, FMU {t}")
        for fmu_name, col in pairs:
            if row[col] == "":
                continue
            ref, got = float(row[col]), float(res[fmu_name][i])
            err = abs(got - ref) / max(1.0, abs(ref))
            compared += 1
            if err > worst:
                worst, where = err, f"{col} at t = {t:.6g} s (CLI {ref!r}, FMU {got!r})"
    n_samples = sum(1 for t in times if 0 < round(t / h) in by_t)
    if compared == 0 or n_samples < len(rows) - 1:
        fail(f"compared {compared} values over {n_samples} samples (the CLI wrote {len(rows)})")
    print(f"{a.fmu.name} vs legsim_cli {a.scene.name}: {compared} values over {n_samples} samples "
          f"({len(pairs)} outputs), largest difference {worst:.3g}" + (f" ({where})" if where else ""))
    if worst > a.tol:
        fail(f"largest difference {worst:.3g} > {a.tol:g}: {where}")
    print("PASS")


if __name__ == "__main__":
    main()
