"""Work-precision of legsim against the bench's reference and the peer engines.

    legsim-bench workprecision [--quick] [--step-sizes H...] [--out DIR | --update-results]
    python -m legsim_bench.benchmarks.workprecision [--quick] [--out DIR]      (from bench/)

For each integrator of the core (RK4 + projection, generalized-alpha index 3),
in the double and the float build (driven in-process through the legsim
Python API, python/legsim), and for each peer engine method (Exudyn
generalized-alpha and trapezoidal index 2, MuJoCo RK4 and semi-implicit
Euler, :mod:`legsim_bench.benchmarks.peers`), at each fixed step h from 1e-2 to 1e-5 s:

* error at t = 0.1 s against the bench's independent reference
  (:mod:`legsim_bench.reference`: minimal coordinates, DOP853 at rtol = atol
  = 1e-13): max |q - q_ref| over the 18 absolute coordinates (m and rad), and
  for legsim also max |R - R_ref| over the joint reactions (N, N m; the peers
  do not report reactions comparably, see peers/README.md);
* run time per simulated second: the integration only, timed inside this
  process (legsim: one ``legsim_step(sim, n)`` call around
  ``time.perf_counter_ns``; peers: their own ``wall_s``, around Exudyn's
  ``SolveDynamic`` / ``mujoco.rollout``), repeated, median and quartiles.
  Repetitions are interleaved across all engines so that load on the machine
  hits all of them alike. For the peers, the per-call set-up (the median time
  of a one-step run) is subtracted as well (the corrected time is the one
  compared; legsim's time is not corrected: that favours the peers).

Scenes: ``free_fall`` (stand pose at rest, gravity, zero actuator forces) and
``upper_step_50N`` (50 N on the upper actuator from t = 0). Both stay inside
the strokes for 0.1 s. The inverse-dynamics scene (the length sinusoid l(t) =
l0 + 0.02 sin(2 pi 2 t) on both actuators from the stand lengths) compares
``legsim_inverse_dynamics`` with the reference's inverse dynamics at 50
samples over one period and times one call.

Every peer method is first checked to converge to the same reference (error
falls with h, at the finest h it is below 1e-5 and at most 1e-3 times the
coarsest error); one that does not is reported and left out of the ratio.

Outputs (``--out``, default out/bench-results/; ``--update-results``: the
committed bench/results/): workprecision.csv, workprecision.md (tables, the
ratio of legsim's time to the best peer's at equal error for error levels
1e-4 ... 1e-10, machine info) and workprecision.png (log-log).
``--quick`` runs 3 step sizes and few repetitions (about a minute) and writes
workprecision_quick.* instead.
"""
from __future__ import annotations

import argparse
import csv
import math
import platform
import statistics
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

import numpy as np

import legsim

from .. import core as lc
from .. import results

REPO_ROOT = lc.REPO_ROOT
MODEL_TOML = REPO_ROOT / "models" / "leg.toml"

T_END = 0.1
STEPS = (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5)  # all divide 0.1 s
QUICK_STEPS = (1e-2, 1e-3, 1e-4)
# beyond the range (1e-2 ... 1e-5): what larger steps would buy, reported apart
STEPS_BEYOND = (5e-2, 2e-2)
RANGE_MAX_H = 1e-2
SCENES = {"free_fall": (0.0, 0.0), "upper_step_50N": (50.0, 0.0)}  # (upper, lower) force, N
ERROR_LEVELS = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
TARGET_RATIO = 0.1  # legsim at most a tenth of the best peer's time
REF_TOL = 1e-13

# the length sinusoid of the inverse-dynamics scene
ID_AMPLITUDE = 0.02  # m
ID_FREQUENCY = 2.0   # Hz
ID_SAMPLES = 50      # over one period


# ---------------------------------------------------------------- methods
@dataclass
class Method:
    key: str           # unique id, e.g. "legsim/rk4/double"
    engine: str        # "legsim", "exudyn", "mujoco"
    method: str
    precision: str     # "double" / "float" (peers: "double")
    label: str
    runner: Callable   # runner(scene, h, t_end) -> dict(q_end, R_end, wall_s, ok, status)
    is_legsim: bool = False
    in_ratio: bool = True   # legsim: counted as "legsim" in the ratio; peers: eligible
    options: dict = field(default_factory=dict)


def legsim_runner(precision: str, integrator: str, **options):
    def run(scene: str, h: float, t_end: float) -> dict:
        fu, fl = SCENES[scene]
        c = legsim.Sim(precision=precision, integrator=integrator, step=h, **options)
        c.assemble_pose("stand")
        c.command_force(0, fu)
        c.command_force(1, fl)
        n = int(round(t_end / h))
        try:
            wall_ns = lc.timed_step(c, n)
        except legsim.LegsimError as e:
            return {"ok": False, "status": e.status_name, "q_end": None, "R_end": None,
                    "wall_s": float("nan"), "n_steps": n}
        return {"ok": True, "status": "LEGSIM_OK", "q_end": c.q, "R_end": c.reactions(),
                "wall_s": wall_ns * 1e-9, "n_steps": n, "residual": c.constraint_residual(),
                "events": c.report().events}
    return run


