"""Work-precision of legsim against MuJoCo on the leg, every engine in compiled code.

    legsim-bench workprecision [--quick] [--step-sizes H...] [--out DIR | --update-results]
    python -m legsim_bench.benchmarks.workprecision [--quick] [--out DIR]      (from bench/)

Scenes (revolute knee, from the stand pose at rest, constant actuator forces):
``upper_step_50N`` (50 N on the upper actuator, 1 s) and ``driven_2s`` (50 N upper,
-30 N lower, 2 s). At each fixed step h from 2e-2 to 5e-6 s, for legsim (RK4 +
projection, generalized-alpha) and MuJoCo (RK4, semi-implicit Euler):

* error: the largest deviation of any of the 18 absolute coordinates (m, rad) from the
  bench's independent reference (legsim_bench.reference: minimal coordinates, DOP853 at
  rtol = atol = 1e-13), maximised over the trajectory sampled every 0.02 s from
  t = 0.1 s to the end;
* cost: instructions per simulated second (valgrind callgrind, the drivers' run_steps()
  only, over the first 1,000 steps or the whole run if shorter) and wall time per
  simulated second (the minimum over repetitions of the whole run, run_steps() only).

The engines run from small C drivers (compiled.py, drivers/*.c) built at run time: legsim
against liblegsim.so (the library the Python API loads), MuJoCo against the mujoco
wheel's own libmujoco and headers. The same work for all: legsim's reactions off
(LEGSIM_DISABLE_REACTIONS; MuJoCo computes its constraint forces in every step anyway)
and its stroke stops off (the reference and the MJCF have none; the 50 N scene passes
the lower actuator's stroke end near t = 0.8 s); MuJoCo with islands off, Newton
solver, loop closures solref = (2 h, 1) (time constant 2 h, critical damping: the
stiffest refsafe admits) and solimp 0.9999.

Every peer method is first checked to converge to the reference (the error falls over
the finest three steps and is below 1e-3 at the finest); one that does not is left out
of the ratio. The ratio: legsim's cost over the best peer's at errors 1e-4 ... 1e-10,
each interpolated log-log along each method's work-precision front.

Outputs (``--out``, default out/bench-results/; ``--update-results``: bench/results/):
workprecision.md, .csv, .png; ``--quick`` (3 steps, 2 repetitions, no reference
cross-check) writes workprecision_quick.* instead.
"""
from __future__ import annotations

import argparse
import csv
import math
import platform
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import legsim

from ..reference import ForceCommand, LegModel
from . import compiled
from . import core as lc
from . import results

REPO_ROOT = lc.REPO_ROOT
MODEL_TOML = REPO_ROOT / "models" / "leg.toml"


@dataclass(frozen=True)
class Scene:
    upper_n: float   # constant axial force on the upper actuator (N, > 0 extends)
    lower_n: float
    t_end: float     # s
    text: str


SCENES = {
    "upper_step_50N": Scene(50.0, 0.0, 1.0, "50 N on the upper actuator from t = 0, 1 s"),
    "driven_2s": Scene(50.0, -30.0, 2.0, "50 N on the upper and -30 N on the lower actuator, 2 s"),
}
T_FROM = 0.1       # s: the error is taken from here to the end
SAMPLE_DT = 0.02   # s: every step size divides it
STEPS = (2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6)
QUICK_STEPS = (1e-2, 1e-3, 1e-4)
ERROR_LEVELS = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
TARGET_RATIO = 0.1
REF_TOL = 1e-13
COUNT_STEPS = 1000  # callgrind: the first steps of each run (all of a shorter run)
LEGSIM_DISABLE = compiled.DISABLE_REACTIONS | compiled.DISABLE_STROKE_LIMITS
LEGSIM_DISABLE_REACTIONS_ON = compiled.DISABLE_STROKE_LIMITS
MUJOCO_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)


