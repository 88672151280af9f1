"""The spatial leg prototype (firmware_core/tools/prototypes/spatial_leg.py): one leg on a rowing
hip yoke on a fixed box, absolute (quaternion) and relative formulations, against the minimal-
coordinate reference (DOP853, 1e-12) and the energy balance. docs/design/spatial.md."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "firmware_core" / "tools" / "prototypes"))
import spatial_leg as sl  # noqa: E402

T = 0.2
SAMPLE = 0.01
STEPS = (2e-3, 1e-3)


@pytest.fixture(autouse=True)
def _double_library():
    """conftest's fixture of the same name skips without liblegsim.so; this module is pure Python"""


@pytest.fixture(scope="module")
def leg():
    return sl.Leg()


@pytest.fixture(scope="module")
def reference(leg):
    return sl.run_reference(leg, T, SAMPLE)[0]


@pytest.fixture(scope="module")
def runs(leg):
    out = {}
    for h in STEPS:
        out["a", h] = sl.run_fixed(sl.Absolute(leg, rows="tree"), h, T, SAMPLE)
        out["b", h] = sl.run_fixed(sl.Relative(leg), h, T, SAMPLE)
    out["a-plane", STEPS[0]] = sl.run_fixed(sl.Absolute(leg, rows="plane"), STEPS[0], T, SAMPLE)
    return out


def test_rows_count_and_rank(leg):
    pose = sl.stand_pose(leg)
    for rows in ("tree", "plane"):
        a = sl.Absolute(leg, rows=rows)
        phi, J, _ = a.rows_eval(a.state(*a.initial(pose)))
        # 7 bodies x 6 - 39 rows = 3 degrees of freedom: the rowing angle and the leg's two
        assert J.shape == (39, 42)
        assert np.max(np.abs(phi)) < 1e-15
        assert np.linalg.svd(J, compute_uv=False)[-1] > 0.2
    # every joint a 3D joint: 45 rows of rank 39, 3 redundant per closed loop
    a = sl.Absolute(leg, rows="full3d")
    _, J, _ = a.rows_eval(a.state(*a.initial(pose)))
    assert J.shape == (45, 42) and np.linalg.matrix_rank(J) == 39


def test_reference_keeps_energy(reference):
    # work of the actuator and the rowing torque = change of kinetic + potential energy
    assert np.ptp(reference[:, 5]) < 1e-9
    assert reference[-1, 1] > 0.02          # the yoke has turned


def test_rank_full_along_the_motion(runs):
    for (name, h), (out, _) in runs.items():
        # smallest singular value of the rows' Jacobian at every sample, far from zero
        assert np.min(out[:, 6]) > (0.2 if name != "b" else 0.05), (name, h)
        assert np.max(out[:, 8]) < 1e-12, (name, h)        # projected onto Phi = 0


def test_agree_with_reference_fourth_order(runs, reference):
    for name in ("a", "b"):
        e = [sl.traj_error(runs[name, h][0], reference)[0] for h in STEPS]
        assert e[0] < 2e-8 and e[1] < 2e-9, (name, e)
        assert e[0] / e[1] > 10, (name, e)                  # RK4: 16 asymptotically
        psi = [sl.traj_error(runs[name, h][0], reference)[1] for h in STEPS]
        assert psi[1] < 1e-10, (name, psi)
    # the two formulations agree with each other, and the plane row set with the tree's
    ea = sl.traj_error(runs["a", STEPS[1]][0], runs["b", STEPS[1]][0])[0]
    assert ea < 2e-9
    # (the same manifold; their Newton projections differ by O(Phi^2) a step)
    ep = sl.traj_error(runs["a-plane", STEPS[0]][0], runs["a", STEPS[0]][0])[0]
    assert ep < 1e-9


def test_quaternions_unit_to_roundoff(runs):
    # the exp-map update keeps |q| = 1 without normalization, to round-off
    for h in STEPS:
        assert np.max(runs["a", h][0][:, 7]) < 1e-14


def test_energy_balance(runs):
    for name in ("a", "b"):
        d = [np.max(np.abs(runs[name, h][0][:, 5] - runs[name, h][0][0, 5])) for h in STEPS]
        assert d[0] < 1e-6 and d[1] < d[0] / 8, (name, d)


def test_planar_when_not_rowing(leg):
    # no rowing torque: the yoke stays put and the leg moves as the planar model in its plane
    ref = sl.run_reference(leg, 0.1, SAMPLE, tau=0.0)[0]
    for form in (sl.Absolute(leg, tau=0.0), sl.Relative(leg, tau=0.0)):
        out, _ = sl.run_fixed(form, 2e-3, 0.1, SAMPLE)
        assert np.max(np.abs(out[:, 1])) < 1e-13
        assert np.max(np.abs(out[:, 3])) < 1e-13          # the foot stays in the plane y = 0
        assert sl.traj_error(out, ref)[0] < 1e-8


def test_counted_fill_is_the_factor_s(leg):
    # the symbolic count of nnz(L) equals a numerical L D L^T's non-zeros at a generic configuration
    a = sl.Absolute(leg, rows="tree")
    nzr, J = sl.absolute_structure(a)
    adj, _ = sl.gram_pattern(nzr)
    order = sl.min_degree(adj)
    A = (J * a.Minv) @ J.T
    A = A[np.ix_(order, order)]
    n = len(order)
    L = np.eye(n)
    for k in range(n):
        L[k + 1:, k] = A[k + 1:, k] / A[k, k]
        A[k + 1:, k + 1:] -= np.outer(L[k + 1:, k], A[k, k + 1:])
    nnz_numeric = int(np.sum(np.abs(np.tril(L, -1)) > 1e-12))
    assert sl.symbolic_ldl(adj, order)[0] == nnz_numeric == 397