def peer_runner(mod, method: str):
    def run(scene: str, h: float, t_end: float) -> dict:
        r = mod.run(scene, t_end, h, method, every=0)
        q_end = np.asarray(r["q_end"], float)
        ok = bool(r["ok"]) and bool(np.all(np.isfinite(q_end)))
        return {"ok": ok, "status": "ok" if ok else "failed", "q_end": q_end if ok else None,
                "R_end": None, "wall_s": float(r["wall_s"]), "n_steps": int(r["n_steps"])}
    return run


def methods(with_float: bool = True, with_peers: bool = True) -> list:
    out = []
    precs = ("double", "float") if with_float else ("double",)
    for prec in precs:
        if not legsim.library_available(prec):
            print(f"# legsim {prec}: {legsim.LIB_NAMES[prec]} not built, skipped", file=sys.stderr)
            continue
        for integ in ("rk4", "galpha"):
            out.append(Method(f"legsim/{integ}/{prec}", "legsim", integ, prec,
                              f"legsim {lc.INTEGRATOR_LABEL[integ]}, {prec}",
                              legsim_runner(prec, integ), is_legsim=True,
                              in_ratio=prec == "double"))
        if prec == "double":
            # the same RK4 with a tighter projection tolerance than the default 1e-10
            out.append(Method("legsim/rk4-tol1e-13/double", "legsim", "rk4", prec,
                              "legsim RK4 + projection, double, newton_tol 1e-13",
                              legsim_runner(prec, "rk4", newton_tol=1e-13), is_legsim=True,
                              in_ratio=True, options={"newton_tol": 1e-13}))
    if with_peers:
        try:
            from .peers import exudyn_leg
            if exudyn_leg.available():
                for m, lab in (("galpha", "generalized-alpha (index 3, rho_inf 0.8)"),
                               ("trapezoidal_index2", "trapezoidal index 2")):
                    out.append(Method(f"exudyn/{m}", "exudyn", m, "double",
                                      f"Exudyn {exudyn_leg.VERSION} {lab}",
                                      peer_runner(exudyn_leg, m)))
        except ImportError:
            print("# exudyn: not importable, skipped", file=sys.stderr)
        try:
            from .peers import mujoco_leg
            if mujoco_leg.available():
                for m, lab in (("rk4", "RK4 (solref 2h)"), ("euler", "semi-implicit Euler")):
                    out.append(Method(f"mujoco/{m}", "mujoco", m, "double",
                                      f"MuJoCo {mujoco_leg.VERSION} {lab}",
                                      peer_runner(mujoco_leg, m)))
        except ImportError:
            print("# mujoco: not importable, skipped", file=sys.stderr)
    return out


# ---------------------------------------------------------------- reference
def reference_model(variant: str = "revolute"):
    from ..reference import LegModel
    return LegModel.from_toml(str(MODEL_TOML), variant=variant)


def reference_end(scene: str, t_end: float = T_END) -> dict:
    from ..reference import ForceCommand
    m = reference_model()
    fu, fl = SCENES[scene]
    r = m.simulate(t_end, t_eval=[0.0, t_end], actuators=[ForceCommand(fu), ForceCommand(fl)],
                   rtol=REF_TOL, atol=REF_TOL)
    return {"q": np.asarray(r.q[-1]), "R": np.asarray(r.reactions[-1]),
            "out_of_stroke": bool(r.out_of_stroke), "lengths": np.asarray(r.lengths)}


# ---------------------------------------------------------------- measurement
@dataclass
class Point:
    method: Method
    scene: str
    h: float
    ok: bool = False
    status: str = ""
    pos_err: float = float("nan")
    reac_err: float = float("nan")
    residual: float = float("nan")
    walls: list = field(default_factory=list)
    overheads: list = field(default_factory=list)
    reps: int = 0

    def per_sim_s(self, q=50.0, corrected=False) -> float:
        if not self.walls:
            return float("nan")
        w = float(np.percentile(self.walls, q))
        if corrected and self.overheads:
            w = max(w - float(np.median(self.overheads)), 0.0)
        return w / T_END


def measure_accuracy(meths, scenes, steps, refs, log) -> list:
    pts = []
    for scene in scenes:
        ref = refs[scene]
        for m in meths:
            for h in steps:
                p = Point(m, scene, h)
                try:
                    r = m.runner(scene, h, T_END)
                except Exception as e:  # a peer that throws is reported, not fatal
                    r = {"ok": False, "status": f"exception: {e}", "q_end": None, "wall_s": 0}
                p.ok, p.status = r["ok"], r["status"]
                if r["ok"]:
                    p.pos_err = float(np.max(np.abs(r["q_end"] - ref["q"])))
                    if r.get("R_end") is not None:
                        p.reac_err = float(np.max(np.abs(r["R_end"] - ref["R"])))
                    p.residual = float(r.get("residual", float("nan")))
                    if not math.isfinite(p.pos_err):
                        p.ok, p.status = False, "non-finite state"
                    else:
                        p.walls.append(r["wall_s"])
                pts.append(p)
                log(f"  {scene:15s} {m.key:28s} h={h:.0e} "
                    + (f"err {p.pos_err:.2e} m|rad" + (f", reactions {p.reac_err:.2e} N"
                                                      if math.isfinite(p.reac_err) else "")
                       if p.ok else f"FAILED ({p.status})"))
    return pts


