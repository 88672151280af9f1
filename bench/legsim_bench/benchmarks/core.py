"""What the bench adds to the legsim Python API for its in-process campaigns.

The core itself is bound by the public package ``legsim`` (python/legsim:
``legsim.Sim``, ``legsim.Model``, statuses as exceptions, library discovery);
the bench uses it like any other user. This module keeps only what is the
bench's own: the repository root, the integrators' labels in result files,
the missing-library message of its subcommands, and two calls that must not
raise or must be timed alone (the stress campaign counts raw statuses; the
benchmarks time one ``legsim_step`` call).
"""
from __future__ import annotations

import os
import sys
import time

# Timings in this process must not compete with idle BLAS worker threads (2-core machines).
if "numpy" not in sys.modules:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pathlib import Path

import legsim


def _repo_root() -> Path:
    """$LEGSIM_ROOT, else the repository this package sits in (bench/legsim_bench/benchmarks/)."""
    env = os.environ.get("LEGSIM_ROOT")
    if env and (Path(env) / "models" / "leg.toml").is_file():
        return Path(env).resolve()
    here = Path(__file__).resolve()
    for d in [*here.parents, Path.cwd(), *Path.cwd().parents]:
        if (d / "models" / "leg.toml").is_file():
            return d
    return here.parents[3]


REPO_ROOT = _repo_root()
MODEL_TOML = REPO_ROOT / "models" / "leg.toml"

INTEGRATOR_LABEL = {"rk4": "RK4 + projection", "galpha": "generalized-alpha (index 3)"}


def library_missing(precision: str = "double") -> bool:
    """True, after saying where it was looked for, when the library is not built."""
    try:
        legsim.find_library(precision)
        return False
    except legsim.LibraryNotFound as e:
        print(e, file=sys.stderr)
        return True


def step_status(sim: legsim.Sim, n: int = 1) -> int:
    """One ``legsim_step(sim, n)`` returning its raw status instead of raising."""
    return int(sim.library.cdll.legsim_step(sim.handle, int(n)))


def timed_step(sim: legsim.Sim, n: int) -> int:
    """Wall time (ns, time.perf_counter_ns) of one ``legsim_step(sim, n)`` call; raises the
    status's exception if it fails."""
    f, h = sim.library.cdll.legsim_step, sim.handle
    t0 = time.perf_counter_ns()
    st = f(h, int(n))
    t1 = time.perf_counter_ns()
    if st != legsim.Status.OK:
        sim.library.check(st, "legsim_step")
    return t1 - t0
