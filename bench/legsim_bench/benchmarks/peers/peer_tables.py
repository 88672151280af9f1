"""What the MuJoCo peers and their result tables share: the MJCF ``<option>`` block (fixed step,
Newton at a tight tolerance, no auto-reset, no islands) and writing a table between two snapshots
of the machine's load."""
from __future__ import annotations

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