def convergence_check(pts, m: Method, scene: str) -> tuple:
    """(converged, text) for one method and scene from its accuracy points.

    Converged: every step size ran, the error falls monotonically as h falls
    over the finest three step sizes, the observed order over the finest pair
    is at least 0.8, and the finest error is below 1e-3 m|rad."""
    ps = sorted([p for p in pts if p.method is m and p.scene == scene and p.h <= RANGE_MAX_H],
                key=lambda p: -p.h)
    good = [p for p in ps if p.ok]
    failed = [f"{p.h:.0e}" for p in ps if not p.ok]
    if len(good) < 2:
        return False, "fewer than two successful step sizes" + (
            f"; failed at h = {', '.join(failed)}" if failed else "")
    fine, coarse = good[-1], good[0]
    order = float("nan")
    if good[-2].pos_err > 0 and fine.pos_err > 0:
        order = math.log(good[-2].pos_err / fine.pos_err) / math.log(good[-2].h / fine.h)
    tail = good[-3:]
    monotone = all(a.pos_err > b.pos_err for a, b in zip(tail, tail[1:]))
    ok = monotone and order >= 0.8 and fine.pos_err < 1e-3
    txt = (f"error {coarse.pos_err:.1e} at h={coarse.h:.0e} -> {fine.pos_err:.1e} at h={fine.h:.0e}, "
           f"observed order {order:.2f}" + ("" if monotone else ", not monotone")
           + (f"; failed at h = {', '.join(failed)}" if failed else ""))
    return ok, txt


def timing_plan(pts, target_s, min_reps, max_reps) -> dict:
    plan = {}
    for i, p in enumerate(pts):
        if not p.ok or not p.walls:
            continue
        w = max(p.walls[0], 1e-6)
        plan[i] = int(min(max_reps, max(min_reps, math.ceil(target_s / w))))
    return plan


def measure_timing(pts, plan, log, peers_overhead=True) -> None:
    """Interleaved repetitions: round r runs every point that still needs one."""
    if not plan:
        return
    rounds = max(plan.values())
    t0 = time.time()
    for r in range(rounds):
        for i, need in plan.items():
            if r >= need:
                continue
            p = pts[i]
            res = p.method.runner(p.scene, p.h, T_END)
            if res["ok"]:
                p.walls.append(res["wall_s"])
            if peers_overhead and not p.method.is_legsim:
                # the engine's per-call set-up: a one-step run
                o = p.method.runner(p.scene, p.h, p.h)
                p.overheads.append(o["wall_s"])
        if r in (0, 4, 19) or r == rounds - 1:
            log(f"  timing round {r + 1}/{rounds} ({time.time() - t0:.0f} s)")
    for i in plan:
        pts[i].reps = len(pts[i].walls)


# ---------------------------------------------------------------- inverse dynamics
def inverse_dynamics_study(precisions, reps: int, log) -> list:
    m = reference_model()
    l0 = m.lengths(m.stand_theta())
    ts = np.arange(ID_SAMPLES) / (ID_SAMPLES * ID_FREQUENCY)
    w = 2 * math.pi * ID_FREQUENCY
    s = np.sin(w * ts)[:, None]
    co = np.cos(w * ts)[:, None]
    L = l0[None, :] + ID_AMPLITUDE * s
    Ld = ID_AMPLITUDE * w * co * np.ones((1, 2))
    Ldd = -ID_AMPLITUDE * w * w * s * np.ones((1, 2))
    ref = m.inverse_dynamics(L, Ld, Ldd)
    rows = []
    for prec in precisions:
        if not legsim.library_available(prec):
            continue
        c = legsim.Sim(precision=prec)
        c.assemble_pose("stand")
        F = np.zeros((ID_SAMPLES, 2))
        R = np.zeros((ID_SAMPLES, c.n_joints, 3))
        Q = np.zeros((ID_SAMPLES, c.n_coords))
        for k in range(ID_SAMPLES):
            F[k] = c.inverse_dynamics(L[k], Ld[k], Ldd[k])
            R[k] = c.reactions()
            Q[k] = c.q
        row = {"precision": prec,
               "force_err": float(np.max(np.abs(F - ref.actuator_forces))),
               "reac_err": float(np.max(np.abs(R - ref.reactions))),
               "pos_err": float(np.max(np.abs(Q - ref.q))),
               "max_force": float(np.max(np.abs(ref.actuator_forces))),
               "max_reaction": float(np.max(np.abs(ref.reactions)))}
        # timing: the ctypes call only, over the prebuilt sample arrays, repeated
        R_ = c.library.real
        args = [((R_ * 2)(*L[k]), (R_ * 2)(*Ld[k]), (R_ * 2)(*Ldd[k])) for k in range(ID_SAMPLES)]
        out = (R_ * 2)()
        fn, sim = c.library.cdll.legsim_inverse_dynamics, c.handle
        per_call = []
        for _ in range(reps):
            c.assemble_pose("stand")
            t0 = time.perf_counter_ns()
            for a, b, d in args:
                fn(sim, a, b, d, out)
            per_call.append((time.perf_counter_ns() - t0) * 1e-9 / ID_SAMPLES)
        # the ctypes call cost alone (a trivial API function with the same binding)
        ft = c.library.cdll.legsim_time
        t0 = time.perf_counter_ns()
        for _ in range(20000):
            ft(sim)
        overhead = (time.perf_counter_ns() - t0) * 1e-9 / 20000
        row.update({"per_call_s": float(np.median(per_call)),
                    "per_call_p25": float(np.percentile(per_call, 25)),
                    "per_call_p75": float(np.percentile(per_call, 75)),
                    "reps": reps, "ctypes_call_s": overhead})
        rows.append(row)
        log(f"  inverse dynamics {prec}: force err {row['force_err']:.2e} N, reactions "
            f"{row['reac_err']:.2e} N, q {row['pos_err']:.2e}; {row['per_call_s'] * 1e6:.2f} us/call")
    return rows


