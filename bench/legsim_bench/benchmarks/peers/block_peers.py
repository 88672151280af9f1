"""The block on an incline in legsim and MuJoCo, against the closed forms of Coulomb friction.

    legsim-bench block-peers --update-results
    python -m legsim_bench.benchmarks.peers.block_peers -o DIR        # from bench/

writes ``block_peers.md`` (default out/bench-results/): the machine section, then per scene
(scenes/block_incline_across.toml: mu_k = tan(alpha), it slides on for good; block_incline_stop.toml:
mu_k = 1.5 tan(alpha), it stops), engine and step h the errors against the closed forms
(reference/block_incline.py): the largest distance of the centre from the closed form's over
the run (m; beside it the largest part of that along the ground's normal: a penetration, or a lift), and for
the stop its time (the first step's end at which the block moves slower than 1e-6 m/s) and its
drift over the rest of the run (m); the cost per step (wall: the smallest over ``--repeats``
runs of one compiled loop, set-up outside the clock; instructions: valgrind callgrind inside
mj_step or legsim's robot_step, at 1 ms).

Both engines take the scene's numbers and the model's (models/block.toml) from their files. legsim:
legsim.Hexapod.from_toml(models/block.toml) on the scene's ground, its three points stuck at the
start, set_velocity, RK4 on the rotation group with its contact events located (the exact
Coulomb cone). MuJoCo: a free body of the file's mass and inertia, three spheres of radius 1e-4 m
whose lowest points are the file's contact points, on a plane geom of the scene's normal; condim
3, elliptic cones, one mu (the scene's mu_kinetic: MuJoCo has no separate static one; for the
stop it exceeds tan(alpha), so it holds), impratio 100, solref (2 h, 1) (the stiffest refsafe
admits), solimp (0.99, 0.99, 0.001): its contacts are soft. RK4, the Newton solver at
tolerance 1e-12.
"""
from __future__ import annotations

import argparse
import math
import shutil
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from .. import results
from . import peer_tables
from ...reference import block_incline
from ...scene import find_root

try:
    import mujoco
    from mujoco import rollout as _rollout
    VERSION = mujoco.__version__
except ImportError:  # the bench's [peers] extra
    mujoco = None
    VERSION = None

SCENES = ("block_incline_across", "block_incline_stop")
H = (1e-2, 5e-3, 2.5e-3, 1e-3, 5e-4)
CALLGRIND_H = 1e-3
SPHERE_M = 1e-4
REST_MPS = 1e-6
COMMAND = "legsim-bench block-peers --update-results"
MODULE_COMMAND = ("LEGSIM_ROOT=$PWD PYTHONPATH=$PWD/python:$PWD/bench "
                  "python -m legsim_bench.benchmarks.peers.block_peers --update-results")


def available() -> bool:
    return mujoco is not None


class Scene:
    """A block scene's numbers from its file and its model's: the plane (normal n, fall line down,
    across, alpha), mu's, the launch, the run's length, the block's mass, inertia and points, and
    its start (legsim_cli's placement: the least rotation from z to n, the points on the plane
    below the origin)."""

    def __init__(self, name: str, root: Path | None = None):
        root = Path(root or find_root())
        self.name = name
        spec = tomllib.loads((root / "scenes" / f"{name}.toml").read_text())
        self.model_path = (root / "scenes" / spec["model"]).resolve()
        model = tomllib.loads(self.model_path.read_text())
        g = spec["ground"]
        s, up = g["slope"], g["uphill"]
        self.n = np.array([-math.sin(s) * math.cos(up), -math.sin(s) * math.sin(up), math.cos(s)])
        _, down, across = block_incline.plane_axes(self.n)
        self.alpha, self.down, self.across = s, np.array(down), np.array(across)
        self.mu_static, self.mu_kinetic = g["mu_static"], g["mu_kinetic"]
        self.k = self.mu_kinetic / math.tan(s)  # k exactly 1 where mu_k = tan(slope)
        self.velocity = np.array(spec["velocity"], float)
        self.v0 = float(np.linalg.norm(self.velocity))
        self.duration = float(spec["duration"])
        self.mass = model["box"]["mass"]
        self.inertia = np.array(model["box"]["inertia"], float)
        self.points = np.array([c["point"] for c in model["box_contact"]], float)
        self.gravity = np.array(model["gravity"], float)
        q = np.array([1 + self.n[2], -self.n[1], self.n[0], 0.0])
        self.quat = q / np.linalg.norm(q)
        low = self.points[:, 2].min()
        self.centre = -low * self.n  # the ground's point is the origin in models/block.toml
        if any(model["ground"]["point"]):
            raise ValueError("block_peers places the block on a plane through the origin")

    def closed(self, t: float) -> np.ndarray:
        """The centre (world) at t by the closed form."""
        x, y, _ = block_incline.across(self.k, self.alpha, self.v0, t, -self.gravity[2])
        return self.centre + x * self.across + y * self.down

    def stop(self):
        return block_incline.stop(self.k, self.alpha, self.v0, -self.gravity[2]) if self.k > 1 else None