# ---------------------------------------------------------------- methods
@dataclass(frozen=True)
class Method:
    key: str
    engine: str       # "legsim" / "mujoco"
    integrator: str   # legsim: rk4 / galpha; mujoco: rk4 / euler
    tol: float        # legsim newton_tol; MuJoCo solver tolerance
    label: str
    reactions: bool = False  # legsim: reactions computed every step (not in the main ratio)


LEGSIM_METHODS = (
    Method("legsim/rk4", "legsim", "rk4", 1e-10, "legsim RK4 + projection (newton_tol 1e-10)"),
    Method("legsim/rk4-tol1e-13", "legsim", "rk4", 1e-13, "legsim RK4 + projection, newton_tol 1e-13"),
    Method("legsim/galpha", "legsim", "galpha", 1e-10, "legsim generalized-alpha (rho_inf 0.8)"),
    Method("legsim/rk4-reactions", "legsim", "rk4", 1e-10, "legsim RK4 + projection, reactions on",
           reactions=True),
)
MUJOCO_METHODS = (
    Method("mujoco/rk4", "mujoco", "rk4", 1e-12, "MuJoCo RK4, Newton tolerance 1e-12"),
    Method("mujoco/rk4-tol1e-8", "mujoco", "rk4", 1e-8, "MuJoCo RK4, Newton tolerance 1e-8 (its default)"),
    Method("mujoco/euler", "mujoco", "euler", 1e-12, "MuJoCo semi-implicit Euler, tolerance 1e-12"),
)


class Engines:
    """The built drivers and what turns their output into the 18 coordinates."""

    def __init__(self, build_dir: Path, with_peers: bool = True):
        self.dir = build_dir
        self.legsim_lib = Path(legsim.find_library("double")).resolve()
        self.legsim_exe = compiled.build_legsim(build_dir, REPO_ROOT, self.legsim_lib)
        self.mujoco_exe = None
        self.mujoco_why = "not asked for (--no-peers)"
        self.mujoco_version = None
        if with_peers:
            try:   # the peers (MuJoCo, optional and heavy) only when asked for
                from .peers import leg_model, mujoco_leg
                if not mujoco_leg.available():
                    raise compiled.DriverError("mujoco is not importable")
                self.mujoco_exe = compiled.build_mujoco(build_dir)
                self._ml, self._leg = mujoco_leg, leg_model.load(MODEL_TOML)
                self.mujoco_version = mujoco_leg.VERSION
                # forward kinematics only: the scene and h of this instance do not matter
                self._kin = mujoco_leg.MujocoLeg("free_fall", 1e-3, islands=False)
                self.mujoco_why = ""
            except (ImportError, compiled.DriverError) as e:
                self.mujoco_why = str(e)

    def methods(self) -> list[Method]:
        return list(LEGSIM_METHODS) + (list(MUJOCO_METHODS) if self.mujoco_exe else [])

    def mjcf(self, m: Method, h: float) -> str:
        return self._ml.build_xml(self._leg, h, m.integrator, tolerance=m.tol,
                                  solimp=MUJOCO_SOLIMP, islands=False)

    def run(self, m: Method, scene: str, h: float) -> compiled.Run:
        sc = SCENES[scene]
        if m.engine == "legsim":
            return compiled.Run(self.legsim_exe, (m.integrator, repr(h), repr(sc.t_end),
                                                  repr(sc.upper_n), repr(sc.lower_n),
                                                  LEGSIM_DISABLE_REACTIONS_ON if m.reactions
                                                  else LEGSIM_DISABLE, repr(m.tol)))
        xml = self.dir / "mjcf" / f"{m.key.replace('/', '_')}_h{h:g}.xml"
        xml.parent.mkdir(parents=True, exist_ok=True)
        xml.write_text(self.mjcf(m, h))
        return compiled.Run(self.mujoco_exe, (xml, repr(sc.t_end), repr(sc.upper_n),
                                              repr(sc.lower_n)))

    def coordinates(self, m: Method, x: np.ndarray) -> np.ndarray:
        """The 18 absolute coordinates from a driver's rows (legsim: already q; MuJoCo: qpos)."""
        if m.engine == "legsim":
            return x
        return np.array([self._kin.q_of(row) for row in x])


