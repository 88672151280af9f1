"""Stability stress campaign of the core's integrators.

    legsim-bench stress [--quick] [--n-steps N] [--out DIR | --update-results]
    python -m legsim_bench.benchmarks.stress [--quick] [--out DIR]        (from bench/)

Driven in-process through the legsim Python API (python/legsim), for each integrator (RK4 +
projection, generalized-alpha) and each build (double, float):

1. Long runs: 10^6 steps at h = 1 ms (1000 s) of the conservative case:
   constant actuator forces (upper -60 N, lower +10 N), gravity, no damping,
   no servo; the leg falls from the stand pose and swings for ever. Reported:
   the largest constraint residual max|Phi| (sampled every 100 steps), the
   energy drift of E = T + V_gravity - sum_a F_a l_a (masses and inertias
   from models/leg.toml, J = m L^2 / 12 unless given), absolute and relative
   to the largest kinetic energy of the run, its final value, and the events
   (a stroke stop is inelastic: the case is conservative only without one,
   which is checked).
2. Step growth: h doubles from 1 ms on the same case (1 s of simulated time,
   at least 20 steps) until the integrator fails; reported: the status it
   returns and when, whether the state it leaves is finite (no NaN, ever), the
   energy error and residual of the runs before.
3. Random command sequences (seeded): force commands (inside, at and beyond
   max_force), length commands (inside the stroke, near and at the stroke
   ends, beyond them, and near the upper actuator's dead centre at 0.75 m),
   foot loads, and step bursts. Every call must return LEGSIM_OK or a status
   legsim.h documents for it; after every call the state must be finite. A
   failed step is recovered by re-assembling the stand pose (counted).
4. Bit-identity: the same random sequence run twice in this process (two
   sims) and once in a fresh process gives the same bytes of q and qd.

Output: stress.md in ``--out`` (default out/bench-results/; ``--update-results``:
the committed bench/results/; ``--quick``: 10^5 steps, fewer sequences,
stress_quick.md). The command exits non-zero if any check
fails (NaN, undocumented status, non-identical runs).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

import legsim

from ..reference.model_file import read_model_file
from . import core as lc
from . import results

REPO_ROOT = lc.REPO_ROOT
MODEL_TOML = REPO_ROOT / "models" / "leg.toml"

H = 1e-3
CONSERVATIVE_FORCES = (-60.0, 10.0)  # upper, lower (N)
CHUNK = 100  # steps between samples
STROKES = [(0.40, 0.80), (0.35, 0.70)]  # leg.toml (checked against the library in tests)
INACCURATE = 1e-2  # step growth: relative energy error that counts as a silent failure

# the statuses legsim.h documents for each call of the random sequences
ALLOWED = {
    "command_force": {legsim.Status.OK, legsim.Status.ERR_BAD_INPUT},
    "command_length": {legsim.Status.OK, legsim.Status.ERR_OUT_OF_STROKE,
                       legsim.Status.ERR_BAD_INPUT},
    "set_force": {legsim.Status.OK, legsim.Status.ERR_BAD_INPUT},
    "step": {legsim.Status.OK, legsim.Status.ERR_SINGULAR, legsim.Status.ERR_NOT_CONVERGED,
             legsim.Status.ERR_DIVERGED, legsim.Status.ERR_UNREACHABLE},
    "assemble_pose": {legsim.Status.OK},
}
STEP_FAILURES = ALLOWED["step"] - {legsim.Status.OK}


# ---------------------------------------------------------------- energy
class Energy:
    """E = T + V_gravity - sum F l from the model file's masses and inertias."""

    def __init__(self, toml_path=MODEL_TOML):
        data = read_model_file(toml_path)
        self.g = np.asarray(data.get("gravity", [0.0, -9.81]), float)
        m, J = [], []
        for b in data["body"]:
            m.append(float(b["mass"]))
            J.append(float(b.get("inertia", b["mass"] * b["length"] ** 2 / 12.0)))
        self.m = np.array(m)
        self.J = np.array(J)

    def kinetic(self, qd) -> float:
        v = np.asarray(qd, float).reshape(-1, 3)
        return 0.5 * float(np.sum(self.m * (v[:, 0] ** 2 + v[:, 1] ** 2) + self.J * v[:, 2] ** 2))

    def potential(self, q, forces, lengths) -> float:
        r = np.asarray(q, float).reshape(-1, 3)
        vg = -float(np.sum(self.m * (r[:, 0] * self.g[0] + r[:, 1] * self.g[1])))
        return vg - float(np.dot(forces, lengths))

    def total(self, c: legsim.Sim, forces) -> tuple:
        q, qd = c.q, c.qd
        T = self.kinetic(qd)
        return T, T + self.potential(q, forces, c.actuator_lengths()[0])


