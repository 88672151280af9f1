"""The block on an incline in legsim and MuJoCo against the closed forms of Coulomb friction
(bench/legsim_bench/benchmarks/peers/block_peers.py; its full table: bench/results/block_peers.md),
the short form at h = 5 ms: legsim's RK4 with its events located on the closed forms to 1e-8 m,
on the plane to 1e-15 m, stopping in the step that holds the closed form's stop and staying; MuJoCo's
soft elliptic cone within a factor of the table's errors (millimetres: while sliding its convex
contact lifts the block off the plane, about 0.5 mm here), stopping later and creeping after.
"""
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.benchmarks.peers import block_peers as bp  # noqa: E402

H = 5e-3
# bench/results/block_peers.md at h = 5 ms: MuJoCo's place and normal errors (m)
MUJOCO = {"block_incline_across": (6.14e-03, 5.28e-04), "block_incline_stop": (2.91e-03, 9.79e-04)}


@pytest.fixture(scope="module")
def legsim_lib():
    legsim = pytest.importorskip("legsim")
    if not legsim.library_available("double"):
        pytest.skip("liblegsim.so not built")
    return legsim


@pytest.mark.parametrize("name", bp.SCENES)
def test_legsim_is_on_the_closed_forms(legsim_lib, name):
    sc = bp.Scene(name, ROOT)
    e = bp.errors(sc, bp.legsim_run(sc, H, timed=False))
    assert e["place"] < 1e-8 and e["normal"] < 1e-15, e
    if sc.stop():
        T = sc.stop()[0]
        assert e["rest_s"] - H < T <= e["rest_s"] and e["drift"] == 0.0, e


@pytest.mark.skipif(not bp.available(), reason="mujoco is not installed (the bench's [peers] extra)")
@pytest.mark.parametrize("name", bp.SCENES)
def test_mujoco_soft_cone_as_the_table_says(name):
    sc = bp.Scene(name, ROOT)
    m = bp.mujoco_run(sc, H)
    assert m["ok"]
    e = bp.errors(sc, m)
    place, normal = MUJOCO[name]
    assert place / 2 < e["place"] < 2 * place and normal / 2 < e["normal"] < 2 * normal, e
    if sc.stop():
        assert e["rest_s"] > sc.stop()[0] + 0.05 and e["drift"] > 1e-9, e  # late, and it creeps