# ---------------------------------------------------------------- reference and error
def sample_times(t_end: float) -> np.ndarray:
    return np.arange(int(round(t_end / SAMPLE_DT)) + 1) * SAMPLE_DT


def reference(scene: str, tol: float = REF_TOL) -> np.ndarray:
    """q of the bench's reference at sample_times (rows of 18)."""
    sc = SCENES[scene]
    model = LegModel.from_toml(str(MODEL_TOML))
    r = model.simulate(sc.t_end, t_eval=sample_times(sc.t_end),
                       actuators=[ForceCommand(sc.upper_n), ForceCommand(sc.lower_n)],
                       rtol=tol, atol=tol)
    return np.asarray(r.q)


def trajectory_error(t: np.ndarray, q: np.ndarray, t_ref: np.ndarray, q_ref: np.ndarray,
                     t_from: float = T_FROM) -> float:
    """max over the samples with t >= t_from of max_i |q_i - q_ref_i| (same sample times)."""
    t, t_ref = np.asarray(t, float), np.asarray(t_ref, float)
    if t.shape != t_ref.shape or np.max(np.abs(t - t_ref)) > 1e-9:
        raise ValueError("the trajectory and the reference are not sampled at the same times")
    keep = t >= t_from - 1e-12
    if not np.any(keep):
        raise ValueError(f"no sample at or after t = {t_from} s")
    return float(np.max(np.abs(np.asarray(q)[keep] - np.asarray(q_ref)[keep])))


# ---------------------------------------------------------------- measurement
@dataclass
class Point:
    method: Method
    scene: str
    h: float
    ok: bool = False
    status: str = ""
    err: float = float("nan")
    wall_min: float = float("nan")    # s, the whole run
    wall_mean: float = float("nan")
    reps: int = 0
    instr: float = float("nan")      # instructions per step
    counted: int = 0

    @property
    def t_end(self) -> float:
        return SCENES[self.scene].t_end

    @property
    def n_steps(self) -> int:
        return int(round(self.t_end / self.h))

    def cost(self, kind: str) -> float:
        """Per simulated second: 'instr' instructions, 'wall' seconds (minimum)."""
        if kind == "instr":
            return self.instr / self.h
        return self.wall_min / self.t_end


def measure(engines: Engines, meths, scenes, steps, refs, log, *, reps_budget_s: float,
            min_reps: int, max_reps: int, callgrind: bool, count_steps: int) -> list[Point]:
    pts = []
    for scene in scenes:
        t_ref = sample_times(SCENES[scene].t_end)
        for m in meths:
            for h in steps:
                p = Point(m, scene, h)
                run = engines.run(m, scene, h)
                try:
                    t, x = run.trajectory(SAMPLE_DT)
                    p.err = trajectory_error(t, engines.coordinates(m, x), t_ref, refs[scene])
                    p.ok = math.isfinite(p.err)
                    p.status = "ok" if p.ok else "non-finite state"
                except compiled.DriverError as e:
                    p.status = str(e).splitlines()[-1]
                if p.ok:
                    est = p.n_steps * 2e-5  # s, a rough guess for the repetition count
                    reps = int(min(max_reps, max(min_reps, math.ceil(reps_budget_s / est))))
                    p.wall_min, p.wall_mean, _ = run.wall(reps)
                    p.reps = reps
                    if callgrind:
                        ir, p.counted = run.instructions(
                            count_steps, engines.dir / "callgrind" / f"{m.key.replace('/', '_')}_"
                            f"{scene}_h{h:g}.out")
                        p.instr = ir / p.counted
                pts.append(p)
                log(f"  {scene:15s} {m.key:20s} h={h:.0e} " + (
                    f"err {p.err:.2e}, {p.wall_min / p.n_steps * 1e6:.2f} us/step (min of {p.reps})"
                    + (f", {p.instr:,.0f} instr/step" if math.isfinite(p.instr) else "")
                    if p.ok else f"FAILED ({p.status})"))
    return pts