def conservative_core(precision, integrator, h=H, stroke_limits=False):
    c = legsim.Sim(precision=precision, integrator=integrator, step=h,
                disable=() if stroke_limits else ("stroke_limits",))
    c.assemble_pose("stand")
    c.command_force(0, CONSERVATIVE_FORCES[0])
    c.command_force(1, CONSERVATIVE_FORCES[1])
    c.clear_events()
    return c


# ---------------------------------------------------------------- 1. long runs
def long_run(precision, integrator, n_steps, log, stroke_limits=False) -> dict:
    en = Energy()
    c = conservative_core(precision, integrator, stroke_limits=stroke_limits)
    F = np.array(CONSERVATIVE_FORCES)
    T0, E0 = en.total(c, F)
    max_res = c.constraint_residual()
    max_dE, max_T = 0.0, T0
    lmin = np.full(2, np.inf)
    lmax = np.full(2, -np.inf)
    status = "LEGSIM_OK"
    done = 0
    finite = True
    t0 = time.perf_counter()
    while done < n_steps:
        n = min(CHUNK, n_steps - done)
        st = lc.step_status(c, n)
        if st != legsim.Status.OK:
            status = legsim.status_name(st)
            break
        done += n
        q, qd = c.q, c.qd
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
            finite = False
            break
        T, E = en.kinetic(qd), None
        E = T + en.potential(q, F, c.actuator_lengths()[0])
        max_dE = max(max_dE, abs(E - E0))
        max_T = max(max_T, T)
        max_res = max(max_res, c.constraint_residual())
        l = c.actuator_lengths()[0]
        lmin = np.minimum(lmin, l)
        lmax = np.maximum(lmax, l)
    wall = time.perf_counter() - t0
    _, E_end = en.total(c, F)
    rep = c.report()
    row = {"precision": precision, "integrator": integrator, "stroke_limits": stroke_limits,
           "steps": done, "status": status,
           "finite": finite and bool(np.all(np.isfinite(c.q))), "max_residual": max_res,
           "E0": E0, "dE_max": max_dE, "dE_end": E_end - E0, "T_max": max_T,
           "rel_drift_max": max_dE / max_T if max_T > 0 else float("nan"),
           "rel_drift_end": (E_end - E0) / max_T if max_T > 0 else float("nan"),
           "events": rep.event_names(), "stroke_mask": c.stroke_event_mask(),
           "lmin": lmin.tolist(), "lmax": lmax.tolist(), "wall_s": wall,
           "us_per_step": 1e6 * wall / max(done, 1)}
    log(f"  {precision:6s} {integrator:6s} stops {'on ' if stroke_limits else 'off'} {done} steps, {status}, max|Phi| {max_res:.2e}, "
        f"|dE|max {max_dE:.2e} J ({row['rel_drift_max']:.2e} of T_max {max_T:.2f} J), "
        f"events {row['events']}, {wall:.1f} s")
    return row


# ---------------------------------------------------------------- 2. step growth
def step_growth(precision, integrator, log, t_sim=1.0, max_doublings=14) -> dict:
    en = Energy()
    F = np.array(CONSERVATIVE_FORCES)
    rows = []
    h = H
    failure = None
    for _ in range(max_doublings):
        try:
            c = conservative_core(precision, integrator, h)
        except legsim.LegsimError as e:  # e.g. h > 1 s is refused by the options check
            rows.append({"h": h, "status": e.status_name, "where": "legsim_init", "steps": 0,
                         "finite": True})
            failure = rows[-1]
            break
        _, E0 = en.total(c, F)
        n = max(20, int(round(t_sim / h)))
        st, done, max_res, max_dE, max_T = legsim.Status.OK, 0, 0.0, 0.0, 0.0
        while done < n:
            st = lc.step_status(c, 1)
            if st != legsim.Status.OK:
                break
            done += 1
            T, E = en.total(c, F)
            max_T = max(max_T, T)
            max_dE = max(max_dE, abs(E - E0))
            max_res = max(max_res, c.constraint_residual())
        q, qd = c.q, c.qd
        finite = bool(np.all(np.isfinite(q)) and np.all(np.isfinite(qd)))
        try:
            R = c.reactions()
            finite = finite and bool(np.all(np.isfinite(R)))
        except legsim.LegsimError:
            pass
        rep = c.report()
        row = {"h": h, "status": legsim.status_name(st), "where": "legsim_step", "steps": done,
               "n": n, "t_fail": done * h if st != legsim.Status.OK else None, "finite": finite,
               "max_residual": max_res, "dE_max": max_dE,
               "rel_dE": max_dE / max_T if max_T > 0 else float("nan"),
               "events": rep.event_names(), "condition": rep.condition,
               "iterations": rep.iterations}
        rows.append(row)
        if st != legsim.Status.OK:
            failure = row
            break
        h *= 2
    inaccurate = next((r for r in rows if r.get("rel_dE", 0) > INACCURATE), None)
    log(f"  {precision:6s} {integrator:6s} " + ", ".join(
        f"h={r['h']:g}: {r['status']}" for r in rows))
    return {"precision": precision, "integrator": integrator, "rows": rows, "failure": failure,
            "inaccurate": inaccurate}