# ---------------------------------------------------------------- analysis
def front(points) -> list:
    """Pareto front (time ascending, error strictly descending) of (err, time) pairs."""
    pts = sorted((t, e) for e, t in points if math.isfinite(e) and math.isfinite(t) and e > 0
                 and t > 0)
    out, best = [], float("inf")
    for t, e in pts:
        if e < best:
            out.append((e, t))
            best = e
    return out


def time_at_error(points, E) -> tuple:
    """(time, kind) to reach error E within the measured step range.

    kind 'interp': log-log interpolation along the front; 'range': the largest
    step measured (1e-2 s) is already more accurate than E, so that step's time
    is the time within the range (a larger step might be cheaper);
    'unreached': no measured step reaches E."""
    f = front(points)
    if not f or f[-1][0] > E:
        return float("nan"), "unreached"
    if f[0][0] <= E:
        return f[0][1], "range"
    for (e0, t0), (e1, t1) in zip(f, f[1:]):
        if e0 > E >= e1:
            x = (math.log(E) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + x * (math.log(t1) - math.log(t0))), "interp"
    return float("nan"), "unreached"


def curve(pts, m, scene, corrected=True, max_h=RANGE_MAX_H):
    return [(p.pos_err, p.per_sim_s(corrected=corrected and not m.is_legsim))
            for p in pts if p.method is m and p.scene == scene and p.ok and p.h <= max_h]


def ratio_table(pts, meths, scene, conv, max_h=RANGE_MAX_H) -> list:
    rows = []
    legs = [m for m in meths if m.is_legsim and m.in_ratio]
    peers = [m for m in meths if not m.is_legsim and conv.get((m.key, scene), (False,))[0]]
    for E in ERROR_LEVELS:
        lt = [(time_at_error(curve(pts, m, scene, max_h=max_h), E), m) for m in legs]
        pt = [(time_at_error(curve(pts, m, scene, max_h=max_h), E), m) for m in peers]
        lt = [x for x in lt if x[0][1] != "unreached"]
        pt = [x for x in pt if x[0][1] != "unreached"]
        row = {"scene": scene, "E": E}
        if lt:
            (tl, kl), ml = min(lt, key=lambda x: x[0][0])
            row.update(legsim=ml.key, t_legsim=tl, kind_legsim=kl)
        else:
            row.update(legsim=None, t_legsim=float("nan"), kind_legsim="unreached")
        if pt:
            (tp, kp), mp = min(pt, key=lambda x: x[0][0])
            row.update(peer=mp.key, t_peer=tp, kind_peer=kp)
        else:
            row.update(peer=None, t_peer=float("nan"), kind_peer="unreached")
        row["ratio"] = row["t_legsim"] / row["t_peer"] if lt and pt else float("nan")
        kl, kp = row["kind_legsim"], row["kind_peer"]
        if not lt and not pt:
            verdict = "neither reaches this error at h >= 1e-5"
        elif not lt:
            verdict = "NOT MET: legsim does not reach this error"
        elif not pt:
            verdict = "met: no converged peer reaches this error at h >= 1e-5"
        else:
            r = row["ratio"]
            verdict = ("met" if r <= TARGET_RATIO else "NOT MET") + f" (ratio {r:.3g})"
            notes = []
            if kl == "range":
                notes.append(f"legsim at h = {max_h:g} is already more accurate")
            if kp == "range":
                notes.append(f"the peer at h = {max_h:g} is already more accurate")
            if notes:
                verdict += "; " + ", ".join(notes)
        row["verdict"] = verdict
        rows.append(row)
    return rows


# ---------------------------------------------------------------- output
def machine_info() -> dict:
    """results.snapshot() (CPU, cores, load, date, commit) and the Python packages' versions."""
    info = results.snapshot()
    info.update(python=platform.python_version(), numpy=np.__version__)
    for mod in ("scipy", "matplotlib"):
        try:
            info[mod] = __import__(mod).__version__
        except ImportError:
            info[mod] = "absent"
    try:
        from .peers import exudyn_leg, mujoco_leg
        info["exudyn"] = exudyn_leg.VERSION
        info["mujoco"] = mujoco_leg.VERSION
    except Exception:
        pass
    return info


def describe_source(src: Path) -> str:
    """A source tree and its commit (git, or the COMMIT file of an exported tree)."""
    c = results.commit(Path(src), paths=("firmware_core", "cmake", "CMakeLists.txt",
                                          "CMakePresets.json", "models"))
    return f"{src}" + ("" if c.startswith("unknown") else f" at {c}")


