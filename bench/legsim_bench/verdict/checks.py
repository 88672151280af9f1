"""Checks of a recording: hil_sim's states against the bench's own model of the leg.

Three independent sources of truth, none of them the core:

* the reference model (legsim_bench.reference: minimal coordinates, DOP853, Newton-Euler),
  replayed with exactly what the bench sent (the float32 setpoints and loads, held between
  exchanges as hil_sim holds them, and the safe state after a command timeout);
* leg.toml's joint equations (legsim_bench.verdict.leg: absolute coordinates, as in the paper)
  evaluated on the received positions: the constraint residual;
* the free-body equations of the six bodies (the same module), with the received positions,
  reactions and actuator forces: the static balance.

`evaluate(rec)` returns an Evaluation: the rows of the pass/fail table (CheckResult) and
the arrays behind them (for CSV, JSON and plots).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..recording import scene_of
from ..reference import ForceCommand, LegModel, LengthCommand, Staircase
from ..scene import ACTUATORS, Scene, find_root
from .analyses import evaluate_analysis
from .leg import Leg, constraint_residual, float32_quantum, slot_s, static_balance
from .result import CheckResult, Evaluation
from .robot_can import evaluate_robot_can

__all__ = ["evaluate", "reference_run", "STATUS_BITS"]

# St_Status bits (can/legsim.dbc)
STATUS_BITS = {"ASSEMBLED": 0, "REALTIME": 1, "SAFE_STATE": 2, "STROKE_MIN": 3, "STROKE_MAX": 4,
               "FORCE_SATURATED": 5, "NEAR_SINGULAR": 6, "HALTED": 7, "FAULT": 8,
               "CMD_WATCHDOG": 9, "STEPPING": 10}


def _arrays(rec: dict) -> dict:
    S = rec["samples"]
    n = len(S)

    def arr(key, width):
        return np.array([s[key] for s in S], float).reshape(n, width)

    return {
        "t": np.array([s["t"] for s in S], float),
        "step": np.array([s["step"] for s in S], int),
        "q": arr("q", 18), "qd": arr("qd", 18), "lengths": arr("lengths", 2),
        "rates": arr("rates", 2), "forces": arr("forces", 2),
        "reactions": arr("reactions", 24).reshape(n, 8, 3),
        "residual": np.array([s["residual"] for s in S], float),
        "condition": np.array([s["condition"] for s in S], float),
        "status": np.array([s["status"] for s in S], int),
        "stroke_mask": np.array([s["stroke_mask"] for s in S], int),
    }


# ---- the reference, replayed -------------------------------------------------------------


def _timeline(scene: Scene, rec: dict, faults: list[dict]) -> list[tuple[int, list]]:
    """[(step, [(mode, value) | None per actuator])]: what each actuator did from that step on
    (value None: hold the length it has then). From the RESET's initial commands, the logged
    ACT_CMDs and the safe state after a command timeout."""
    init_len = rec.get("initial_lengths") or [None, None]
    if scene.init == "hold_length":
        cur = [("length", init_len[0]), ("length", init_len[1])]
    else:
        cur = [("force", 0.0), ("force", 0.0)]
    events: list[tuple[int, int, list]] = [(0, 0, list(cur))]
    for c in rec["commands"]:
        events.append((c["step"], 1, [tuple(c[a]) if a in c else None for a in ACTUATORS]))
    for f in faults:
        if f["code"] == "CMD_TIMEOUT":
            v = [("force", 0.0)] * 2 if scene.safe_state == "zero_force" else [("length", None)] * 2
            events.append((f["step"], 0, v))
    events.sort(key=lambda e: (e[0], e[1]))
    out = []
    for step, _, v in events:
        cur = [v[a] if v[a] is not None else cur[a] for a in range(2)]
        if out and out[-1][0] == step:
            out[-1] = (step, list(cur))
        else:
            out.append((step, list(cur)))
    return out



def reference_run(scene: Scene, rec: dict, model_path, *, rtol=1e-10, atol=1e-11) -> dict:
    """The reference model at the recorded sample steps, driven as hil_sim was."""

    h = scene.step_s
    model = LegModel.from_toml(model_path, variant=scene.variant)
    steps = np.array([s["step"] for s in rec["samples"]], int)
    faults = [f for s in rec["samples"] for f in s["faults"]]
    tl = _timeline(scene, rec, faults)
    if "actuators" in scene.disable:
        tl = [(k, [None, None]) for k, _ in tl]
    gravity = "gravity" not in scene.disable
    loads = [(0, (0.0, 0.0))] + [(x["step"], tuple(x["value"])) for x in rec["loads"] if x["index"] == 0]
    if "force_elements" in scene.disable:
        loads = [(0, (0.0, 0.0))]
    if scene.lengths is not None:
        if scene.variant != "revolute":
            raise NotImplementedError("assembly at given lengths: revolute variant only")
        theta = model.theta_from_lengths(scene.lengths, near=model.stand_theta())
    else:
        theta = model.stand_theta()
    if scene.variant == "slot":
        # the stand pose drives phi3 and phi6 only: the slot coordinate s (C to D along the
        # shank axis, the reference's third coordinate) is wherever the core's assembly put
        # it. Take it from the received pose at t = 0.
        theta = theta.copy()
        theta[2] = slot_s(Leg.from_toml(model_path, "slot"), np.asarray(rec["samples"][0]["q"], float))
    thetad = np.zeros(model.ndof)
    theta0 = np.array(theta, float)

    # segments: where an actuator changes mode (within one the setpoints are a staircase)
    def modes(entry):
        return tuple(None if c is None else c[0] for c in entry[1])

    seg_starts = [0] + [tl[i][0] for i in range(1, len(tl)) if modes(tl[i]) != modes(tl[i - 1])]
    seg_starts = sorted(set(k for k in seg_starts if k < scene.n_steps))
    end_step = int(steps.max()) if len(steps) else 0
    out = {k: np.full((len(steps),) + s, np.nan) for k, s in
           (("q", (18,)), ("qd", (18,)), ("lengths", (2,)), ("forces", (2,)), ("reactions", (8, 3)),
            ("foot", (2,)), ("ne_residual", ()))}
    out["t"] = steps * h
    nfev = 0
    cur_len = None
    for si, k0 in enumerate(seg_starts):
        if k0 >= end_step:
            break
        k1 = seg_starts[si + 1] if si + 1 < len(seg_starts) else end_step
        k1 = min(k1, end_step)
        # commands of this segment: the entry in force at k0, then the changes before k1
        entries = [e for e in tl if e[0] <= k0][-1:] + [e for e in tl if k0 < e[0] < k1]
        cmds = []
        for a in range(2):
            if entries[0][1][a] is None:
                cmds.append(None)
                continue
            ts, vs = [], []
            for k, e in entries:
                val = e[a][1]
                if val is None:  # hold the length it has (hold-length safe state)
                    val = float(cur_len[a]) if cur_len is not None else float(rec["initial_lengths"][a])
                ts.append((k - k0) * h if k > k0 else 0.0)
                vs.append(float(val))
            sc = Staircase(ts, vs)
            cmds.append(ForceCommand(sc) if entries[0][1][a][0] == "force" else LengthCommand(sc))
        lent = [e for e in loads if e[0] <= k0][-1:] + [e for e in loads if k0 < e[0] < k1]
        lts = [((k - k0) * h if k > k0 else 0.0) for k, _ in lent]
        foot = (Staircase(lts, [v[0] for _, v in lent]), Staircase(lts, [v[1] for _, v in lent]))
        sel = (steps > k0) & (steps <= k1) if si > 0 else (steps >= k0) & (steps <= k1)
        local = np.unique(np.concatenate([(steps[sel] - k0) * h, [(k1 - k0) * h]]))
        res = model.simulate((k1 - k0) * h, t_eval=local, actuators=cmds, foot_load=foot,
                             gravity=gravity, theta0=theta, thetad0=thetad, rtol=rtol, atol=atol)
        nfev += res.nfev
        idx = np.nonzero(sel)[0]
        pos = np.searchsorted(res.t, (steps[idx] - k0) * h - 1e-12)
        for key, src in (("q", res.q), ("qd", res.qd), ("lengths", res.lengths),
                         ("forces", res.actuator_forces), ("reactions", res.reactions),
                         ("foot", res.foot), ("ne_residual", res.ne_residual)):
            out[key][idx] = src[pos]
        theta, thetad = res.theta[-1].copy(), res.thetad[-1].copy()
        cur_len = res.lengths[-1].copy()
    out["nfev"] = nfev
    out["theta0"] = theta0
    out["stroke"] = [a.stroke for a in model.actuators]
    return out


# ---- the checks ----------------------------------------------------------------------------

def _where(data, i: int, label: str) -> str:
    return f"t={data['t'][i]:.4f}s {label}"


def _coord_label(leg: Leg, c: int) -> str:
    return f"{leg.body_names[c // 3]}.{('x', 'y', 'phi')[c % 3]}"


def _max_err(err, mask=None):
    """(value, row, col) of the largest |err| over the rows in mask."""
    e = np.abs(np.asarray(err, float))
    e = e.reshape(len(e), -1)
    e = np.where(np.isnan(e), np.inf, e)   # a NaN received (or not computed) fails, never hides
    if mask is not None:
        e = np.where(np.asarray(mask)[:, None], e, np.nan)
    if not np.any(np.isfinite(e)):
        return None, -1, -1
    flat = int(np.nanargmax(e))
    r, c = divmod(flat, e.shape[1])
    return float(e[r, c]), r, c


def _wrap(d):
    return (d + np.pi) % (2 * np.pi) - np.pi


def evaluate(rec: dict, root: Path | None = None, *, scene: Scene | None = None,
             reference: bool = True) -> Evaluation:
    """All the checks the scene asks for, on one recording."""

    root = root or find_root()
    scene = scene or scene_of(rec, root)
    if not scene.over_can or rec.get("runner") == "legsim_cli":   # statics, sweep, ...: legsim_cli
        return evaluate_analysis(rec, scene, root)
    if scene.robot:          # the two-leg robot over CAN, against RobotModel
        return evaluate_robot_can(rec, scene, root)
    ch = scene.checks
    model_path = scene.model_path or root / "models" / "leg.toml"   # the scene's model file
    leg = Leg.from_toml(model_path, scene.variant)
    results: list[CheckResult] = []
    ev = Evaluation(scene, rec, results, leg=leg)
    S = rec["samples"]
    if not S:
        results.append(CheckResult("run: all exchanges answered", False, 0.0,
                                   float(len(scene.boundaries()) + 1), "samples",
                                   detail="no state sample recorded: " +
                                   "; ".join(e["error"] for e in rec["errors"])))
        return ev
    d = ev.data = _arrays(rec)
    n = len(S)

    # -- the run itself
    expected = len(scene.boundaries()) + 1
    grid_err = float(np.max(np.abs(d["t"] - d["step"] * scene.step_s)))
    bad_state = [s for s in S if s["state"] == "HALTED" or s["legsim_status"] != 0]
    problems = [e["error"] for e in rec["errors"]]
    if not rec.get("complete"):
        problems.append("run not complete")
    if n != expected:
        problems.append(f"{n} samples, expected {expected}")
    if bad_state:
        problems.append(f"HALTED / legsim_status {bad_state[0]['legsim_status']} at t={bad_state[0]['t']:.4f}")
    if grid_err > 1e-9:
        problems.append(f"St_Time off the step grid by {grid_err:.2g} s")
    results.append(CheckResult(
        "run: all exchanges answered", not problems, float(n), float(expected), "samples",
        f"to t={d['t'][-1]:.4f}s",
        "; ".join(problems) or f"steps 0..{d['step'][-1]}, St_Time on the grid ({grid_err:.1g} s)"))

    # -- the DBC's resolution (float32) must sit well below every tolerance it bears on
    quanta = []
    xy = d["q"].reshape(n, 6, 3)
    for key, values, unit in (("position_m", xy[..., 0:2], "m"), ("angle_rad", xy[..., 2], "rad"),
                              ("reaction_n", d["reactions"][..., 0:2], "N"),
                              ("moment_nm", d["reactions"][..., 2], "N m"),
                              ("actuator_force_n", d["forces"], "N"),
                              ("balance_n", d["reactions"][..., 0:2], "N"),
                              ("balance_nm", d["reactions"][..., 2], "N m"),
                              ("residual", xy[..., 0:2], "m"), ("stays_put_m", xy[..., 0:2], "m"),
                              ("statics_reaction_n", d["reactions"][..., 0:2], "N")):
        tol = getattr(ch, key)
        if tol is not None:
            quanta.append((float32_quantum(values) / tol, key, float32_quantum(values), tol, unit))
    if quanta:
        worst = max(quanta)
        results.append(CheckResult(
            "DBC float32 resolution < tolerance x %g" % ch.resolution_ratio,
            worst[0] <= ch.resolution_ratio, worst[2], worst[3] * ch.resolution_ratio, worst[4],
            worst[1], "; ".join(f"{k} {qv:.2g} {un}" for _, k, qv, _, un in quanta)))

    # -- the window where the reference applies (no stroke stops in it)
    window = np.ones(n, bool)
    stroke_idx = None
    hit = (d["stroke_mask"] != 0) | ((d["status"] >> STATUS_BITS["STROKE_MIN"]) & 1).astype(bool) | \
        ((d["status"] >> STATUS_BITS["STROKE_MAX"]) & 1).astype(bool)
    if np.any(hit):
        stroke_idx = int(np.argmax(hit))
    if ch.compare == "until_stroke" and stroke_idx is not None:
        window[stroke_idx:] = False
    after0 = window & (d["step"] > 0)   # forces and reactions exist after the first step

    # -- the reference model
    need_ref = reference and any(getattr(ch, k) is not None for k in
                                 ("position_m", "angle_rad", "reaction_n", "moment_nm",
                                  "actuator_force_n", "statics_force_n", "statics_reaction_n"))
    ref = None
    if need_ref:
        try:
            ref = ev.ref = reference_run(scene, rec, model_path)
        except Exception as e:  # noqa: BLE001 - a failing reference is a failed check, not a crash
            results.append(CheckResult("reference model", False, detail=f"{type(e).__name__}: {e}"))
    if ref is not None:
        lo = np.array([s[0] for s in ref["stroke"]])
        hi = np.array([s[1] for s in ref["stroke"]])
        inside = np.all((ref["lengths"] >= lo) & (ref["lengths"] <= hi), axis=1)
        if ch.compare == "until_stroke":
            first_out = np.argmax(~inside) if np.any(~inside) else n
            window[first_out:] = False
            after0 &= window
        ref_note = f"{int(window.sum())}/{n} samples" + ("" if window.all() else
                                                          f" (to t={d['t'][window][-1]:.4f}s)")
        if stroke_idx is not None and ch.compare == "all":
            ref_note += (f"; a stroke stop at t={d['t'][stroke_idx]:.4f}s (the reference has none: "
                         "compare = \"until_stroke\" if the scene means it)")
        slot_note = "" if scene.variant != "slot" else \
            f"; slot s0 = {ref['theta0'][2]:.7f} m from the received pose at t = 0"
        dq = d["q"] - ref["q"]
        dq[:, 2::3] = _wrap(dq[:, 2::3])
        dq = dq.reshape(n, 6, 3)
        if ch.position_m is not None:
            v, r, c = _max_err(dq[..., 0:2].reshape(n, 12), window)
            results.append(CheckResult("positions x, y vs reference", v is not None and v <= ch.position_m,
                                       v, ch.position_m, "m",
                                       _where(d, r, _coord_label(leg, (c // 2) * 3 + c % 2)) if r >= 0 else "",
                                       ref_note + slot_note))
        if ch.angle_rad is not None:
            v, r, c = _max_err(dq[..., 2], window)
            results.append(CheckResult("angles vs reference", v is not None and v <= ch.angle_rad, v,
                                       ch.angle_rad, "rad",
                                       _where(d, r, _coord_label(leg, 3 * c + 2)) if r >= 0 else "", ref_note))
        if ch.actuator_force_n is not None:
            v, r, c = _max_err(d["forces"] - ref["forces"], after0)
            results.append(CheckResult("actuator forces vs reference", v is not None and v <= ch.actuator_force_n,
                                       v, ch.actuator_force_n, "N",
                                       _where(d, r, ACTUATORS[c]) if r >= 0 else "", ref_note))
        if "reactions" not in scene.disable:
            dr = d["reactions"] - ref["reactions"]
            if ch.reaction_n is not None:
                v, r, c = _max_err(dr[..., 0:2].reshape(n, 16), after0)
                results.append(CheckResult("reaction forces vs reference (Newton-Euler)",
                                           v is not None and v <= ch.reaction_n, v, ch.reaction_n, "N",
                                           _where(d, r, f"{leg.joint_names[c // 2]}.f{'xy'[c % 2]}") if r >= 0 else "",
                                           ref_note))
            if ch.moment_nm is not None:
                v, r, c = _max_err(dr[..., 2], after0)
                results.append(CheckResult("reaction moments vs reference", v is not None and v <= ch.moment_nm,
                                           v, ch.moment_nm, "N m",
                                           _where(d, r, f"{leg.joint_names[c]}.m") if r >= 0 else "", ref_note))

    d["window"] = window   # samples the reference comparison covers
    # -- invariants of the received data
    if ch.residual is not None:
        res = constraint_residual(leg, d["q"])
        i = int(np.argmax(res))
        results.append(CheckResult(f"constraint residual |Phi(q)| ({leg.n_constraints} eqs, leg.toml)",
                                   bool(res[i] <= ch.residual), float(res[i]), ch.residual, "m|rad",
                                   _where(d, i, ""), f"hil_sim's own St_Residual max {np.max(d['residual']):.2g}"))
    foot = _foot_loads(scene, rec, d["step"])
    if ch.balance_n is not None or ch.balance_nm is not None:
        bf, bm = static_balance(leg, d["q"], d["reactions"], d["forces"], foot, "gravity" not in scene.disable)
        m = d["step"] > 0
        if ch.balance_n is not None:
            v, r, _ = _max_err(bf, m)
            results.append(CheckResult("static balance, forces (received data)", v is not None and v <= ch.balance_n,
                                       v, ch.balance_n, "N", _where(d, r, "") if r >= 0 else "",
                                       "sum of forces on each body, qdd = 0"))
        if ch.balance_nm is not None:
            v, r, _ = _max_err(bm, m)
            results.append(CheckResult("static balance, moments (received data)",
                                       v is not None and v <= ch.balance_nm, v, ch.balance_nm, "N m",
                                       _where(d, r, "") if r >= 0 else "", "about each centre of mass"))
    if ch.stays_put_m is not None:
        disp = np.abs(xy[..., 0:2] - xy[0, :, 0:2]).reshape(n, 12)
        v, r, c = _max_err(disp)
        results.append(CheckResult("stays put (drift from the first sample)", v <= ch.stays_put_m, v,
                                   ch.stays_put_m, "m",
                                   _where(d, r, _coord_label(leg, (c // 2) * 3 + c % 2)), ""))
    if ch.statics_force_n is not None or ch.statics_reaction_n is not None:
        results.extend(_statics_checks(scene, rec, d, model_path, leg))

    if ch.stroke is not None:
        results.extend(_stroke_checks(scene, d, leg, ref, stroke_idx))
    results.extend(_fault_checks(scene, rec, d))
    return ev


def _foot_loads(scene: Scene, rec: dict, steps) -> np.ndarray:
    """The foot load in force at each sample (after the step that produced it)."""
    out = np.zeros((len(steps), 2))
    if "force_elements" in scene.disable:
        return out
    for x in sorted(rec["loads"], key=lambda x: x["step"]):
        if x["index"] == 0:
            out[np.asarray(steps) > x["step"]] = x["value"]
    return out


def _statics_checks(scene, rec, d, model_path, leg) -> list[CheckResult]:

    ch = scene.checks
    out = []
    model = LegModel.from_toml(model_path, variant=scene.variant)
    load = (0.0, 0.0)
    if rec["loads"]:
        load = tuple(rec["loads"][0]["value"])
    th = model.stand_theta() if scene.lengths is None else model.theta_from_lengths(scene.lengths)
    try:
        F, R = model.statics(theta=th, foot_load=load, gravity="gravity" not in scene.disable)
    except Exception as e:  # noqa: BLE001
        return [CheckResult("reference statics", False, detail=f"{type(e).__name__}: {e}")]
    if ch.statics_force_n is not None:
        m = d["step"] > 0
        v, r, c = _max_err(d["forces"] - F[None], m)
        out.append(CheckResult("actuator forces vs reference statics", v is not None and v <= ch.statics_force_n,
                               v, ch.statics_force_n, "N",
                               _where(d, r, ACTUATORS[c]) if r >= 0 else "",
                               f"statics ({F[0]:.4f}, {F[1]:.4f}) N; received "
                               f"({d['forces'][-1, 0]:.4f}, {d['forces'][-1, 1]:.4f}) N at the end"))
    if ch.statics_reaction_n is not None:
        m = d["step"] > 0
        v, r, c = _max_err((d["reactions"] - R[None])[..., 0:2].reshape(len(m), 16), m)
        out.append(CheckResult("reactions vs reference statics", v is not None and v <= ch.statics_reaction_n,
                               v, ch.statics_reaction_n, "N",
                               _where(d, r, f"{leg.joint_names[c // 2]}.f{'xy'[c % 2]}") if r >= 0 else "",
                               f"load ({load[0]:g}, {load[1]:g}) N"))
    return out


def _stroke_checks(scene, d, leg, ref, stroke_idx) -> list[CheckResult]:
    s = scene.checks.stroke
    a = s.actuator
    name = ACTUATORS[a]
    lo, hi = leg.actuators[a]["stroke"]
    end = lo if s.end == "min" else hi
    bit = STATUS_BITS["STROKE_MIN" if s.end == "min" else "STROKE_MAX"]
    ev = ((d["stroke_mask"] >> a) & 1).astype(bool) & ((d["status"] >> bit) & 1).astype(bool)
    out = []
    first = int(np.argmax(ev)) if np.any(ev) else None
    detail = "never raised"
    if first is not None:
        detail = f"first at t={d['t'][first]:.4f}s (St_StrokeMask bit {a}, St_Status {['STROKE_MIN', 'STROKE_MAX'][s.end == 'max']})"
        if ref is not None:
            cross = np.nonzero((ref["lengths"][:, a] < end) if s.end == "min" else (ref["lengths"][:, a] > end))[0]
            if cross.size:
                detail += f"; the unstopped reference passes {end:g} m by t={d['t'][cross[0]]:.4f}s"
    out.append(CheckResult(f"stroke event: {name} reaches its {s.end} end", first is not None,
                           None if first is None else float(d["t"][first]), None, "s",
                           "" if first is None else _where(d, first, ""), detail))
    L = d["lengths"][:, a]
    over = (end - L) if s.end == "min" else (L - end)
    i = int(np.argmax(over))
    out.append(CheckResult(f"{name} length never passes {end:g} m", bool(over[i] <= s.tolerance_m),
                           float(max(over[i], 0.0)), s.tolerance_m, "m", _where(d, i, name),
                           f"length range {L.min():.6f} .. {L.max():.6f} m"))
    return out


def _fault_checks(scene: Scene, rec: dict, d) -> list[CheckResult]:
    out = []
    faults = [f for s in rec["samples"] for f in s["faults"]] + list(rec.get("late_faults", []))
    used = set()
    timeout_steps = math.ceil(scene.cmd_timeout_ms * 1e6 / scene.step_ns) if scene.cmd_timeout_ms else 0
    for inj in rec["injections"]:
        want = inj["expect"]
        got = None
        if inj["kind"] == "silence":
            last_cmd = max((c["step"] for c in rec["commands"] if c["step"] <= inj["step"]), default=None)
            trip = None if last_cmd is None else last_cmd + timeout_steps
            for i, f in enumerate(faults):
                if i not in used and f["code"] == want and inj["step"] <= f["step"] <= inj["step"] + inj["silence_steps"]:
                    got = i
                    break
            ok = got is not None and (trip is None or faults[got]["step"] == trip)
            # the row's name carries the label: the detail does not repeat it
            det = f"timeout {scene.cmd_timeout_ms} ms after the ACT_CMD at step {last_cmd}"
            if got is not None:
                used.add(got)
                f = faults[got]
                det += f" -> {f['code']} at step {f['step']} (expected {trip})"
                safe = _safe_state_ok(scene, rec, d, f["step"])
                if safe:
                    ok = False
                    det += "; " + safe
                else:
                    det += "; SAFE_STATE set until the next ACT_CMD" + \
                        (", actuator forces 0" if scene.safe_state == "zero_force" else "")
            else:
                det += " -> no " + want
            out.append(CheckResult(f"fault {want}: {inj['label']}", ok, None, None, "",
                                   f"t={inj['t']:.4f}s", det,
                                   got=faults[got]["code"] if got is not None else "none", want=want))
            continue
        for i, f in enumerate(faults):
            if i in used or f["code"] != want:
                continue
            if f["frame_id"] != inj["frame_id"] or f["step"] != inj["step"]:
                continue
            got = i
            break
        ok = got is not None
        near = [f["code"] for f in faults if f["step"] == inj["step"]]
        det = f"frame 0x{inj['frame_id']:03x} len {inj['length']}"
        if inj.get("seq") is not None:
            det += f" seq {inj['seq']}"
        if got is not None:
            used.add(got)
            f = faults[got]
            det += f" -> {f['code']}"
            if f.get("signal"):
                det += f" ({f['signal']})"
            if inj.get("expect_signal") and f.get("signal") != inj["expect_signal"]:
                ok = False
                det += f", expected signal {inj['expect_signal']}"
            # FAULT bit and St_LastFault in the sample after it
            nxt = next((s for s in rec["samples"] if s["step"] > inj["step"]), None)
            if nxt is not None:
                if "FAULT" not in nxt["status_names"]:
                    ok = False
                    det += "; St_Status FAULT bit not set"
                if nxt["last_fault"] != want:
                    ok = False
                    det += f"; St_LastFault {nxt['last_fault']}"
        else:
            det += f" -> no {want}" + (f" (got {', '.join(near)})" if near else "")
        shown = "none"
        if got is not None:
            shown = faults[got]["code"]
        elif near:
            shown = ",".join(near)
        out.append(CheckResult(f"fault {want}: {inj['label']}", ok, None, None, "",
                               f"t={inj['t']:.4f}s", det, got=shown, want=want))
    extra = [f for i, f in enumerate(faults) if i not in used]
    if rec["injections"] or extra:
        out.append(CheckResult("no unexpected faults", not extra, float(len(extra)), 0.0, "faults", "",
                               "; ".join(f"{f['code']} frame 0x{f['frame_id']:03x} step {f['step']}"
                                         for f in extra[:5]) or f"{len(used)} faults, all expected"))
    return out


def _safe_state_ok(scene, rec, d, trip_step) -> str:
    """'' if SAFE_STATE is set (and the forces are 0 in the zero-force safe state) in every
    sample from the trip to the next ACT_CMD, and cleared after it; else what is wrong."""
    nxt_cmd = min((c["step"] for c in rec["commands"] if c["step"] >= trip_step), default=None)
    bit = STATUS_BITS["SAFE_STATE"]
    for i, k in enumerate(d["step"]):
        in_safe = k > trip_step and (nxt_cmd is None or k <= nxt_cmd)
        on = bool((d["status"][i] >> bit) & 1)
        if in_safe and not on:
            return f"SAFE_STATE missing at step {k}"
        if nxt_cmd is not None and k > nxt_cmd and on:
            return f"SAFE_STATE still set at step {k} after the ACT_CMD at step {nxt_cmd}"
        if in_safe and scene.safe_state == "zero_force" and np.any(d["forces"][i] != 0):
            return f"actuator forces {d['forces'][i].tolist()} at step {k} in the safe state"
    return ""