# ---------------------------------------------------------------- 3. random sequences
def random_sequence(seed: int, n_segments: int) -> list:
    """A reproducible list of operations: (op, args)."""
    rng = np.random.default_rng(seed)
    strokes = STROKES
    fmax = 1500.0
    ops = []
    for _ in range(n_segments):
        a = int(rng.integers(0, 2))
        kind = rng.choice(["force", "force_edge", "force_bad", "length", "length_end",
                           "length_beyond", "dead_centre", "knee_straight", "load", "nan"],
                          p=[0.2, 0.07, 0.05, 0.2, 0.12, 0.05, 0.12, 0.06, 0.09, 0.04])
        lo, hi = strokes[a]
        if kind == "force":
            ops.append(("command_force", (a, float(rng.normal(0.0, 150.0)))))
        elif kind == "force_edge":
            ops.append(("command_force", (a, float(rng.choice([-1, 1]) * fmax))))
        elif kind == "force_bad":
            ops.append(("command_force", (a, float(rng.choice([-1, 1]) * fmax * (1 + rng.random())))))
        elif kind == "length":
            ops.append(("command_length", (a, float(rng.uniform(lo, hi)))))
        elif kind == "length_end":
            eps = float(10 ** rng.uniform(-9, -2))
            ops.append(("command_length", (a, lo + eps if rng.random() < 0.5 else hi - eps)))
        elif kind == "length_beyond":
            eps = float(10 ** rng.uniform(-9, -1))
            ops.append(("command_length", (a, lo - eps if rng.random() < 0.5 else hi + eps)))
        elif kind == "dead_centre":  # the upper actuator near 0.75 m (thigh straight down)
            ops.append(("command_length", (0, 0.75 + float(rng.uniform(-0.01, 0.01)))))
            ops.append(("command_length", (1, float(rng.uniform(0.55, 0.70)))))
        elif kind == "knee_straight":  # the lower near 0.70 m: its stroke end, knee straight
            ops.append(("command_length", (1, 0.70 - float(10 ** rng.uniform(-9, -2)))))
            ops.append(("command_length", (0, float(rng.uniform(0.6, 0.75)))))
        elif kind == "load":
            ops.append(("set_force", (0, (float(rng.normal(0, 100)), float(rng.uniform(-200, 600))))))
        else:
            ops.append(("command_force", (a, float("nan"))))
        ops.append(("step", (int(rng.integers(1, 200)),)))
    return ops