def library_info() -> dict:
    out = {}
    for prec in ("double", "float"):
        if legsim.library_available(prec):
            api = legsim.load_library(prec)
            cache = None
            for d in (api.path.parent, api.path.parent.parent):
                if (d / "CMakeCache.txt").is_file():
                    cache = d / "CMakeCache.txt"
                    break
            bt, src = "?", None
            if cache:
                for line in cache.read_text().splitlines():
                    if line.startswith("CMAKE_BUILD_TYPE:"):
                        bt = line.split("=", 1)[1]
                    if line.startswith("CMAKE_HOME_DIRECTORY:"):
                        src = line.split("=", 1)[1]
            out[prec] = (f"{api.path} (CMAKE_BUILD_TYPE={bt}, sim storage {api.sim_size} B"
                         + (f", source {describe_source(src)}" if src else "") + ")")
    return out


def fmt(x, spec=".2e") -> str:
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def write_csv(path: Path, pts) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scene", "engine", "method", "precision", "key", "h_s", "ok", "status",
                    "pos_err", "reaction_err", "constraint_residual", "reps",
                    "wall_per_sim_s_median", "wall_per_sim_s_p25", "wall_per_sim_s_p75",
                    "wall_per_sim_s_min", "setup_per_call_s_median",
                    "wall_per_sim_s_corrected_median", "us_per_step_median"])
        for p in pts:
            m = p.method
            n = T_END / p.h
            w.writerow([p.scene, m.engine, m.method, m.precision, m.key, f"{p.h:g}", int(p.ok),
                        p.status, f"{p.pos_err:.6e}", f"{p.reac_err:.6e}", f"{p.residual:.3e}",
                        len(p.walls), f"{p.per_sim_s():.6e}", f"{p.per_sim_s(25):.6e}",
                        f"{p.per_sim_s(75):.6e}",
                        f"{(min(p.walls) / T_END if p.walls else float('nan')):.6e}",
                        f"{(float(np.median(p.overheads)) if p.overheads else 0.0):.6e}",
                        f"{p.per_sim_s(corrected=True):.6e}",
                        f"{(p.per_sim_s() * T_END / n * 1e6):.4f}"])


# one colour and one marker per engine, method and precision (float is not double dashed)
STYLES = {
    "legsim/rk4/double": ("tab:blue", "o", "-"),
    "legsim/rk4-tol1e-13/double": ("tab:cyan", "P", ":"),
    "legsim/galpha/double": ("tab:green", "s", "-"),
    "legsim/rk4/float": ("tab:pink", "h", "--"),
    "legsim/galpha/float": ("tab:olive", "d", "--"),
    "exudyn/galpha": ("tab:red", "^", "-"),
    "exudyn/trapezoidal_index2": ("tab:orange", "v", "-"),
    "mujoco/rk4": ("tab:purple", "D", "-"),
    "mujoco/euler": ("tab:brown", "x", "-"),
}
SCENE_LINES = ("-", ":")  # the reaction panel tells the scenes apart by line style


