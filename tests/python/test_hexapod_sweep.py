"""The paper's Section V through the Python API (legsim.Hexapod.reaction_sweep:
legsim_hexapod_reaction_sweep) and one leg's inverse kinematics (Hexapod.leg_reach), against
closed forms and the statics they stand on:

- on a tripod on level ground every point's vertical foot forces are the barycentric closed form
  of the centre of mass in the support triangle (to 1e-9 of the weight), the horizontal ones
  zero, and the moving foot is where the sweep says (its distance and direction from the hip);
- moving the foot out along its heading shifts weight from it to the opposite foot (leg 5);
- parts of a grid, run separately, concatenate into the whole bit for bit;
- leg_reach puts a foot at its target (statics' foot positions at the pose it gives); a point out
  of reach or a sweep out of range is refused, a point the leg cannot stand at is its status.
"""
from __future__ import annotations

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

HEXAPOD = legsim.data_path("models/hexapod.toml")
TRIPOD = (0, 2, 4)


@pytest.fixture(scope="module")
def hexapod():
    return legsim.Hexapod.from_toml(HEXAPOD)


def barycentric(com, a, b, c):
    """The weights of a, b, c whose combination is com (x, y)."""
    T = np.array([[a[0] - c[0], b[0] - c[0]], [a[1] - c[1], b[1] - c[1]]])
    wa, wb = np.linalg.solve(T, [com[0] - c[0], com[1] - c[1]])
    return np.array([wa, wb, 1 - wa - wb])


def test_tripod_reactions_are_the_closed_form_over_a_grid(hexapod):
    r = hexapod.reaction_sweep(distance_m=(0.40, 0.62), n_distance=6, heading_rad=(-0.3, 0.3), n_heading=5)
    assert (r["status"] == 0).all()
    stand = hexapod.reaction_sweep(distance_m=(0.5, 0.5), n_distance=1)
    hip_distance = []
    for k in range(len(r["index"])):
        f = r["foot_force_n"][k]
        W = -hexapod.body_masses().sum() * hexapod.desc.gravity_mps2[2]
        w = barycentric(r["com_m"][k], *(r["foot_m"][k][j] for j in TRIPOD))
        assert np.abs(f[list(TRIPOD), 2] - w * W).max() < 1e-9 * W
        assert np.abs(f[list(TRIPOD), :2]).max() < 1e-9 * W
        assert np.abs(f[[1, 3, 5]]).max() == 0  # off the stance
        assert np.abs(r["foot_m"][k][list(TRIPOD), 2]).max() < 1e-9  # the feet on the plane
        hip_distance.append(r["foot_m"][k][0, :2])
    # the moving foot on its circles about one hip point: the same distance for every direction
    hip_distance = np.array(hip_distance).reshape(6, 5, 2)
    d = r["distance_m"].reshape(6, 5)
    # the hip: where the foot at distance rho and direction a from heading h is p - rho (cos, sin)(h + a);
    # solve for the hip and heading from two points of one circle and check the rest
    p0, p1 = hip_distance[0, 2], hip_distance[-1, 2]  # direction 0 at the nearest and farthest distances
    heading = np.arctan2(*(p1 - p0)[::-1])
    hip = p0 - d[0, 2] * np.array([np.cos(heading), np.sin(heading)])
    a = r["heading_rad"].reshape(6, 5)
    expect = hip + d[..., None] * np.stack([np.cos(heading + a), np.sin(heading + a)], axis=-1)
    assert np.abs(hip_distance - expect).max() < 1e-9
    # the robot's weight from its masses, at every point
    weight = -hexapod.body_masses().sum() * hexapod.desc.gravity_mps2[2]
    assert np.allclose(r["foot_force_n"][:, list(TRIPOD), 2].sum(axis=1), weight, rtol=1e-12, atol=0)
    assert np.isclose(stand["foot_force_n"][0][list(TRIPOD), 2].sum(), weight, rtol=1e-12, atol=0)


def test_foot_moving_out_shifts_weight_to_the_opposite_foot(hexapod):
    r = hexapod.reaction_sweep(distance_m=(0.40, 0.62), n_distance=12)
    fz = r["foot_force_n"][:, :, 2]
    assert (np.diff(fz[:, 0]) < 0).all() and (np.diff(fz[:, 4]) > 0).all()
    # Section V's actuators: the upper one pushes harder as the foot goes out, the lower one turns to a pull
    upper, lower = r["actuator_force_n"][:, 0, 0], r["actuator_force_n"][:, 0, 1]
    assert (np.diff(upper) > 0).all() and lower[0] > 0 > lower[-1]


def test_parts_concatenate_into_the_whole(hexapod):
    grid = dict(distance_m=(0.42, 0.6), n_distance=4, heading_rad=(-0.2, 0.25), n_heading=3)
    whole = hexapod.reaction_sweep(**grid)
    parts = [hexapod.reaction_sweep(**grid, first=a, count=b - a) for a, b in ((0, 5), (5, 6), (6, 12))]
    for key, value in whole.items():
        assert np.array_equal(np.concatenate([p[key] for p in parts]), value, equal_nan=True), key


def test_leg_reach_puts_the_foot_at_its_target(hexapod):
    pose = hexapod.stand_pose(1.0)
    stand = hexapod.statics(pose)
    for leg, shift in ((0, (0.03, 0.02, 0.01)), (3, (-0.04, 0.03, -0.02)), (5, (0.0, -0.05, 0.0))):
        target = stand["foot_m"][leg] - np.array(pose["box_m"]) + shift  # the box level at its place: box frame
        psi, lengths = hexapod.leg_reach(leg, target)
        moved = {**pose, "rowing_rad": list(pose["rowing_rad"]), "length_m": [list(x) for x in pose["length_m"]]}
        moved["rowing_rad"][leg] = psi
        moved["length_m"][leg] = list(lengths)
        got = hexapod.statics(moved)["foot_m"][leg] - np.array(pose["box_m"])
        assert np.abs(got - target).max() < 1e-9


def test_refusals_and_statuses(hexapod):
    with pytest.raises(legsim.LegsimError):
        hexapod.leg_reach(0, (5.0, 0.0, -1.0))  # beyond the leg's reach
    with pytest.raises(legsim.LegsimError):
        hexapod.leg_reach(6, (0.5, 0.0, -1.0))
    with pytest.raises(ValueError):
        hexapod.leg_reach(0, (0.5, 0.0))
    for bad in (dict(n_distance=0), dict(leg=1), dict(stance=(0, 2)), dict(box_height_m=0.0),
                dict(distance_m=(0.0, 0.5)), dict(heading_rad=(0.0, 4.0)), dict(first=23, count=1)):
        with pytest.raises(legsim.LegsimError):
            hexapod.reaction_sweep(**bad)
    # the foot far out: the leg cannot reach it, the point says so and has no numbers
    r = hexapod.reaction_sweep(distance_m=(0.5, 3.0), n_distance=2)
    assert r["status"][0] == 0 and r["status"][1] != 0
    assert np.isnan(r["foot_force_n"][1]).all() and np.isfinite(r["foot_force_n"][0]).all()
