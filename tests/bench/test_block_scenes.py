"""The block's scenes (scenes/block_*.toml, scenes/README.md "A block"): legsim_cli runs a hexapod
file of no legs (models/block.toml) through the hexapod's C API; here its JSON against the closed
forms of a body sliding on an inclined plane with Coulomb friction (the bench's
reference/block_incline.py: launched across the fall line, mu_k = k tan(alpha)), and against the
Python API's run of the same block (legsim.Hexapod.sim with its points stuck, set_velocity, step).
The block's centre of mass is over its points' centroid: it translates."""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from built import legsim_cli

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.reference import block_incline  # noqa: E402

SCENES = ROOT / "scenes"
G = block_incline.G0


def _run(name):
    r = subprocess.run([str(legsim_cli()), str(SCENES / f"{name}.toml")], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def _plane(d):
    """The incline's angle, its fall line (down) and the horizontal across it, from the JSON's ground."""
    alpha, down, across = block_incline.plane_axes(d["ground"]["normal"])
    return alpha, np.array(down), np.array(across)


def test_across_the_fall_line_at_mu_tan_alpha_follows_the_closed_form():
    """block_incline_across: every sample's place (1e-8 m) and speed (1e-8 m/s) on the closed form
    (RK4 at 5 ms: tests/model/test_spatial_block.cpp measures 1.6e-9 m), the three points sliding
    throughout, the normal forces summing to m g cos(alpha), no spin."""
    d = _run("block_incline_across")
    alpha, down, across = _plane(d)
    k = d["ground"]["mu_kinetic"] / math.tan(alpha)
    assert abs(k - 1) < 1e-15
    v0 = np.array(d["velocity"])
    assert abs(v0 @ down) < 1e-15  # launched across
    r0 = np.array(d["samples"][0]["box"])
    n = np.array(d["ground"]["normal"])
    worst_x = worst_v = worst_n = 0.0
    for s in d["samples"][1:]:
        x, y, v = block_incline.across(1, alpha, float(np.linalg.norm(v0)), s["t"])
        dr = np.array(s["box"]) - r0
        worst_x = max(worst_x, math.hypot(dr @ across - x, dr @ down - y))
        worst_v = max(worst_v, abs(np.linalg.norm(s["box_velocity"]) - v))
        assert [c["state"] for c in s["contacts"]] == ["sliding"] * 3
        worst_n = max(worst_n, abs(sum(np.array(c["force"]) @ n for c in s["contacts"]) - d["mass"] * G * math.cos(alpha)))
        assert np.abs(s["box_omega"]).max() < 1e-12
    assert worst_x < 1e-8 and worst_v < 1e-8, (worst_x, worst_v)
    assert worst_n < 1e-10
    assert abs(d["samples"][-1]["t"] - 1.0) < 1e-12 and worst_x > 0  # a real comparison, over the whole second


def test_with_more_friction_it_stops_where_and_when_the_closed_form_does():
    """block_incline_stop (k = 1.5): the three points stuck at once at the end of the step holding
    the closed form's stop T, the block there (5e-8 m) and at rest for the rest of the run."""
    d = _run("block_incline_stop")
    alpha, down, across = _plane(d)
    k = d["ground"]["mu_kinetic"] / math.tan(alpha)
    assert abs(k - 1.5) < 1e-14
    v0 = float(np.linalg.norm(d["velocity"]))
    T, xs, ys = block_incline.stop(k, alpha, v0)
    h = d["step_s"]
    r0 = np.array(d["samples"][0]["box"])
    rest = next(s for s in d["samples"] if all(c["state"] == "stuck" for c in s["contacts"]) and s["t"] > 0)
    assert rest["t"] - h < T <= rest["t"], (rest["t"], T)
    for s in d["samples"]:
        states = {c["state"] for c in s["contacts"]}
        dr = np.array(s["box"]) - r0
        if s["t"] < rest["t"] - 1e-12:
            assert states == {"sliding"}
            x, y, _ = block_incline.across(k, alpha, v0, s["t"])
            assert math.hypot(dr @ across - x, dr @ down - y) < 5e-8
        else:
            assert states == {"stuck"}
            assert math.hypot(dr @ across - xs, dr @ down - ys) < 5e-8
            assert np.abs(s["box_velocity"]).max() < 1e-15


@pytest.mark.parametrize("name", ["block_incline_across", "block_incline_stop"])
def test_the_python_api_runs_the_same_block_bit_for_bit(name):
    """The scene through legsim.Hexapod (from_toml, on_ground, sim with its points stuck,
    set_velocity, step), from the pose the JSON says it took: every sample equal."""
    legsim = pytest.importorskip("legsim")
    d = _run(name)
    try:
        block = legsim.Hexapod.from_toml(ROOT / "models" / "block.toml")
    except (OSError, RuntimeError) as e:  # no liblegsim built
        pytest.skip(str(e))
    g = d["ground"]
    block = block.on_ground(normal=g["normal"], mu_static=g["mu_static"], mu_kinetic=g["mu_kinetic"])
    pose = {"box_m": d["pose"]["box"], "box_quat": d["pose"]["box_quat"], "rowing_rad": [0.0] * 6,
            "length_m": [[0.0, 0.0]] * 6}
    sim = block.sim(pose, box_stuck=range(3))
    sim.set_velocity(d["velocity"], d["omega"])
    for i, s in enumerate(d["samples"]):
        if i:
            sim.step(1, h_s=d["step_s"])
        x = sim.state()
        assert x["t_s"] == s["t"]
        assert list(x["box_m"]) == s["box"] and list(x["box_velocity_mps"]) == s["box_velocity"]
        assert x["box_contact_force_n"].tolist() == [c["force"] for c in s["contacts"]]
        assert x["box_contact_state"] == [c["state"] for c in s["contacts"]]