def convergence_check(pts, m: Method, scene: str) -> tuple[bool, str]:
    """(converged, evidence): every step ran, the error falls over the finest three steps and
    the finest error is below 1e-3."""
    ps = sorted([p for p in pts if p.method == m and p.scene == scene], key=lambda p: -p.h)
    good = [p for p in ps if p.ok]
    failed = [f"{p.h:.0e}" for p in ps if not p.ok]
    if len(good) < 2:
        return False, "fewer than two successful steps" + (f"; failed at h = {', '.join(failed)}"
                                                          if failed else "")
    tail = good[-3:]
    falls = all(a.err > b.err for a, b in zip(tail, tail[1:]))
    ok = falls and good[-1].err < 1e-3
    return ok, (f"{good[0].err:.1e} at h = {good[0].h:.0e} -> {good[-1].err:.1e} at h = "
                f"{good[-1].h:.0e}" + ("" if falls else ", not falling")
                + (f"; failed at h = {', '.join(failed)}" if failed else ""))


# ---------------------------------------------------------------- the ratio
def front(points) -> list:
    """Work-precision front of (error, cost) pairs: cost ascending, error strictly falling."""
    pts = sorted((c, e) for e, c in points if math.isfinite(e) and math.isfinite(c) and e > 0
                 and c > 0)
    out, best = [], float("inf")
    for c, e in pts:
        if e < best:
            out.append((e, c))
            best = e
    return out


def cost_at_error(points, E: float) -> tuple[float, str]:
    """(cost, kind) to reach error E: 'interp' log-log along the front; 'range' the largest
    step measured is already more accurate than E (its cost; a larger step might be
    cheaper); 'unreached' no step measured reaches E."""
    f = front(points)
    if not f or f[-1][0] > E:
        return float("nan"), "unreached"
    if f[0][0] <= E:
        return f[0][1], "range"
    for (e0, c0), (e1, c1) in zip(f, f[1:]):
        if e0 > E >= e1:
            x = (math.log(E) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(c0) + x * (math.log(c1) - math.log(c0))), "interp"
    return float("nan"), "unreached"


def curve(pts, m: Method, scene: str, kind: str) -> list:
    return [(p.err, p.cost(kind)) for p in pts if p.method == m and p.scene == scene and p.ok]


def ratio_table(pts, meths, scene: str, conv: dict, kind: str, reactions: bool = False) -> list[dict]:
    """Per error level: the cheapest legsim method (reactions off, or on with ``reactions``)
    and the cheapest converged peer, their costs and kinds, and the ratio."""
    legs = [m for m in meths if m.engine == "legsim" and m.reactions == reactions]
    peers = [m for m in meths if m.engine != "legsim" and conv.get((m.key, scene), (False,))[0]]
    rows = []
    for E in ERROR_LEVELS:
        row = {"E": E}
        for side, group in (("legsim", legs), ("peer", peers)):
            got = [(cost_at_error(curve(pts, m, scene, kind), E), m) for m in group]
            got = [g for g in got if g[0][1] != "unreached"]
            if got:
                (c, k), m = min(got, key=lambda g: g[0][0])
                row.update({side: m.key, f"c_{side}": c, f"k_{side}": k})
            else:
                row.update({side: None, f"c_{side}": float("nan"), f"k_{side}": "unreached"})
        row["ratio"] = row["c_legsim"] / row["c_peer"]
        rows.append(row)
    return rows


# ---------------------------------------------------------------- output
def fmt(x, spec=".2e") -> str:
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def describe_source(src: Path) -> str:
    """A source tree and its commit (git, or the COMMIT file of an exported tree)."""
    c = results.commit(Path(src), paths=("firmware_core", "cmake", "CMakeLists.txt",
                                          "CMakePresets.json", "models"))
    return f"{src}" + ("" if c.startswith("unknown") else f" at {c}")


