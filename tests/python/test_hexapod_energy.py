"""No OK step of the hexapod creates energy (firmware_core/benchmarks/hexapod_energy.py, its short
form: 10 seeded drops of 0.3 s onto the ground under constant force commands; the long form is
the benchmark's own command, 200 runs): every step's gain of kinetic + gravity's potential less
the commands' work below its round-off (1e-10 of the energies moved) and every run OK, with
touchdowns, slips and lift-offs among them. And driven past the strokes (--past: 300 to 800 N
more on four actuators, 10 to 20 N m on two rowing motors; h = 0.5 ms, where RK4's own error
under those forces stays below the round-off tolerance: at 1 ms it reaches 7e-6 J a step, falling
30-fold a halving): every OK step leaves every length and rowing angle inside its stroke
(1e-12), with arrivals on the stops, and a stroke the state reports on a stop is at its end."""
from __future__ import annotations

import importlib.util

import numpy as np
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


def test_driven_past_the_strokes_stops_hold_and_create_no_energy():
    res = hexapod_energy.campaign(runs=6, steps=600, seed=2, dt=5e-4, past=True)
    print(f"gain at most {max(r['gain'] for r in res):.2e} J over {sum(r['steps'] for r in res)} steps, "
          f"{sum(r['stop_impacts'] for r in res)} arrivals on a stop, furthest past a stroke "
          f"{max(r['past'] for r in res):.1e}")
    assert all(r["status"] == "ok" for r in res)
    assert sum(r["steps"] for r in res) == 3600
    assert sum(r["stop_impacts"] for r in res) >= 30
    assert all(r["over"] == 0 for r in res)
    assert max(r["past"] for r in res) <= 1e-12
    # the state's report: strokes held on their stops at some steps' ends, each at its end
    assert sum(r["on_stop"] for r in res) >= 100
    assert max(r["off_stop"] for r in res) <= 1e-12


def test_a_stop_and_a_foot_at_one_instant_take_no_turns():
    """The campaign driven past the strokes at h = 1 ms (``hexapod_energy.py --past --runs 40 --seed 1
    --steps 1000``), its run 6: at 0.429 s leg 1's lower actuator reaches its stop while its foot
    slides, and the two took turns without end (the stop's impulse taken with the feet free threw the
    foot off, its touchdown pulled the stroke off its stop, ...: LEGSIM_ERR_CONTACT, "too many
    events", at step 430). One impact problem of the stop and the feet (spatial/contact's
    contact_impact) runs its 1,000 steps, every stroke inside its stroke and no step's energy gain
    above RK4's own error at this step (4.0e-6 J, as before it failed: below 1e-5 J)."""
    h = legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))
    mass = hexapod_energy.bodies_mass(h)
    rng = np.random.default_rng(1)
    for _ in range(6):  # the earlier runs' draws
        hexapod_energy.one_run(h, rng, 0, 1e-3, mass, past=True)
    r = hexapod_energy.one_run(h, rng, 1000, 1e-3, mass, past=True)
    print(f"run 6: {r['status']}, {r['steps']} steps, {r['events']} events, {r['impacts']} impacts, "
          f"{r['stop_impacts']} arrivals on a stop, largest gain {r['gain']:.2e} J")
    assert r["status"] == "ok" and r["steps"] == 1000
    assert r["stop_impacts"] >= 20 and r["impacts"] >= 20
    assert r["past"] <= 1e-12 and r["off_stop"] <= 1e-12
    assert r["gain"] < 1e-5