def plot(path: Path, pts, meths, scenes, id_rows) -> bool:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.lines import Line2D
    except ImportError:
        return False
    fig, axes = plt.subplots(2, 2, figsize=(14, 12), layout="constrained")
    for ax, scene in zip(axes[0], scenes):
        for m in meths:
            ps = sorted([p for p in pts if p.method is m and p.scene == scene and p.ok],
                        key=lambda p: -p.h)
            if not ps:
                continue
            c, mk, ls = STYLES.get(m.key, ("tab:gray", ".", "-"))
            x = [p.per_sim_s(corrected=not m.is_legsim) for p in ps]
            y = [max(p.pos_err, 1e-16) for p in ps]
            ax.loglog(x, y, color=c, marker=mk, ls=ls, label=m.label, ms=5)
            for p, xi, yi in zip(ps, x, y):
                if p.h in (1e-2, 1e-3, 1e-4, 1e-5):
                    ax.annotate(f"{p.h:.0e}", (xi, yi), fontsize=6, alpha=0.6,
                                textcoords="offset points", xytext=(3, 3))
        ax.axhspan(1e-10, 1e-4, color="0.9", zorder=0)
        ax.set_title(f"{scene}: position error at t = {T_END} s vs time")
        ax.set_xlabel("wall time per simulated second (s), median")
        ax.set_ylabel("max |q - q_ref| over 18 coordinates (m, rad)")
        ax.grid(True, which="both", alpha=0.3)
    # one legend for both scenes, above the panels: inside, it covered curves
    handles, labels = {}, {}
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="outside upper center", ncol=3,
                   fontsize=8, title="grey band: the target's error range 1e-10 ... 1e-4; "
                   "labels: step size h (s)", title_fontsize=8)
    ax = axes[1][0]
    for scene, ls in zip(scenes, SCENE_LINES):
        for m in meths:
            if not m.is_legsim:
                continue
            ps = sorted([p for p in pts if p.method is m and p.scene == scene and p.ok
                         and math.isfinite(p.reac_err)], key=lambda p: -p.h)
            if not ps:
                continue
            c, mk, _ = STYLES.get(m.key, ("tab:gray", ".", "-"))
            ax.loglog([p.per_sim_s() for p in ps], [max(p.reac_err, 1e-16) for p in ps],
                      color=c, marker=mk, ls=ls, ms=4)
    ax.set_title("legsim joint reactions: max |R - R_ref| at t = 0.1 s vs time")
    ax.set_xlabel("wall time per simulated second (s), median")
    ax.set_ylabel("reaction error (N, N m)")
    ax.grid(True, which="both", alpha=0.3)
    # colours and markers as above; the legend only says which line style is which scene
    ax.legend([Line2D([], [], color="k", ls=ls) for ls in SCENE_LINES[:len(scenes)]],
              list(scenes), fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0),
              title="scene", title_fontsize=8)
    ax = axes[1][1]
    prec_colour = {"double": "tab:blue", "float": "tab:pink"}
    for r in id_rows:
        for key, mk, what in (("force_err", "o", "actuator forces (N)"),
                              ("reac_err", "s", "reactions (N, N m)"),
                              ("pos_err", "^", "positions (m, rad)")):
            ax.semilogy([r["per_call_s"] * 1e6], [max(r[key], 1e-16)], marker=mk, ls="", ms=7,
                        color=prec_colour.get(r["precision"], "tab:gray"),
                        label=f"{r['precision']}: {what}")
    ax.set_title("inverse dynamics (length sinusoid): error vs time per call")
    ax.set_xlabel("time per legsim_inverse_dynamics call (us), median")
    ax.set_ylabel("max error over 50 samples (N, N m, m)")
    ax.margins(x=0.25)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(5))
    ax.grid(True, which="both", alpha=0.3)
    if id_rows:
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    for ax in (*axes[0], axes[1][0]):  # over less than a decade the minor labels overlapped
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def write_md(path: Path, pts, meths, scenes, steps, conv, ratios, id_rows, info, libinfo, refs,
             quick, elapsed, png_name, ratios_beyond=None, beyond=(), info_end=None) -> None:
    L = []
    a = L.append
    a("# Work-precision: legsim vs Exudyn and MuJoCo on the leg")
    a("")
    a(f"Generated by `legsim-bench workprecision{' --quick' if quick else ''}` "
      f"(bench/legsim_bench/benchmarks/workprecision.py) in {elapsed:.0f} s.")
    a("")
    L.extend(results.machine_section(info, info_end)[:-1])
    a("- the machine may be shared: timings scatter, which is why repetitions are interleaved "
      "across engines and medians are used")
    a(f"- Python {info['python']}, numpy {info['numpy']}, scipy {info['scipy']}, matplotlib "
      f"{info['matplotlib']}, exudyn {info.get('exudyn', '?')}, mujoco {info.get('mujoco', '?')}")
    for prec, s in libinfo.items():
        a(f"- legsim {prec}: {s}")
    a("")
    a("## Method")
    a("")
    a(f"- Scenes: {', '.join(scenes)} (revolute knee), from the stand pose at rest, to t = {T_END} s. "
      "The reference (legsim_bench.reference: minimal coordinates, DOP853, rtol = atol = "
      f"{REF_TOL:g}) stays inside the strokes: "
      + "; ".join(f"{s}: out_of_stroke={refs[s]['out_of_stroke']}" for s in scenes) + ".")
    a("- Error: max |q - q_ref| over the 18 absolute coordinates (m and rad) at t = 0.1 s; for "
      "legsim also max |R - R_ref| over the 8 joints' (Fx, Fy, M) (N, N m). The peers' reactions "
      "are not compared (Exudyn's prismatic multipliers are scaled differently, MuJoCo's loop "
      "closures are soft; see peers/README.md).")
    a(f"- Step sizes: {', '.join(f'{h:g}' for h in steps)} s (each divides 0.1 s)"
      + (f"; also {', '.join(f'{h:g}' for h in beyond)} s, beyond the range, reported apart "
         "and left out of the main ratio table." if beyond else "."))
    a("- Time: wall time of the integration only per simulated second, measured inside this "
      "process: legsim through one `legsim_step(sim, n)` ctypes call around "
      "`time.perf_counter_ns` (a fresh sim per repetition; nothing subtracted), the peers by "
      "their own `wall_s` around `SolveDynamic` / `mujoco.rollout`, minus each engine's per-call "
      "set-up (the median wall time of a one-step run, 0.1-0.2 ms) so that start-up is excluded. "
      "Median over the repetitions (quartiles in the CSV); repetitions are interleaved over all "
      "engines and step sizes.")
    a("- legsim options: the defaults (`legsim_default_options`: newton_tol 1e-10 double / 1e-5 "
      "float, rho_inf 0.8, 25 iterations), plus RK4 with newton_tol 1e-13 as a separate curve.")
    a("")
    a("## Peer convergence (checked before timing)")
    a("")
    a("| peer method | scene | converges to the reference | evidence |")
    a("|---|---|---|---|")
    for (key, scene), (ok, txt) in conv.items():
        a(f"| {key} | {scene} | {'yes' if ok else 'NO (left out of the ratio)'} | {txt} |")
    a("")
    a(f"## Ratio of legsim's time to the best peer's at equal error (target <= {TARGET_RATIO:g})")
    a("")
    a("Time at an error level is interpolated log-log along each method's work-precision front "
      "(the points that are more accurate than every cheaper one). 'legsim' is the fastest "
      "double-precision legsim curve at that error; 'best peer' the fastest converged peer. "
      "A star (*) marks a curve whose largest step in the range (h = 1e-2 s) is already more "
      "accurate than the level: its time there is that step's time (a step larger than the "
      "range might be cheaper, for legsim and the peers alike).")
    a("")
    for scene in scenes:
        a(f"### {scene}")
        a("")
        a("| error level | legsim (method) | legsim s per sim s | best peer (method) | peer s per sim s | ratio legsim/peer | target |")
        a("|---|---|---|---|---|---|---|")
        for r in ratios[scene]:
            bl = "* " if r["kind_legsim"] == "range" else ""
            bp = "* " if r["kind_peer"] == "range" else ""
            a(f"| {r['E']:.0e} | {r['legsim'] or '—'} | {bl}{fmt(r['t_legsim'])} | "
              f"{r['peer'] or '—'} | {bp}{fmt(r['t_peer'])} | {fmt(r['ratio'], '.3g')} | "
              f"{r['verdict']} |")
        a("")
    a("### Summary")
    a("")
    for scene in scenes:
        met = [f"{r['E']:.0e}" for r in ratios[scene] if r["verdict"].startswith("met")]
        notmet = [f"{r['E']:.0e} ({fmt(r['ratio'], '.2g')})" for r in ratios[scene]
                  if not r["verdict"].startswith("met")]
        a(f"- {scene}: target met at {', '.join(met) or 'no level'}; not met at "
          f"{', '.join(notmet) or 'no level'}.")
    a("- Where legsim is starred its largest step of the range, h = 1e-2 s, is already more "
      "accurate than the level: the range stops legsim from trading accuracy for time there, "
      "and its cost is the cost of 10 steps per 0.1 s (per-step cost, not accuracy, decides "
      "these rows).")
    a("")
    if ratios_beyond:
        a(f"### Beyond the range: steps up to {max(beyond):g} s")
        a("")
        a(f"The issue's range stops at h = 1e-2 s. The same comparison with the steps "
          f"{', '.join(f'{h:g}' for h in beyond)} s added for every engine (measured and timed "
          "like the others; at 2 to 5 steps per run the peers' time is dominated by the per-call "
          "set-up that is subtracted, so their figures here are rough):")
        a("")
        a("| error level | scene | legsim (method) | legsim s per sim s | best peer (method) | peer s per sim s | ratio | target |")
        a("|---|---|---|---|---|---|---|---|")
        for scene in scenes:
            for r in ratios_beyond[scene]:
                bl = "* " if r["kind_legsim"] == "range" else ""
                bp = "* " if r["kind_peer"] == "range" else ""
                a(f"| {r['E']:.0e} | {scene} | {r['legsim'] or '—'} | {bl}{fmt(r['t_legsim'])} | "
                  f"{r['peer'] or '—'} | {bp}{fmt(r['t_peer'])} | {fmt(r['ratio'], '.3g')} | "
                  f"{r['verdict'].split(' (')[0]} |")
        a("")
    a("## All measurements")
    a("")
    a(f"![work-precision]({png_name})")
    a("")
    for scene in scenes:
        a(f"### {scene}")
        a("")
        a("| method | h (s) | position error | reaction error (N) | max abs Phi | s per sim s (median) | [p25, p75] | peer set-up subtracted | reps |")
        a("|---|---|---|---|---|---|---|---|---|")
        for m in meths:
            for p in sorted([p for p in pts if p.method is m and p.scene == scene], key=lambda p: -p.h):
                if not p.ok:
                    a(f"| {m.key} | {p.h:g} | FAILED: {p.status} | | | | | | |")
                    continue
                a(f"| {m.key} | {p.h:g} | {fmt(p.pos_err)} | {fmt(p.reac_err)} | "
                  f"{fmt(p.residual, '.1e')} | {fmt(p.per_sim_s(corrected=not m.is_legsim), '.3e')} | "
                  f"[{fmt(p.per_sim_s(25), '.2e')}, {fmt(p.per_sim_s(75), '.2e')}] | "
                  f"{'yes' if p.overheads else 'no'} | {len(p.walls)} |")
        a("")
    a("## Inverse dynamics: the length sinusoid")
    a("")
    a(f"l(t) = l_stand + {ID_AMPLITUDE} sin(2 pi {ID_FREQUENCY:g} t) on both actuators, "
      f"{ID_SAMPLES} samples over one period; `legsim_inverse_dynamics` (lengths, rates, "
      "accelerations; it assembles from the previous sample's pose) against the reference's "
      "closed-form poses and Newton-Euler inverse dynamics. The time is per call (median over "
      "repetitions of the 50-sample sweep), including the ctypes call cost shown. Neither peer "
      "is measured here: this bench has no like-for-like inverse dynamics of the closed loops "
      "in Exudyn or MuJoCo (MuJoCo's `mj_inverse` works on its soft loop closures).")
    a("")
    a("| build | max actuator-force error (N) | max reaction error (N, N m) | max q error (m, rad) | largest |F| / |R| (N) | us per call (median [p25, p75]) | ctypes call alone (us) | s per simulated s at 1 kHz |")
    a("|---|---|---|---|---|---|---|---|")
    for r in id_rows:
        a(f"| {r['precision']} | {r['force_err']:.2e} | {r['reac_err']:.2e} | {r['pos_err']:.2e} | "
          f"{r['max_force']:.1f} / {r['max_reaction']:.1f} | {r['per_call_s'] * 1e6:.2f} "
          f"[{r['per_call_p25'] * 1e6:.2f}, {r['per_call_p75'] * 1e6:.2f}] | "
          f"{r['ctypes_call_s'] * 1e6:.2f} | {r['per_call_s'] * 1e3:.2e} |")
    a("")
    path.write_text("\n".join(L) + "\n")