def run_sequence(precision, integrator, ops, h=H) -> dict:
    """Runs ops; checks statuses and finiteness after every call; a digest of q, qd."""
    c = legsim.Sim(precision=precision, integrator=integrator, step=h)
    c.assemble_pose("stand")
    counts = Counter()
    bad = []
    recoveries = 0
    events = Counter()
    digest = hashlib.sha256()
    lib = c.library.cdll
    R = c.library.real
    max_res = 0.0
    for i, (op, args) in enumerate(ops):
        if op == "command_force":
            st = lib.legsim_command_force(c.handle, args[0], args[1])
        elif op == "command_length":
            st = lib.legsim_command_length(c.handle, args[0], args[1])
        elif op == "set_force":
            st = lib.legsim_set_force(c.handle, args[0], (R * 2)(*args[1]))
        else:
            st = lib.legsim_step(c.handle, args[0])
        counts[(op, legsim.status_name(st))] += 1
        if st not in ALLOWED[op]:
            bad.append(f"op {i} {op}{args}: {legsim.status_name(st)}")
        q, qd = c.q, c.qd
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
            bad.append(f"op {i} {op}{args}: non-finite state after {legsim.status_name(st)}")
            break
        if op == "step":
            rep = c.report()
            for name in rep.event_names():
                events[name] += 1
            c.clear_events()
            if st == legsim.Status.OK:
                max_res = max(max_res, c.constraint_residual())
                try:
                    if not np.all(np.isfinite(c.reactions())):
                        bad.append(f"op {i}: non-finite reactions")
                except legsim.LegsimError:
                    pass
            else:
                recoveries += 1
                st2 = lib.legsim_assemble_pose(c.handle, 0)
                counts[("assemble_pose", legsim.status_name(st2))] += 1
                if st2 not in ALLOWED["assemble_pose"]:
                    bad.append(f"op {i}: recovery assemble_pose {legsim.status_name(st2)}")
                    break
                # the recovery starts from rest in the stand pose with the commands kept
        digest.update(c.state_bytes())
    return {"counts": counts, "bad": bad, "recoveries": recoveries, "events": events,
            "digest": digest.hexdigest(), "final": c.state_bytes().hex(), "max_residual": max_res,
            "steps": c.step_count, "time": c.time}


def _subprocess_digest(precision, integrator, seed, n_segments) -> str:
    code = ("import json,sys; from legsim_bench.benchmarks.stress import random_sequence, run_sequence;"
            f"r = run_sequence({precision!r}, {integrator!r}, random_sequence({seed}, {n_segments}));"
            "print(json.dumps(r['digest']))")
    env = dict(**__import__("os").environ)
    env["PYTHONPATH"] = str(REPO_ROOT / "bench") + (":" + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         cwd=REPO_ROOT / "bench")
    if out.returncode != 0:
        return "subprocess failed: " + out.stderr.strip().splitlines()[-1] if out.stderr else "?"
    return json.loads(out.stdout.strip().splitlines()[-1])