def library_info(lib: Path) -> str:
    cache = next((d / "CMakeCache.txt" for d in (lib.parent, lib.parent.parent)
                  if (d / "CMakeCache.txt").is_file()), None)
    bt, src = "?", None
    if cache:
        for line in cache.read_text().splitlines():
            if line.startswith("CMAKE_BUILD_TYPE:"):
                bt = line.split("=", 1)[1]
            if line.startswith("CMAKE_HOME_DIRECTORY:"):
                src = line.split("=", 1)[1]
    return f"{lib} (CMAKE_BUILD_TYPE={bt}" + (f", source {describe_source(src)}" if src else "") + ")"


def write_csv(path: Path, pts) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scene", "method", "h_s", "ok", "status", "max_error", "steps",
                    "wall_min_s", "wall_mean_s", "reps", "us_per_step_min",
                    "instructions_per_step", "steps_counted", "instructions_per_sim_s",
                    "wall_per_sim_s_min"])
        for p in pts:
            w.writerow([p.scene, p.method.key, f"{p.h:g}", int(p.ok), p.status, f"{p.err:.6e}",
                        p.n_steps, f"{p.wall_min:.6e}", f"{p.wall_mean:.6e}", p.reps,
                        f"{p.wall_min / p.n_steps * 1e6:.4f}", f"{p.instr:.1f}", p.counted,
                        f"{p.cost('instr'):.6e}", f"{p.cost('wall'):.6e}"])


STYLES = {"legsim/rk4": ("tab:blue", "o"), "legsim/rk4-reactions": ("tab:olive", "v"),
          "legsim/rk4-tol1e-13": ("tab:cyan", "P"),
          "legsim/galpha": ("tab:green", "s"), "mujoco/rk4": ("tab:purple", "D"),
          "mujoco/rk4-tol1e-8": ("tab:red", "^"), "mujoco/euler": ("tab:brown", "x")}


def plot(path: Path, pts, meths, scenes, kinds) -> bool:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    xlabel = {"instr": "instructions per simulated second (callgrind)",
              "wall": "wall time per simulated second (s, minimum)"}
    fig, axes = plt.subplots(len(kinds), len(scenes), figsize=(6 * len(scenes), 4.5 * len(kinds)),
                             squeeze=False, constrained_layout=True)
    for i, kind in enumerate(kinds):
        for j, scene in enumerate(scenes):
            ax = axes[i][j]
            for m in meths:
                c = sorted(curve(pts, m, scene, kind), key=lambda ec: ec[1])
                if c:
                    col, mk = STYLES.get(m.key, ("tab:gray", "."))
                    ax.loglog([x for _, x in c], [e for e, _ in c], marker=mk, color=col,
                              label=m.key)
            for E in ERROR_LEVELS:
                ax.axhline(E, color="0.85", lw=0.6, zorder=0)
            ax.set_title(f"{scene} ({SCENES[scene].t_end:g} s)")
            ax.set_xlabel(xlabel[kind])
            ax.set_ylabel(f"max coordinate error, t = {T_FROM:g} s to the end (m, rad)")
            ax.grid(True, which="major", alpha=0.3)
            ax.legend(fontsize=7)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return True