_f = peer_tables._f


def mjcf(sc: Scene, h: float) -> str:
    """The block in MJCF (the module's docstring)."""
    spheres = "\n".join(
        f'      <geom type="sphere" size="{SPHERE_M!r}" pos="{_f(p + [0, 0, SPHERE_M])}" friction="{sc.mu_kinetic!r} 0 0"'
        f' condim="3" solref="{2 * h!r} 1" solimp="0.99 0.99 0.001 0.5 2"/>' for p in sc.points)
    return f"""<mujoco model="{sc.name}">
{peer_tables.option_block(h, "RK4", sc.gravity, cone="elliptic", impratio=100.0)}
  <worldbody>
    <geom type="plane" size="0 0 1" quat="{_f(sc.quat)}" friction="{sc.mu_kinetic!r} 0 0" condim="3"
          solref="{2 * h!r} 1" solimp="0.99 0.99 0.001 0.5 2"/>
    <body name="block" pos="{_f(sc.centre)}" quat="{_f(sc.quat)}">
      <freejoint/>
      <inertial pos="0 0 0" mass="{sc.mass!r}" diaginertia="{_f(sc.inertia)}"/>
{spheres}
    </body>
  </worldbody>
</mujoco>"""


def mujoco_run(sc: Scene, h: float) -> dict:
    """The centre and velocity at every step (mujoco.rollout, one thread) and the wall time per step
    of the rollout alone."""
    m = mujoco.MjModel.from_xml_string(mjcf(sc, h))
    d = mujoco.MjData(m)
    n = int(round(sc.duration / h))
    d.qvel[0:3] = sc.velocity
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    x0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, x0, spec)
    state = np.empty((1, n, x0.size))
    t0 = time.perf_counter()
    _rollout.rollout(m, d, x0[None, :], np.zeros((1, n, 0)), nstep=n, state=state)
    wall = time.perf_counter() - t0
    s = state[0]
    return {"t": s[:, 0], "x": s[:, 1:4], "v": s[:, 1 + m.nq:4 + m.nq], "per_step_s": wall / n,
            "ok": bool(np.all(np.isfinite(s))) and d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number == 0}


def legsim_run(sc: Scene, h: float, timed: bool = True) -> dict:
    """legsim's block (legsim.Hexapod of models/block.toml on the scene's ground): the centre and
    velocity at every step (step(1) calls), then the wall time per step of one step(n) call."""
    import legsim

    block = legsim.Hexapod.from_toml(sc.model_path).on_ground(normal=sc.n, mu_static=sc.mu_static,
                                                             mu_kinetic=sc.mu_kinetic)
    pose = {"box_m": sc.centre, "box_quat": sc.quat, "rowing_rad": [0.0] * 6, "length_m": [[0.0, 0.0]] * 6}
    n = int(round(sc.duration / h))

    def start():
        sim = block.sim(pose, box_stuck=range(len(sc.points)))
        sim.set_velocity(sc.velocity)
        return sim

    sim = start()
    t, x, v = [], [], []
    for _ in range(n):
        sim.step(1, h_s=h)
        st = sim.state()
        t.append(st["t_s"])
        x.append(st["box_m"])
        v.append(st["box_velocity_mps"])
    per = float("nan")
    if timed:
        sim = start()
        t0 = time.perf_counter()
        sim.step(n, h_s=h)
        per = (time.perf_counter() - t0) / n
    return {"t": np.array(t), "x": np.array(x), "v": np.array(v), "per_step_s": per, "ok": True}


def errors(sc: Scene, run: dict) -> dict:
    """Against the closed forms: place (the largest distance of the centre, m), normal (its part
    along the ground's normal, m), and for a stop its time (s) and the drift after it (m)."""
    if not run["ok"]:
        return {"place": float("nan"), "normal": float("nan"), "rest_s": float("nan"), "drift": float("nan")}
    ref = np.array([sc.closed(t) for t in run["t"]])
    dx = run["x"] - ref
    out = {"place": float(np.linalg.norm(dx, axis=1).max()), "normal": float(np.abs(dx @ sc.n).max()),
           "rest_s": float("nan"), "drift": float("nan")}
    if sc.stop() is not None:
        slow = np.linalg.norm(run["v"], axis=1) < REST_MPS
        if slow.any():
            i = int(np.argmax(slow))
            out["rest_s"] = float(run["t"][i])
            out["drift"] = float(np.linalg.norm(run["x"][-1] - run["x"][i]))
    return out


