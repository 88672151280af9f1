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
    r = _campaign_run(h, 6)
    print(f"run 6: {r['status']}, {r['steps']} steps, {r['events']} events, {r['impacts']} impacts, "
          f"{r['stop_impacts']} arrivals on a stop, largest gain {r['gain']:.2e} J")
    assert r["status"] == "ok" and r["steps"] == 1000
    assert r["stop_impacts"] >= 20 and r["impacts"] >= 20
    assert r["past"] <= 1e-12 and r["off_stop"] <= 1e-12
    assert r["gain"] < 1e-5


def _campaign_run(h, run, check=None):
    """Run `run` of the campaign (seed 1, h = 1 ms, past the strokes): its 1,000 steps after the
    earlier runs' draws."""
    mass = hexapod_energy.bodies_mass(h)
    rng = np.random.default_rng(1)
    for _ in range(run):  # the earlier runs' draws
        hexapod_energy.one_run(h, rng, 0, 1e-3, mass, past=True)
    return hexapod_energy.one_run(h, rng, 1000, 1e-3, mass, past=True, check=check)


def _contact_invariants(h):
    """A check for one_run: after every OK step each foot on its contact law (the ground's force on a
    stuck foot in its mu_s cone, on a sliding foot on its mu_k cone's surface, none on a free foot; no
    foot below the ground), and the largest violations kept."""
    g = h.ground
    n = np.array(g["normal"])
    p0 = np.array(g["point"])
    worst = {"pull": 0.0, "cone": 0.0, "slide": 0.0, "free": 0.0, "under": 0.0, "steps": 0, "sliding": 0}

    def check(sim, st, gain):
        worst["steps"] += 1
        f, x = st["foot_force_n"], st["foot_m"]
        for k, mode in enumerate(st["foot_state"]):
            N = float(f[k] @ n)
            ft = float(np.linalg.norm(f[k] - N * n))
            worst["under"] = max(worst["under"], -float((x[k] - p0) @ n))
            if mode == "free":
                worst["free"] = max(worst["free"], float(np.linalg.norm(f[k])))
                continue
            worst["pull"] = max(worst["pull"], -N)
            if mode == "stuck":
                worst["cone"] = max(worst["cone"], ft - g["mu_static"] * N)
            else:
                worst["sliding"] += 1
                worst["slide"] = max(worst["slide"], abs(ft - g["mu_kinetic"] * N) / max(N, 1.0))

    return worst, check


@pytest.mark.parametrize("run, what", [(17, "a sliding foot and a stop no mode keeps"),
                                       (37, "the feet and the stops decided in one problem")])
def test_campaign_runs_that_failed_now_run(run, what):
    """The campaign driven past the strokes at h = 1 ms (``hexapod_energy.py --past --runs 40 --seed 1
    --steps 1000``). Run 37 ended at 0.660 s (LEGSIM_ERR_CONTACT): the modes' check decided the stuck
    feet on their cones and let the held stops go one at a time after them, and a foot and a stroke
    at one instant found no order that settled; now the stuck feet and the held stops are one
    acceleration-level contact problem (spatial/contact's contact_modes: a stop a cone of mu = 0,
    its push >= 0). Run 17 ended at 0.452 s: leg 0's sliding foot pulls with its actuator's stop
    held, the stop pulls with the foot on the ground, the foot let go accelerates into the ground
    (Painleve's inconsistent case: the stop's push moves it into its stop through the foot's
    friction); now an impact without collision of the foot and the strokes at their ends stops the
    slip (contact_impact's jammed). Both run their 1,000 steps: every stroke inside its stroke,
    a held one at its end, every foot on its contact law after every step, and no step's energy
    gain above RK4's own error at this step (at most 3.9e-5 J over the campaign's OK steps before
    the change)."""
    h = legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))
    worst, check = _contact_invariants(h)
    r = _campaign_run(h, run, check)
    print(f"run {run} ({what}): {r['status']}, {r['steps']} steps, {r['events']} events, {r['impacts']} impacts, "
          f"{r['stop_impacts']} arrivals on a stop, largest gain {r['gain']:.2e} J; {worst}")
    assert r["status"] == "ok" and r["steps"] == 1000
    assert r["stop_impacts"] >= 20 and r["on_stop"] >= 500
    assert r["past"] <= 1e-12 and r["off_stop"] <= 1e-12
    assert r["gain"] < 1e-4
    assert worst["steps"] == 1000 and worst["sliding"] > 0
    assert worst["pull"] <= 1e-7 and worst["cone"] <= 1e-7 and worst["free"] == 0.0
    assert worst["slide"] <= 1e-12 and worst["under"] <= 1e-9