def write_md(path: Path, *, pts, meths, scenes, steps, conv, ratios, ratios_on, info, info_end, engines,
             ref_spread, quick, elapsed, png_name, kinds, count_steps) -> None:
    L = []
    a = L.append
    a("# Work-precision: legsim vs MuJoCo on the leg, compiled drivers")
    a("")
    a(f"Generated by `legsim-bench workprecision{' --quick' if quick else ''}` "
      f"(bench/legsim_bench/benchmarks/workprecision.py) in {elapsed:.0f} s.")
    a("")
    L.extend(results.machine_section(info, info_end)[:-1])
    a(f"- legsim: {library_info(engines.legsim_lib)}")
    if engines.mujoco_exe:
        a(f"- MuJoCo {engines.mujoco_version}: the wheel's {compiled.mujoco_library()}")
    else:
        a(f"- MuJoCo: not run ({engines.mujoco_why})")
    a(f"- drivers: {engines.dir}/ (`{compiled.cc()} {' '.join(compiled.CFLAGS)}`); valgrind "
      "callgrind for the instruction counts")
    a("")
    a("## Method")
    a("")
    a("- Scenes (revolute knee, stand pose at rest, constant forces): "
      + "; ".join(f"`{s}`: {SCENES[s].text}" for s in scenes) + ".")
    a(f"- Error: max over the samples t = {T_FROM:g}, {T_FROM + SAMPLE_DT:g}, ... s to the end "
      "of max |q_i - q_ref,i| over the 18 absolute coordinates (m, rad). Reference: "
      f"legsim_bench.reference (minimal coordinates, DOP853, rtol = atol = {REF_TOL:g})"
      + (f"; it differs from the same at 1e-12 by at most {', '.join(f'{s}: {v:.1e}' for s, v in ref_spread.items())}."
         if ref_spread else "."))
    a(f"- Step sizes: {', '.join(f'{h:g}' for h in steps)} s.")
    a("- Every engine runs from a small C driver (drivers/legsim_wp.c, drivers/mujoco_wp.c) "
      "compiled at run time; both time and count the same function, `run_steps()`, which only "
      "steps (legsim: one `legsim_step(sim, n)`; MuJoCo: n `mj_step` calls). Set-up (legsim_init "
      "+ assembly; mj_loadXML + mj_makeData + mj_resetData) is outside it for both.")
    a("- Wall time: the minimum over repetitions (2 to 20, about 1 s per point) of the whole "
      "run, per simulated second. Instructions: valgrind callgrind "
      f"`--toggle-collect=run_steps` over the first {count_steps:,} steps (all of a shorter run), "
      "per step, times 1/h; they do not move with the machine's load.")
    a("- The same work: legsim with reactions off (`LEGSIM_DISABLE_REACTIONS`; MuJoCo's step "
      "computes its constraint forces anyway; `legsim/rk4-reactions` has them on and its own "
      "ratio column) and stroke stops off "
      "(`LEGSIM_DISABLE_STROKE_LIMITS`: the reference and the MJCF have none); default "
      "options otherwise (rho_inf 0.8, 25 iterations).")
    a("- MuJoCo: islands off (`island=\"disable\"`, `mjDSBL_ISLAND`), contacts off, Newton "
      "solver (100 iterations, 50 line-search), loop closures as two `connect` equalities "
      "with solref = (2 h, 1): soft-constraint time constant 2 h (20 ms at h = 1e-2 s, 20 us at "
      "1e-5 s), damping ratio 1, the stiffest MuJoCo's refsafe rule admits, and solimp "
      f"{MUJOCO_SOLIMP} (impedance 0.9999, the largest allowed).")
    a("")
    a("## Peer convergence (checked before the ratio)")
    a("")
    a("| peer method | scene | converges | evidence |")
    a("|---|---|---|---|")
    for (key, scene), (ok, txt) in conv.items():
        a(f"| {key} | {scene} | {'yes' if ok else 'NO (left out of the ratio)'} | {txt} |")
    a("")
    a(f"## Ratio legsim cost / best peer cost at equal error (goal <= {TARGET_RATIO:g})")
    a("")
    a("Cost at an error level is interpolated log-log along each method's work-precision front; "
      "'legsim' is the cheapest legsim method at that level, 'peer' the cheapest converged peer "
      f"method. A star marks a method whose largest step ({max(steps):g} s) is already more "
      "accurate than the level (its cost there; a larger step might be cheaper).")
    a("")
    names = {"instr": "instructions per simulated second", "wall": "wall seconds per simulated second"}
    for scene in scenes:
        a(f"### {scene}")
        a("")
        a("| error | " + " | ".join(f"ratio ({k})" for k in kinds)
          + f" | ratio ({kinds[0]}), legsim reactions on | legsim method | "
          + " | ".join(f"legsim {names[k]}" for k in kinds) + " | peer method | "
          + " | ".join(f"peer {names[k]}" for k in kinds) + " |")
        a("|---" * (4 + 3 * len(kinds)) + "|")
        r0 = ratios[(scene, kinds[0])]
        for i, E in enumerate(ERROR_LEVELS):
            rs = [ratios[(scene, k)][i] for k in kinds]
            star = lambda r, s: "*" if r[f"k_{s}"] == "range" else ""  # noqa: E731
            a(f"| {E:.0e} | " + " | ".join(fmt(r["ratio"], ".3g") for r in rs)
              + f" | {fmt(ratios_on[scene][i]['ratio'], '.3g')} | {r0[i]['legsim'] or '—'} | "
              + " | ".join(star(r, "legsim") + fmt(r["c_legsim"], ".3g") for r in rs)
              + f" | {r0[i]['peer'] or '—'} | "
              + " | ".join(star(r, "peer") + fmt(r["c_peer"], ".3g") for r in rs) + " |")
        a("")
    a("## Instructions per step at h = 1e-3 s (callgrind)")
    a("")
    a("| method | " + " | ".join(scenes) + " |")
    a("|---" * (1 + len(scenes)) + "|")
    for m in meths:
        cells = []
        for s in scenes:
            p = next((p for p in pts if p.method == m and p.scene == s and abs(p.h - 1e-3) < 1e-12), None)
            cells.append(f"{p.instr:,.0f}" if p and math.isfinite(p.instr) else "—")
        a(f"| {m.key} | " + " | ".join(cells) + " |")
    a("")
    a("## All measurements")
    a("")
    a(f"![work-precision]({png_name})")
    a("")
    a("| scene | method | h (s) | max error | us per step (min) | reps | instructions per step |")
    a("|---|---|---|---|---|---|---|")
    for p in pts:
        if not p.ok:
            a(f"| {p.scene} | {p.method.key} | {p.h:g} | FAILED: {p.status} | | | |")
            continue
        a(f"| {p.scene} | {p.method.key} | {p.h:g} | {p.err:.2e} | "
          f"{p.wall_min / p.n_steps * 1e6:.3f} | {p.reps} | "
          + (f"{p.instr:,.0f}" if math.isfinite(p.instr) else "—") + " |")
    a("")
    path.write_text("\n".join(L) + "\n")


