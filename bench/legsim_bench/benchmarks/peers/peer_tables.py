"""What the MuJoCo peers and their result tables share: the MJCF ``<option>`` block (fixed step,
Newton at a tight tolerance, no auto-reset, no islands) and writing a table between two snapshots
of the machine's load."""
from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from .. import results


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def option_block(h: float, integrator: str, gravity, *, tolerance: float = 1e-12, iterations: int = 100,
                 flags: dict | None = None, **attrs) -> str:
    """MJCF ``<option>``: step h, the integrator (MuJoCo's name), gravity, the Newton solver at
    ``tolerance``, 50 line-search iterations; ``attrs`` further options (cone, impratio, ...; None
    left out); flags autoreset and island disabled (a blow-up shows as NaN, one problem for the
    whole robot) plus ``flags``."""
    extra = "".join(f' {k}="{v!r}"' if isinstance(v, float) else f' {k}="{v}"'
                    for k, v in attrs.items() if v is not None)
    fl = {"autoreset": "disable", "island": "disable", **(flags or {})}
    return (f'  <option timestep="{h!r}" integrator="{integrator}" gravity="{_f(gravity)}"{extra}\n'
            f'          solver="Newton" iterations="{iterations}" tolerance="{tolerance!r}" ls_iterations="50">\n'
            f'    <flag {" ".join(f"{k}={chr(34)}{v}{chr(34)}" for k, v in fl.items())}/>\n'
            f'  </option>')


def write(out, name: str, collect, markdown, **kw) -> Path:
    """``out/name`` (directories made): ``markdown(collect(**kw), before, after)``, the machine's
    snapshots (results.snapshot) taken around the collection."""
    before = results.snapshot()
    rows = collect(**kw)
    after = results.snapshot()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / name
    path.write_text(markdown(rows, before, after))
    return path


# legsim_hexapod_step is entered from libffi, which callgrind does not name: count inside the
# step it calls once a step (its events and contact problems inside; the pattern leaves out its
# [clone .part.0], whose nested toggle would stop the count)
TOGGLE = {"mujoco": "mj_step", "legsim": "legsim::spatial::robot_step(*Integrator)"}


def callgrind_total(engine: str, module: str, args: list[str]) -> int:
    """Instructions valgrind's callgrind counts inside the engine's step (TOGGLE) over one run of
    ``python -m module *args`` (set-up and Python outside the count)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "cg.out"
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", f"--toggle-collect={TOGGLE[engine]}",
               sys.executable, "-m", module, *args]
        for _ in range(2):  # one retry: valgrind's python now and then exits 1
            run = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ))
            if run.returncode == 0:
                break
        else:
            raise RuntimeError(f"callgrind of {module} {' '.join(args)}: {run.stderr[-2000:]}")
        text = out.read_text()
    m = re.search(r"^totals:\s*(\d+)", text, re.M) or re.search(r"^summary:\s*(\d+)", text, re.M)
    return int(m.group(1))
