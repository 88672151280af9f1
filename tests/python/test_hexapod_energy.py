"""No OK step of the hexapod creates energy (firmware_core/benchmarks/hexapod_energy.py, its short
form: 10 seeded drops of 0.3 s onto the ground under constant force commands; the long form is
the benchmark's own command, 200 runs): every step's gain of kinetic + gravity's potential less
the commands' work below its round-off (1e-10 of the energies moved) and every run OK, with
touchdowns, slips and lift-offs among them."""
from __future__ import annotations

import importlib.util

import pytest

legsim = pytest.importorskip("legsim")

from conftest import ROOT  # noqa: E402

_spec = importlib.util.spec_from_file_location("hexapod_energy",
                                               ROOT / "firmware_core" / "benchmarks" / "hexapod_energy.py")
hexapod_energy = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(hexapod_energy)


def test_drops_create_no_energy():
    res = hexapod_energy.campaign(runs=10, steps=300, seed=1, dt=1e-3)
    print(f"gain at most {max(r['gain'] for r in res):.2e} J over {sum(r['steps'] for r in res)} steps, "
          f"{sum(r['events'] for r in res)} events, {sum(r['impacts'] for r in res)} impacts")
    assert all(r["status"] == "ok" for r in res)
    assert sum(r["steps"] for r in res) == 3000
    assert sum(r["impacts"] for r in res) >= 30
    assert all(r["over"] == 0 for r in res)
