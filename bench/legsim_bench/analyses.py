"""The analyses that have no CAN frames: statics, statics_sweep, inverse_dynamics, assembly.

The DBC (can/legsim.dbc) carries dynamics only: RESET, STEP and state samples. A scene of
another analysis is run by the bench in legsim_cli, the core on this host through the same
scene file (`legsim_cli SCENE --format json`), and its numbers are checked against the
bench's reference model exactly as hil_sim's are: the reference's closed-form pose, its
Newton-Euler statics and inverse dynamics, its statics sweep, leg.toml's joint equations
and the free-body balance (legsim_bench.checks). The recording is the same file format
(`legsim-bench-recording/1`) with `"runner": "legsim_cli"` and the CLI's JSON output.

legsim_cli is $LEGSIM_CLI, else the one of hil_sim's build ($LEGSIM_HIL_SIM's
../firmware_core/legsim_cli), else build/host/firmware_core/legsim_cli.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
import os
import platform
import subprocess
import time
from pathlib import Path

import numpy as np

from .scene import ACTUATORS, Scene, find_root

__all__ = ["cli_path", "record_analysis", "evaluate_analysis"]


def cli_path(root: Path | None = None) -> Path:
    env = os.environ.get("LEGSIM_CLI")
    if env:
        return Path(env)
    hil = os.environ.get("LEGSIM_HIL_SIM")
    if hil:
        p = Path(hil).resolve().parent.parent / "firmware_core" / "legsim_cli"
        if p.is_file():
            return p
    return (root or find_root()) / "build" / "host" / "firmware_core" / "legsim_cli"


def record_analysis(scene: Scene, fmt: str, *, root: Path | None = None, log=None) -> dict:
    """Runs the scene in legsim_cli; the recording holds its JSON output (or the error)."""
    log = log or (lambda msg: None)
    rec: dict = {
        "format": fmt, "runner": "legsim_cli", "scene_name": scene.name,
        "scene_path": str(scene.path) if scene.path else None, "scene_source": scene.source,
        "started": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "host": platform.node(), "python": platform.python_version(), "bus": "none (legsim_cli)",
        "heartbeat": None, "samples": [], "commands": [], "loads": [], "injections": [],
        "late_faults": [], "errors": [], "complete": False, "initial_lengths": None, "cli": None,
    }
    t0 = time.monotonic()
    cli = cli_path(root)
    if scene.path is None:
        rec["errors"].append({"step": None, "error": "legsim_cli runs scene files: this scene has no path"})
    elif not cli.is_file():
        rec["errors"].append({"step": None, "error": f"legsim_cli not found at {cli}: build it (cmake "
                              "--build --preset host --target legsim_cli) or set LEGSIM_CLI"})
    else:
        rec["cli"] = str(cli)
        r = subprocess.run([str(cli), str(scene.path), "--format", "json"], capture_output=True,
                           text=True, timeout=3600)
        rec["cli_exit"] = r.returncode
        try:
            out = json.loads(r.stdout) if r.stdout.strip() else None
        except json.JSONDecodeError as e:
            out = None
            rec["errors"].append({"step": None, "error": f"legsim_cli wrote no JSON: {e}"})
        rec["cli_output"] = out
        if r.returncode != 0:
            rec["errors"].append({"step": None, "error": f"legsim_cli exit {r.returncode}: {r.stderr.strip()}"})
        if out is not None:
            # samples in the bench's shape for the summary lines (no faults: no bus)
            rec["samples"] = [dict(s, faults=[]) for s in out.get("samples", [])]
        rec["complete"] = r.returncode == 0 and out is not None and out.get("status") == "ok"
    rec["wall_time_s"] = time.monotonic() - t0
    for e in rec["errors"]:
        log(e["error"])
    return rec


# ---- checks -------------------------------------------------------------------------------

def _wrap(d):
    return (d + np.pi) % (2 * np.pi) - np.pi


def _arrays(out: dict) -> dict:
    """The CLI's samples as arrays in the model's body, actuator and joint order."""
    bodies, joints, acts = out["bodies"], out["joints"], out["actuators"]
    S = out["samples"]

    def num(v):
        return float("nan") if v is None else float(v)

    q = np.array([[num(s["q"][b][c]) for b in bodies for c in ("x", "y", "phi")] for s in S], float)
    F = np.array([[num(s["actuators"][a]["force"]) for a in acts] for s in S], float)
    L = np.array([[num(s["actuators"][a]["length"]) for a in acts] for s in S], float)
    R = np.array([[[num(s["reactions"][j][k]) for k in ("fx", "fy", "moment")] for j in joints]
                  if s["reactions"] is not None else [[math.nan] * 3] * len(joints) for s in S], float)
    return {"t": np.array([s["t"] for s in S], float), "q": q.reshape(len(S), -1), "forces": F,
            "lengths": L, "reactions": R.reshape(len(S), len(joints), 3)}


def _max(err) -> tuple[float, int, int]:
    e = np.abs(np.asarray(err, float))
    e = e.reshape(len(e), -1) if e.ndim > 1 else e.reshape(-1, 1)
    e = np.where(np.isnan(e), np.inf, e)   # a missing number fails, never hides
    i = int(np.argmax(e))
    r, c = divmod(i, e.shape[1])
    return float(e[r, c]), r, c


def evaluate_analysis(rec: dict, scene: Scene, root: Path | None = None):
    """The checks of a legsim_cli run against the reference model (an Evaluation)."""
    from .checks import CheckResult, Evaluation, Leg, _slot_s, constraint_residual, static_balance
    from .reference import LegModel

    root = root or find_root()
    ch = scene.checks
    model_path = scene.model_path or root / "models" / "leg.toml"
    leg = Leg.from_toml(model_path, scene.variant)
    results: list = []
    ev = Evaluation(scene, rec, results, leg=leg)
    out = rec.get("cli_output")
    ok = rec.get("complete") and out is not None
    n = len(out.get("samples", [])) if out else 0
    results.append(CheckResult(f"run: legsim_cli {scene.analysis}", bool(ok), float(n), None, "samples",
                               "", "; ".join(e["error"] for e in rec["errors"]) or
                               f"status {out.get('status_code')} ({rec.get('cli')})"))
    if not ok:
        return ev

    gravity = "gravity" not in scene.disable
    load = (0.0, 0.0) if scene.foot_load is None or "force_elements" in scene.disable else scene.foot_load
    model = LegModel.from_toml(model_path, variant=scene.variant)
    where_t = lambda d, r: f"t={d['t'][r]:.4f}s"  # noqa: E731

    def tol_check(name, key, err, unit, label, detail=""):
        tol = getattr(ch, key)
        if tol is None:
            return
        v, r, c = _max(err)
        results.append(CheckResult(name, v <= tol, v, tol, unit, label(r, c), detail))

    def body_label(r, c):
        return f"{where_t(d, r)} {leg.body_names[c // 3]}.{('x', 'y', 'phi')[c % 3]}"

    def pose_checks(q_ref, note):
        dq = d["q"] - q_ref
        dq[:, 2::3] = _wrap(dq[:, 2::3])
        xy = np.delete(dq, np.s_[2::3], axis=1)
        tol_check("positions x, y vs reference", "position_m", xy, "m",
                  lambda r, c: body_label(r, (c // 2) * 3 + c % 2), note)
        tol_check("angles vs reference", "angle_rad", dq[:, 2::3], "rad",
                  lambda r, c: body_label(r, 3 * c + 2), note)
        if ch.residual is not None:
            res = constraint_residual(leg, d["q"])
            tol_check(f"constraint residual |Phi(q)| ({leg.n_constraints} eqs, {model_path.name})",
                      "residual", res, "m|rad", lambda r, c: where_t(d, r))

    def theta0():
        th = model.stand_theta() if scene.lengths is None else \
            model.theta_from_lengths(scene.lengths, near=model.stand_theta())
        if scene.variant == "slot":   # s is wherever the core's assembly put it (cf. checks)
            th = th.copy()
            th[2] = _slot_s(Leg.from_toml(model_path, "slot"), d["q"][0])
        return th

    if scene.analysis == "statics_sweep":
        w = out["worst_case"]
        ref = model.statics_sweep(scene.grid, load, gravity)
        got_R = np.array([w["reactions"][j]["max_force"] for j in leg.joint_names], float)
        got_F = np.array([w["actuators"][a]["max_force"] for a in ACTUATORS], float)
        results.append(CheckResult("sweep: poses evaluated vs reference", w["n_poses"] == ref.n_poses,
                                   float(w["n_poses"]), float(ref.n_poses), "poses", "",
                                   f"{scene.grid} x {scene.grid} grid; failed: legsim {w['n_failed']}, "
                                   f"reference {ref.n_failed}"))
        d = {"t": np.zeros(1)}
        tol_check("sweep: max actuator forces vs reference", "statics_force_n",
                  (got_F - ref.max_actuator_force)[None], "N", lambda r, c: ACTUATORS[c],
                  f"legsim {', '.join(f'{x:.4f}' for x in got_F)} N")
        tol_check("sweep: max reaction forces vs reference", "statics_reaction_n",
                  (got_R - ref.max_reaction)[None], "N", lambda r, c: leg.joint_names[c])
        return ev

    d = _arrays(out)   # not ev.data: the report and the plots are for hil_sim's samples
    if scene.analysis == "assembly":
        pose_checks(model.absolute_q(theta0())[None], f"pose {scene.pose_name}"
                    + ("" if scene.lengths is None else f", lengths {list(scene.lengths)}"))
    elif scene.analysis == "statics":
        th = theta0()
        pose_checks(model.absolute_q(th)[None], f"pose {scene.pose_name}")
        F, R = model.statics(theta=th, foot_load=load, gravity=gravity)
        tol_check("actuator forces vs reference statics", "statics_force_n", d["forces"] - F[None], "N",
                  lambda r, c: ACTUATORS[c], f"reference ({F[0]:.4f}, {F[1]:.4f}) N, load {load} N")
        tol_check("reactions vs reference statics", "statics_reaction_n",
                  (d["reactions"] - R[None])[..., 0:2].reshape(len(d["t"]), -1), "N",
                  lambda r, c: f"{leg.joint_names[c // 2]}.f{'xy'[c % 2]}")
        if ch.balance_n is not None or ch.balance_nm is not None:
            bf, bm = static_balance(leg, d["q"], d["reactions"], d["forces"], load, gravity)
            tol_check("static balance, forces (legsim's numbers)", "balance_n", bf, "N",
                      lambda r, c: "", "sum of forces on each body")
            tol_check("static balance, moments (legsim's numbers)", "balance_nm", bm, "N m",
                      lambda r, c: "", "about each centre of mass")
    elif scene.analysis == "inverse_dynamics":
        th = theta0()
        hold = model.lengths(th)
        t = d["t"]
        L = np.tile(hold, (len(t), 1))
        Ld, Ldd = np.zeros_like(L), np.zeros_like(L)
        for c in scene.commands:
            if c is None:
                continue
            s = c.schedule
            L[:, c.actuator] = [s(x, float(hold[c.actuator])) for x in t]
            if s.kind == "sinusoid":
                w = 2 * math.pi * s.frequency
                Ld[:, c.actuator] = s.amplitude * w * np.cos(w * t + s.phase)
                Ldd[:, c.actuator] = -s.amplitude * w * w * np.sin(w * t + s.phase)
        ref = model.inverse_dynamics(L, Ld, Ldd, foot_load=load, gravity=gravity, near=th)
        pose_checks(ref.q, "the reference's pose at the commanded lengths")
        tol_check("actuator forces vs reference inverse dynamics", "actuator_force_n",
                  d["forces"] - ref.actuator_forces, "N", lambda r, c: f"{where_t(d, r)} {ACTUATORS[c]}")
        dr = d["reactions"] - ref.reactions
        tol_check("reaction forces vs reference (Newton-Euler)", "reaction_n",
                  dr[..., 0:2].reshape(len(t), -1), "N",
                  lambda r, c: f"{where_t(d, r)} {leg.joint_names[c // 2]}.f{'xy'[c % 2]}")
        tol_check("reaction moments vs reference", "moment_nm", dr[..., 2], "N m",
                  lambda r, c: f"{where_t(d, r)} {leg.joint_names[c]}.m")
    return ev