# ---------------------------------------------------------------- command
def configure_parser(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.description = __doc__.split("\n\n")[0]
    p.add_argument("--quick", action="store_true",
                   help="3 step sizes, few repetitions (about a minute); writes workprecision_quick.*")
    results.add_output_options(p)
    p.add_argument("--step-sizes", type=float, nargs="+", default=None, metavar="H",
                   help="step sizes (s), each dividing 0.1 s (default 1e-2 ... 1e-5)")
    results.refuse_renamed(p, "--steps", "--step-sizes", "step sizes in s")
    p.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    p.add_argument("--no-peers", action="store_true", help="legsim only")
    p.add_argument("--no-float", action="store_true", help="double build only")
    p.add_argument("--no-beyond", action="store_true",
                   help="do not add the steps 5e-2 and 2e-2 beyond the issue's range")
    p.add_argument("--target-s", type=float, default=None,
                   help="timing budget per point (s of repeated runs); default 1.0 (quick 0.15)")
    p.add_argument("--min-reps", type=int, default=None)
    p.add_argument("--max-reps", type=int, default=None)
    return p


def run(args) -> int:
    t_start = time.time()
    quick = bool(getattr(args, "quick", False))
    steps = tuple(args.step_sizes) if args.step_sizes else (QUICK_STEPS if quick else STEPS)
    beyond = () if (quick or args.no_beyond or args.step_sizes) else STEPS_BEYOND
    for h in steps:
        if abs(T_END / h - round(T_END / h)) > 1e-9:
            print(f"step {h} does not divide {T_END} s", file=sys.stderr)
            return 2
    target_s = args.target_s if args.target_s is not None else (0.15 if quick else 1.0)
    min_reps = args.min_reps if args.min_reps is not None else (3 if quick else 7)
    max_reps = args.max_reps if args.max_reps is not None else (15 if quick else 61)
    out = results.output_dir(args)
    out.mkdir(parents=True, exist_ok=True)
    stem = "workprecision_quick" if quick else "workprecision"

    def log(s):
        print(s, flush=True)

    if not legsim.library_available("double"):
        print(str(legsim.LibraryNotFound("liblegsim.so not built")), file=sys.stderr)
        try:
            legsim.find_library("double")
        except legsim.LibraryNotFound as e:
            print(e, file=sys.stderr)
        return 2
    info = machine_info()
    scenes = list(args.scenes)
    meths = methods(with_float=not args.no_float, with_peers=not args.no_peers)
    log(f"# methods: {', '.join(m.key for m in meths)}")
    log("# reference (DOP853, rtol 1e-13)")
    refs = {s: reference_end(s) for s in scenes}
    log("# accuracy (one run per point)")
    pts = measure_accuracy(meths, scenes, tuple(beyond) + tuple(steps), refs, log)
    conv = {}
    for m in meths:
        if m.is_legsim:
            continue
        for s in scenes:
            conv[(m.key, s)] = convergence_check(pts, m, s)
            log(f"  convergence {m.key} {s}: {'ok' if conv[(m.key, s)][0] else 'NO'} "
                f"({conv[(m.key, s)][1]})")
    # peers that do not converge are not timed
    for p in pts:
        if not p.method.is_legsim and not conv[(p.method.key, p.scene)][0]:
            p.walls = []
    plan = timing_plan(pts, target_s, min_reps, max_reps)
    for i in plan:  # the accuracy run was a warm-up: time afresh
        pts[i].walls = []
    log(f"# timing ({sum(plan.values())} runs, interleaved)")
    measure_timing(pts, plan, log)
    log("# inverse dynamics (length sinusoid)")
    id_rows = inverse_dynamics_study(("double",) if args.no_float else ("double", "float"),
                                     reps=20 if quick else 200, log=log)
    ratios = {s: ratio_table(pts, meths, s, conv) for s in scenes}
    ratios_beyond = ({s: ratio_table(pts, meths, s, conv, max_h=max(beyond)) for s in scenes}
                     if beyond else None)
    info_end = results.snapshot()
    csv_path, md_path, png_path = out / f"{stem}.csv", out / f"{stem}.md", out / f"{stem}.png"
    write_csv(csv_path, pts)
    have_png = plot(png_path, pts, meths, scenes, id_rows)
    write_md(md_path, pts, meths, scenes, steps, conv, ratios, id_rows, info, library_info(),
             refs, quick, time.time() - t_start, png_path.name if have_png else "(matplotlib absent)",
             ratios_beyond=ratios_beyond, beyond=beyond, info_end=info_end)
    log(f"# wrote {csv_path}, {md_path}" + (f", {png_path}" if have_png else ""))
    for s in scenes:
        log(f"## {s}")
        for r in ratios[s]:
            log(f"  E={r['E']:.0e}: legsim {r['legsim']} {fmt(r['t_legsim'])} ({r['kind_legsim']}), "
                f"peer {r['peer']} {fmt(r['t_peer'])} ({r['kind_peer']}): {r['verdict']}")
    return 0


def main(argv=None) -> int:
    p = configure_parser(argparse.ArgumentParser(prog="legsim-bench workprecision"))
    return run(p.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