def compare(name: str, h: float, engine: str, repeats: int = 1, root=None) -> dict:
    sc = Scene(name, root)
    best = None
    for _ in range(max(1, repeats)):
        r = mujoco_run(sc, h) if engine == "mujoco" else legsim_run(sc, h)
        if best is None or r["per_step_s"] < best["per_step_s"]:
            best = r
    return {"scene": name, "engine": engine, "h": h, "per_step_s": best["per_step_s"], **errors(sc, best)}


def instructions_per_step(engine: str, name: str, h: float) -> float:
    """Instructions per step (valgrind callgrind inside mj_step or legsim's robot_step) of one run."""
    total = peer_tables.callgrind_total(engine, "legsim_bench.benchmarks.peers.block_peers",
                                        ["--once", engine, name, repr(h)])
    # legsim's run steps twice (sampled, then timed): count one
    return total / int(round(Scene(name).duration / h)) / (2 if engine == "legsim" else 1)


def collect(scenes=SCENES, hs=H, repeats: int = 3, callgrind: bool = True) -> list[dict]:
    rows = []
    for name in scenes:
        for engine in ("legsim", "mujoco"):
            for h in hs:
                r = compare(name, h, engine, repeats)
                r["instructions"] = instructions_per_step(engine, name, h) if callgrind and h == CALLGRIND_H else None
                rows.append(r)
    return rows


def _e(x) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.2e}"


def markdown(rows: list[dict], before: dict, after: dict | None = None) -> str:
    lines = [f"Regenerate: `{COMMAND}` (liblegsim built; or, from the repository, `{MODULE_COMMAND}`)", "",
             "# The block on an incline in legsim and MuJoCo, against the closed forms of Coulomb friction", ""]
    lines += results.machine_section(before, after)
    about = " ".join(" ".join(__doc__.split("\n\n")[2:4]).split())
    lines += ["P" + about[about.index("per scene") + 1:], "",
              "Model: bench/legsim_bench/benchmarks/peers/block_peers.py; closed forms: "
              "bench/legsim_bench/reference/block_incline.py.", ""]
    for name in dict.fromkeys(r["scene"] for r in rows):
        s = Scene(name)
        stop = s.stop()
        head = (f"## {name}: alpha {math.degrees(s.alpha):.0f} deg, k = mu_k / tan(alpha) = {s.k:g}, "
                f"v0 {s.v0:g} m/s, {s.duration:g} s")
        if stop:
            head += f"; the closed form stops at T = {stop[0]:.6f} s"
        lines += [head, "", "| engine | h (s) | place (m) | normal (m) | rest (s) | drift after rest (m) | "
                  "cost per step (us) | instructions per step |", "|---|---|---|---|---|---|---|---|"]
        for r in rows:
            if r["scene"] != name:
                continue
            eng = "legsim double, RK4, events located" if r["engine"] == "legsim" else f"mujoco {VERSION}, rk4"
            ins = f"{r['instructions']:,.0f}" if r.get("instructions") else "-"
            rest = "-" if math.isnan(r["rest_s"]) else f"{r['rest_s']:.4f}"
            lines.append(f"| {eng} | {r['h']:g} | {_e(r['place'])} | {_e(r['normal'])} | {rest} | {_e(r['drift'])} | "
                         f"{r['per_step_s'] * 1e6:.1f} | {ins} |")
        lines.append("")
    return "\n".join(lines)


def write(out: Path, **kw) -> Path:
    return peer_tables.write(out, "block_peers.md", collect, markdown, **kw)


def configure_parser(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of `legsim-bench block-peers`."""
    results.add_output_options(p)
    p.add_argument("--repeats", type=int, default=3, help="timing repeats of every engine (the smallest cost is kept)")
    p.add_argument("--scenes", nargs="+", choices=SCENES, default=list(SCENES))
    p.add_argument("--no-callgrind", action="store_true", help="no instruction counts (valgrind)")
    return p


def run(a) -> int:
    if a.repeats < 1:
        raise SystemExit("block-peers: --repeats must be at least 1")
    if not available():
        raise SystemExit("block-peers: mujoco is not installed (the bench's [peers] extra)")
    print(write(results.output_dir(a), scenes=tuple(a.scenes), repeats=a.repeats,
                callgrind=not a.no_callgrind and shutil.which("valgrind") is not None))
    return 0


def main(argv=None) -> int:
    if argv is None:
        argv = sys.argv[1:]
    if argv[:1] == ["--once"]:  # one run, the process instructions_per_step counts
        engine, name, h = argv[1:4]
        (mujoco_run if engine == "mujoco" else legsim_run)(Scene(name), float(h))
        return 0
    p = argparse.ArgumentParser(description="The block on an incline in legsim and MuJoCo against the closed forms")
    return run(configure_parser(p).parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
