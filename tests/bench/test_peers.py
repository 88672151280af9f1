"""The peer engines (Exudyn, MuJoCo) model the same leg and converge to the
same reference before anyone times them.

Reference: the bench's reference model (legsim_bench.reference) when it is
importable, else the peers' own absolute-coordinate check (peers.selfref);
when both are there they are checked against each other too.

Each engine's tests are skipped, with the reason, only if the engine is not
importable. Runtime ~15 s on the 2-core machine.
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if importlib.util.find_spec("legsim_bench") is None:
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.benchmarks.peers import exudyn_leg, leg_model as lm, mujoco_leg, selfref  # noqa: E402
from legsim_bench.benchmarks.peers.convergence import energy_balance, errors  # noqa: E402
from legsim_bench.benchmarks.peers.reference import bench_reference_available, reference  # noqa: E402

T_END = 0.1
SCENES = tuple(lm.SCENES)
VARIANTS = lm.VARIANTS

needs_exudyn = pytest.mark.skipif(not exudyn_leg.available(),
                                  reason="exudyn is not importable (pip install exudyn)")
needs_mujoco = pytest.mark.skipif(not mujoco_leg.available(),
                                  reason="mujoco is not importable (pip install mujoco)")

_REF = {}


def ref_q(scene, variant):
    key = (scene, variant)
    if key not in _REF:
        _REF[key] = reference(scene, T_END, variant=variant)["q"][-1]
    return _REF[key]


# ---- the shared model -------------------------------------------------------

@pytest.mark.parametrize("variant", VARIANTS)
def test_stand_pose_satisfies_our_constraints(variant):
    m = lm.load(variant=variant)
    q0 = lm.stand_q0(m)
    assert len(lm.constraints(m, q0)) == (16 if variant == "revolute" else 15)
    assert np.max(np.abs(lm.constraints(m, q0))) < 1e-14
    # the facts of leg.toml's stand pose
    assert q0[8] == pytest.approx(np.pi / 3, abs=1e-15) and q0[17] == 0.0
    assert q0[2] == q0[5] == pytest.approx(0.7137244, abs=1e-7)
    assert q0[11] == q0[14] == pytest.approx(0.7661626, abs=1e-7)
    assert lm.actuator_lengths(m, q0) == pytest.approx([0.6614378, 0.6244998], abs=1e-7)
    assert lm.point(q0, 5, 0.3) == pytest.approx([0.4330127, -0.85], abs=1e-7)  # foot


def test_selfref_jacobian_and_gamma_match_finite_differences():
    rng = np.random.default_rng(1)
    for variant in VARIANTS:
        m = lm.load(variant=variant)
        q = lm.stand_q0(m) + 0.02 * rng.standard_normal(18)
        qd = rng.standard_normal(18)
        J, g = selfref.jacobian_gamma(m, q, qd)
        eps = 1e-6
        Jn = np.array([(lm.constraints(m, q + eps * e) - lm.constraints(m, q - eps * e)) / (2 * eps)
                       for e in np.eye(18)]).T
        assert np.max(np.abs(J - Jn)) < 1e-8
        Jp, _ = selfref.jacobian_gamma(m, q + eps * qd, qd)
        Jm, _ = selfref.jacobian_gamma(m, q - eps * qd, qd)
        assert np.max(np.abs(g + (Jp - Jm) / (2 * eps) @ qd)) < 1e-7


@pytest.mark.skipif(not bench_reference_available(),
                    reason="legsim_bench.reference not importable: the peers use selfref alone")
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("scene", SCENES)
def test_selfref_agrees_with_the_bench_reference(scene, variant):
    a = selfref.run(scene, T_END, variant=variant)["q"][-1]
    b = ref_q(scene, variant)
    assert np.max(np.abs(a - b)) < 1e-10


# ---- Exudyn -----------------------------------------------------------------

@needs_exudyn
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("scene", SCENES)
@pytest.mark.parametrize("method", exudyn_leg.METHODS)
def test_exudyn_converges_second_order(method, scene, variant):
    e = {h: errors(exudyn_leg.run(scene, T_END, h, method, variant=variant, every=0)["q_end"],
                   ref_q(scene, variant))[0] for h in (1e-3, 1e-4)}
    assert e[1e-4] < 1e-7
    assert 60.0 < e[1e-3] / e[1e-4] < 160.0  # order 2


@needs_exudyn
def test_exudyn_small_step_free_fall_below_1e_6():
    r = exudyn_leg.run("free_fall", T_END, 1e-5, "galpha")
    pos, ang = errors(r["q_end"], ref_q("free_fall", "revolute"))
    assert pos < 1e-6 and ang < 1e-6
    m = lm.load()
    assert np.max(np.abs(lm.constraints(m, r["q_end"]))) < 1e-12  # index 3: on the manifold
    assert abs(energy_balance(m, "free_fall", r["q"][0], r["q_end"], r["qd_end"])) < 1e-8


@needs_exudyn
def test_exudyn_refuses_explicit_solvers():
    with pytest.raises(NotImplementedError, match="do not support joints"):
        exudyn_leg.run("free_fall", T_END, 1e-3, "rk44")


# ---- MuJoCo -----------------------------------------------------------------

@needs_mujoco
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("scene", SCENES)
def test_mujoco_rk4_converges(scene, variant):
    e = {h: errors(mujoco_leg.run(scene, T_END, h, "rk4", variant=variant, every=0)["q_end"],
                   ref_q(scene, variant))[0] for h in (1e-3, 1e-4)}
    assert e[1e-4] < 1e-8
    # second order, not fourth: the loop closures are soft with time constant 2h
    assert 60.0 < e[1e-3] / e[1e-4] < 160.0


@needs_mujoco
def test_mujoco_small_step_free_fall_below_1e_6():
    r = mujoco_leg.run("free_fall", T_END, 1e-5, "rk4")
    pos, ang = errors(r["q_end"], ref_q("free_fall", "revolute"))
    assert pos < 1e-6 and ang < 1e-6
    m = lm.load()
    assert np.max(np.abs(lm.constraints(m, r["q_end"]))) < 1e-10
    assert abs(energy_balance(m, "free_fall", r["q"][0], r["q_end"], r["qd_end"])) < 1e-8


@needs_mujoco
def test_mujoco_euler_converges_first_order():
    e = {h: errors(mujoco_leg.run("free_fall", T_END, h, "euler", every=0)["q_end"],
                   ref_q("free_fall", "revolute"))[0] for h in (1e-4, 1e-5, 1e-6)}
    assert 7.0 < e[1e-4] / e[1e-5] < 13.0
    assert e[1e-6] < 1e-6


@needs_mujoco
def test_mujoco_unstable_closure_is_reported(tmp_path, monkeypatch):
    # stiffer than refsafe allows and explicit Euler: the closure blows up
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its warning to ./MUJOCO_LOG.TXT
    r = mujoco_leg.run("free_fall", T_END, 1e-3, "euler", every=0, solref=(0.5e-3, 1.0),
                       refsafe=False)
    assert not r["ok"]


# ---- the output contract, and the peers against each other --------------------

@pytest.mark.parametrize("peer,method", [
    pytest.param(exudyn_leg, "galpha", marks=needs_exudyn),
    pytest.param(mujoco_leg, "rk4", marks=needs_mujoco),
])
def test_run_returns_our_absolute_coordinates(peer, method):
    h = 1e-3
    r = peer.run("upper_step_50N", T_END, h, method)
    q0 = lm.stand_q0(lm.load())
    assert r["q"].shape == (101, 18) and r["t"].shape == (101,)
    assert r["t"][0] == 0.0 and r["t"][-1] == pytest.approx(T_END, abs=1e-12)
    assert np.allclose(np.diff(r["t"]), h, atol=1e-12)
    assert np.max(np.abs(r["q"][0] - q0)) < 1e-15
    assert np.max(np.abs(r["q"][-1] - r["q_end"])) < 1e-15
    assert r["wall_s"] > 0.0 and r["ok"]
    # the step extends the upper actuator
    lengths = lm.actuator_lengths(lm.load(), r["q_end"])
    assert lengths[0] > lm.actuator_lengths(lm.load(), q0)[0]
    sparse = peer.run("upper_step_50N", T_END, h, method, every=10)
    assert sparse["q"].shape == (11, 18)
    assert np.max(np.abs(sparse["q"] - r["q"][::10])) < 1e-14


@needs_exudyn
@needs_mujoco
@pytest.mark.parametrize("variant", VARIANTS)
def test_peers_agree_with_each_other(variant):
    a = exudyn_leg.run("upper_step_50N", T_END, 1e-4, "galpha", variant=variant)
    b = mujoco_leg.run("upper_step_50N", T_END, 1e-4, "rk4", variant=variant)
    assert np.max(np.abs(a["q"] - b["q"])) < 1e-7  # whole trajectories, every step