# ---------------------------------------------------------------- output
def write_md(path, info, long_rows, growth, seq_rows, ident_rows, n_long, n_seq, n_seg, elapsed,
             problems, info_end=None) -> None:
    L = []
    a = L.append
    a("# Stability stress campaign")
    a("")
    a(f"Generated by `legsim-bench stress` (bench/legsim_bench/benchmarks/stress.py) in {elapsed:.0f} s.")
    a("")
    L.extend(results.machine_section(info, info_end))
    a("**Checks: " + ("all passed" if not problems else "FAILED: " + "; ".join(problems)) + "**")
    a("")
    a(f"## 1. Long runs: {n_long:,} steps at h = {H:g} s, conservative case")
    a("")
    a(f"Constant actuator forces (upper {CONSERVATIVE_FORCES[0]:g} N, lower "
      f"{CONSERVATIVE_FORCES[1]:g} N), gravity, no damping, no servo: from the stand pose the leg "
      "falls and swings for ever, passing the fully stretched poses: upper 0.75 m (its dead "
      "centre) and lower 0.70 m, which is both the knee-straight length (0.50 + 0.20 m) and the "
      "lower stroke's end. The conservative rows run with LEGSIM_DISABLE_STROKE_LIMITS (a stop "
      "is an inelastic impact), and the lengths are checked to stay inside the strokes to 10 "
      "newton_tol (1e-9 m double, 1e-4 m float: the float build keeps the constraints to "
      "1e-5); "
      "the rows 'stops on' repeat the run with the stroke stops active. E = T + V_gravity - "
      "sum F l; 'relative' is to the largest kinetic energy of the run. Residual sampled every "
      f"{CHUNK} steps.")
    a("")
    a("| build | integrator | stroke stops | steps done | status | max abs Phi | max abs(E - E0) (J) | relative | E_end - E0 (J) | relative | T max (J) | lengths min / max (m) | events | us/step |")
    a("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in long_rows:
        a(f"| {r['precision']} | {r['integrator']} | {'on' if r['stroke_limits'] else 'off'} | {r['steps']:,} | {r['status']} | "
          f"{r['max_residual']:.2e} | {r['dE_max']:.2e} | {r['rel_drift_max']:.2e} | "
          f"{r['dE_end']:+.2e} | {r['rel_drift_end']:+.2e} | {r['T_max']:.2f} | "
          f"{np.round(r['lmin'], 4).tolist()} / {np.round(r['lmax'], 4).tolist()} | "
          f"{', '.join(r['events']) or 'none'} (stroke mask {r['stroke_mask']}) | {r['us_per_step']:.2f} |")
    a("")
    a("## 2. Step growth until failure")
    a("")
    a("The same conservative case (stroke stops off) for 1 s of simulated time (at least 20 "
      "steps), h doubling from 1 ms. A status other than LEGSIM_OK is the hard failure; a run "
      f"that returns OK with a relative energy error above {INACCURATE:g} is marked as the "
      "first inaccurate step (the integrator does not detect that). "
      "'finite' is whether q, qd (and the reactions) left after the failure are finite: the "
      "API must report, never return NaN.")
    a("")
    for g in growth:
        a(f"### {g['integrator']}, {g['precision']}")
        a("")
        a("| h (s) | status | steps done | failed at t (s) | state finite | max abs Phi | max abs dE (J) | relative dE | events | cond | Newton it. |")
        a("|---|---|---|---|---|---|---|---|---|---|---|")
        for r in g["rows"]:
            if r["where"] != "legsim_step":
                a(f"| {r['h']:g} | {r['status']} (refused by {r['where']}) | 0 | | yes | | | | | | |")
                continue
            a(f"| {r['h']:g} | {r['status']} | {r['steps']} / {r['n']} | "
              f"{'' if r['t_fail'] is None else format(r['t_fail'], '.3f')} | {'yes' if r['finite'] else 'NO'} | "
              f"{r['max_residual']:.1e} | {r['dE_max']:.2e} | {r['rel_dE']:.1e} | "
              f"{', '.join(r['events']) or 'none'} | {r['condition']:.3g} | {r['iterations']} |")
        f = g["failure"]
        a("")
        ia = g["inaccurate"]
        a("Fails at h = " + (f"{f['h']:g} s with {f['status']}" if f else "none of the h tried")
          + (f"; first relative energy error above {INACCURATE:g} (while returning OK) at "
             f"h = {ia['h']:g} s" if ia and ia["status"] == "LEGSIM_OK" else "") + ".")
        a("")
    a(f"## 3. Random command sequences ({n_seq} seeds x {n_seg} segments per integrator and build)")
    a("")
    a("Each segment: one command (force inside / at / beyond max_force, NaN; length inside / "
      "near the ends (1e-9 ... 1e-2 m) / beyond them; the upper length within 0.01 m of the "
      "0.75 m dead centre; a foot load) then a burst of 1-199 steps. After a failed step the "
      "stand pose is re-assembled (a recovery). Every status must be one legsim.h documents "
      "for the call, and the state must stay finite after every call.")
    a("")
    a("| build | integrator | calls | statuses | recoveries | events (steps that raised them) | max abs Phi after an OK step | violations |")
    a("|---|---|---|---|---|---|---|---|")
    for r in seq_rows:
        st = ", ".join(f"{op}: {name.replace('LEGSIM_', '')} x{n}" for (op, name), n in
                       sorted(r["counts"].items()))
        ev = ", ".join(f"{k} x{v}" for k, v in sorted(r["events"].items())) or "none"
        a(f"| {r['precision']} | {r['integrator']} | {sum(r['counts'].values())} | {st} | "
          f"{r['recoveries']} | {ev} | {r['max_residual']:.1e} | "
          f"{len(r['bad'])}{': ' + '; '.join(r['bad'][:3]) if r['bad'] else ''} |")
    a("")
    a("## 4. Bit-identical results for identical runs")
    a("")
    a("The same seeded sequence run twice in this process (two sims in separate storage) and "
      "once in a fresh Python process: SHA-256 over the bytes of q and qd after every call.")
    a("")
    a("| build | integrator | seed | run 1 | run 2 | fresh process | identical |")
    a("|---|---|---|---|---|---|---|")
    for r in ident_rows:
        a(f"| {r['precision']} | {r['integrator']} | {r['seed']} | `{r['d1'][:16]}` | "
          f"`{r['d2'][:16]}` | `{r['d3'][:16]}` | {'yes' if r['identical'] else 'NO'} |")
    a("")
    Path(path).write_text("\n".join(L) + "\n")


def configure_parser(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.description = __doc__.split("\n\n")[0]
    p.add_argument("--quick", action="store_true", help="10^5-step long runs, fewer sequences")
    p.add_argument("--n-steps", type=int, default=None, metavar="N",
                   help="steps of each long run (default 10^6, quick 10^5)")
    results.refuse_renamed(p, "--steps", "--n-steps", "the number of steps of each long run")
    p.add_argument("--seeds", type=int, default=None, help="random sequences per integrator and build")
    p.add_argument("--segments", type=int, default=None, help="segments per sequence")
    results.add_output_options(p)
    return p


def run(args) -> int:
    t0 = time.time()
    quick = bool(args.quick)
    n_long = args.n_steps or (100_000 if quick else 1_000_000)
    n_seq = args.seeds or (3 if quick else 20)
    n_seg = args.segments or (60 if quick else 150)
    out = results.output_dir(args)
    out.mkdir(parents=True, exist_ok=True)

    def log(s):
        print(s, flush=True)

    if lc.library_missing("double"):
        return 2
    info = results.snapshot()
    precs = [p for p in ("double", "float") if legsim.library_available(p)]
    integs = ("rk4", "galpha")
    problems = []
    log(f"# 1. long runs ({n_long} steps)")
    long_rows = [long_run(p, i, n_long, log, sl) for sl in (False, True) for p in precs
                 for i in integs]
    for r in long_rows:
        if not r["finite"]:
            problems.append(f"long run {r['precision']} {r['integrator']}: non-finite state")
        if r["stroke_limits"]:
            continue  # reported: with the stops on the case is not conservative
        if r["status"] != "LEGSIM_OK":
            problems.append(f"long run {r['precision']} {r['integrator']}: {r['status']}")
        tol = 10 * legsim.load_library(r["precision"]).default_options().newton_tol
        if r["stroke_mask"] or any(lo < s0 - tol or hi > s1 + tol for lo, hi, (s0, s1) in
                                   zip(r["lmin"], r["lmax"], STROKES)):
            problems.append(f"long run {r['precision']} {r['integrator']}: left the strokes")
    log("# 2. step growth")
    growth = [step_growth(p, i, log) for p in precs for i in integs]
    for g in growth:
        for r in g["rows"]:
            if not r["finite"]:
                problems.append(f"step growth {g['precision']} {g['integrator']} h={r['h']:g}: "
                                "non-finite state")
    log(f"# 3. random sequences ({n_seq} x {n_seg})")
    seq_rows = []
    for p in precs:
        for i in integs:
            agg = {"precision": p, "integrator": i, "counts": Counter(), "bad": [],
                   "recoveries": 0, "events": Counter(), "max_residual": 0.0}
            for seed in range(n_seq):
                r = run_sequence(p, i, random_sequence(seed, n_seg))
                agg["counts"].update(r["counts"])
                agg["bad"].extend(f"seed {seed}: {b}" for b in r["bad"])
                agg["recoveries"] += r["recoveries"]
                agg["events"].update(r["events"])
                agg["max_residual"] = max(agg["max_residual"], r["max_residual"])
            seq_rows.append(agg)
            log(f"  {p:6s} {i:6s} {sum(agg['counts'].values())} calls, {agg['recoveries']} "
                f"recoveries, {len(agg['bad'])} violations")
            problems.extend(f"random {p} {i}: {b}" for b in agg["bad"][:5])
    log("# 4. bit-identity")
    ident = []
    for p in precs:
        for i in integs:
            seed = 12345
            ops = random_sequence(seed, n_seg)
            d1 = run_sequence(p, i, ops)["digest"]
            d2 = run_sequence(p, i, ops)["digest"]
            d3 = _subprocess_digest(p, i, seed, n_seg)
            ok = d1 == d2 == d3
            ident.append({"precision": p, "integrator": i, "seed": seed, "d1": d1, "d2": d2,
                          "d3": d3, "identical": ok})
            log(f"  {p:6s} {i:6s} identical: {ok}")
            if not ok:
                problems.append(f"bit-identity {p} {i}")
    stem = "stress_quick" if quick else "stress"
    write_md(out / f"{stem}.md", info, long_rows, growth, seq_rows, ident, n_long, n_seq, n_seg,
             time.time() - t0, problems, info_end=results.snapshot())
    log(f"# wrote {out / (stem + '.md')}")
    if problems:
        log("# PROBLEMS: " + "; ".join(problems))
    return 1 if problems else 0


def main(argv=None) -> int:
    p = configure_parser(argparse.ArgumentParser(prog="legsim-bench stress"))
    return run(p.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