# ---------------------------------------------------------------- command
def configure_parser(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.description = __doc__.split("\n\n")[0]
    p.add_argument("--quick", action="store_true",
                   help="3 step sizes, 2 repetitions, no reference cross-check; writes "
                   "workprecision_quick.*")
    results.add_output_options(p)
    p.add_argument("--step-sizes", type=float, nargs="+", default=None, metavar="H",
                   help=f"step sizes (s), each dividing {SAMPLE_DT} s (default 2e-2 ... 5e-6)")
    results.refuse_renamed(p, "--steps", "--step-sizes", "step sizes in s")
    p.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    p.add_argument("--no-peers", action="store_true", help="legsim only")
    p.add_argument("--no-callgrind", action="store_true", help="wall times only")
    p.add_argument("--count-steps", type=int, default=None,
                   help=f"steps counted by callgrind per point (default {COUNT_STEPS}, quick 200)")
    p.add_argument("--target-s", type=float, default=None,
                   help="wall-time budget per point (s of repeated runs; default 1.0, quick 0.1)")
    p.add_argument("--min-reps", type=int, default=None)
    p.add_argument("--max-reps", type=int, default=None)
    return p


def run(args) -> int:
    t_start = time.time()
    quick = bool(args.quick)
    steps = tuple(args.step_sizes) if args.step_sizes else (QUICK_STEPS if quick else STEPS)
    for h in steps:
        if abs(SAMPLE_DT / h - round(SAMPLE_DT / h)) > 1e-9:
            print(f"step {h} does not divide the sampling interval {SAMPLE_DT} s", file=sys.stderr)
            return 2
    if not legsim.library_available("double"):
        try:
            legsim.find_library("double")
        except legsim.LibraryNotFound as e:
            print(f"liblegsim not built: {e}", file=sys.stderr)
        return 2
    out = results.output_dir(args)
    out.mkdir(parents=True, exist_ok=True)
    stem = "workprecision_quick" if quick else "workprecision"
    scenes = list(args.scenes)

    def log(s):
        print(s, flush=True)

    info = results.snapshot()
    info.update(python=platform.python_version())
    build_dir = REPO_ROOT / "out" / "wpbench"
    try:
        engines = Engines(build_dir, with_peers=not args.no_peers)
    except compiled.DriverError as e:
        print(str(e), file=sys.stderr)
        return 2
    if engines.mujoco_why and not args.no_peers:
        log(f"# MuJoCo not run: {engines.mujoco_why}")
    meths = engines.methods()
    callgrind = not args.no_callgrind
    if callgrind and shutil.which("valgrind") is None:
        print("valgrind is not installed (tools/setup.sh installs it); or --no-callgrind",
              file=sys.stderr)
        return 2
    kinds = ("instr", "wall") if callgrind else ("wall",)
    count_steps = args.count_steps or (200 if quick else COUNT_STEPS)
    log(f"# drivers in {build_dir}; methods: {', '.join(m.key for m in meths)}")
    log(f"# reference (DOP853, rtol {REF_TOL:g})")
    refs = {s: reference(s) for s in scenes}
    ref_spread = {}
    if not quick:
        for s in scenes:
            ref_spread[s] = float(np.max(np.abs(reference(s, 1e-12) - refs[s])))
            log(f"  {s}: reference at 1e-12 vs 1e-13: {ref_spread[s]:.1e}")
    log("# runs")
    pts = measure(engines, meths, scenes, steps, refs, log,
                  reps_budget_s=args.target_s if args.target_s is not None else (0.1 if quick else 1.0),
                  min_reps=args.min_reps or (1 if quick else 2),
                  max_reps=args.max_reps or (2 if quick else 20),
                  callgrind=callgrind, count_steps=count_steps)
    conv = {(m.key, s): convergence_check(pts, m, s) for m in meths if m.engine != "legsim"
            for s in scenes}
    ratios = {(s, k): ratio_table(pts, meths, s, conv, k) for s in scenes for k in kinds}
    ratios_on = {s: ratio_table(pts, meths, s, conv, kinds[0], reactions=True) for s in scenes}
    info_end = results.snapshot()
    csv_path, md_path, png_path = out / f"{stem}.csv", out / f"{stem}.md", out / f"{stem}.png"
    write_csv(csv_path, pts)
    have_png = plot(png_path, pts, meths, scenes, kinds)
    write_md(md_path, pts=pts, meths=meths, scenes=scenes, steps=steps, conv=conv, ratios=ratios,
             ratios_on=ratios_on,
             info=info, info_end=info_end, engines=engines, ref_spread=ref_spread, quick=quick,
             elapsed=time.time() - t_start,
             png_name=png_path.name if have_png else "(matplotlib absent)", kinds=kinds,
             count_steps=count_steps)
    log(f"# wrote {csv_path}, {md_path}" + (f", {png_path}" if have_png else ""))
    for s in scenes:
        log(f"## {s}: ratio legsim / best peer at " + ", ".join(f"{E:.0e}" for E in ERROR_LEVELS))
        for k in kinds:
            log(f"  {k:5s} " + " ".join(fmt(r["ratio"], ".3g") for r in ratios[(s, k)]))
        log(f"  {kinds[0]:5s} " + " ".join(fmt(r["ratio"], ".3g") for r in ratios_on[s])
            + " (legsim reactions on)")
    return 0


def main(argv=None) -> int:
    p = configure_parser(argparse.ArgumentParser(prog="legsim-bench workprecision"))
    return run(p.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
