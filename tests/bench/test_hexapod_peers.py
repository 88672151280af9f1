"""The hexapod in MuJoCo and legsim against the bench's reference (HexapodModel, minimal
coordinates, DOP853 at rtol 1e-12) on scene b (a tripod held, three legs free), at t = 0.2 s:
the errors bench/results/hexapod_peers.md gives, within a factor; MuJoCo's positional errors
falling at order 2 (its soft equalities, solref (2h, 1)) and its ground forces on their
h-independent floor (about 4e-3 N: the equalities' stabilisation b v + k r times the feet's
effective mass); legsim's RK4 at h = 1 ms three to six orders of magnitude closer.
"""
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.benchmarks.peers import mujoco_hexapod as mh  # noqa: E402
from legsim_bench.reference.hexapod import HexapodModel  # noqa: E402

pytestmark = pytest.mark.skipif(not mh.available(), reason="mujoco is not installed (the bench's [peers] extra)")

KEYS = ("box", "rot", "rowing", "lengths", "force")
# bench/results/hexapod_peers.md, b_tripod: box (m), rotation (rad), rowing (rad), lengths (m), forces (N)
MUJOCO = {1e-3: (7.95e-08, 3.97e-08, 1.09e-07, 1.15e-07, 4.30e-03),
          5e-4: (2.03e-08, 1.01e-08, 2.77e-08, 2.85e-08, 4.36e-03)}
LEGSIM_1MS = (3.02e-13, 1.61e-11, 1.59e-11, 5.95e-12, 5.35e-09)


@pytest.fixture(scope="module")
def scene():
    ref = HexapodModel.from_toml(ROOT / "models" / "hexapod.toml")
    sc = mh.setup("b_tripod", ref)
    return sc, ref, mh.reference(sc, ref)


def test_mujoco_model(scene):
    """6 box dofs, per leg a yoke hinge and 6 bar joints; per leg two loop connects, per held
    foot one; the masses the file's."""
    sc, ref, _ = scene
    p = mh.MujocoHexapod(sc, ref, 1e-3)
    assert p.m.nv == 6 + 6 * 7
    assert p.m.neq == 2 * 6 + len(sc.stance)
    assert abs(p.m.body_mass.sum() - ref.mass) < 1e-12


def test_mujoco_converges(scene):
    sc, ref, res = scene
    err = {h: mh.compare(sc, ref, h, res)["err"] for h in MUJOCO}
    for h, e in err.items():
        print(f"mujoco h = {h:g}: " + ", ".join(f"{k} {e[k]:.2e}" for k in KEYS))
        for k, table in zip(KEYS, MUJOCO[h]):
            assert table / 2 < e[k] < 2 * table, (h, k)
    for k in KEYS[:4]:
        ratio = err[1e-3][k] / err[5e-4][k]
        assert ratio > 3.0, (k, ratio)          # order 2 (ratio 4)
    # the forces on their floor: not better at h / 2
    assert 2e-3 < err[5e-4]["force"] < 8e-3


def test_legsim_beside(scene):
    legsim = pytest.importorskip("legsim")
    if not legsim.library_available("double"):
        pytest.skip("liblegsim.so is not built (cmake --build build/host --target legsim)")
    sc, ref, res = scene
    c = mh.compare(sc, ref, 1e-3, res, engine="legsim")
    e = c["err"]
    print("legsim h = 1 ms: " + ", ".join(f"{k} {e[k]:.2e}" for k in KEYS))
    assert c["ok"]
    assert e["box"] < 1e-11                      # near round-off
    for k, table in zip(KEYS[1:], LEGSIM_1MS[1:]):
        assert table / 3 < e[k] < 3 * table, k
    for k, table in zip(KEYS, MUJOCO[1e-3]):
        assert e[k] < 1e-3 * table, k
