"""The hexapod walking (legsim.Hexapod.walk: the tripod gait's set-points through the servos, the
statics of the planned pose as feed-forward; the feet on the ground's cones, events located),
against the gait's own plan and the invariants of contact:

- straight, two periods (RK4 and generalized-alpha): the box advances the gait's distance
  (step_length / duty a period) to 10 %, keeps its height to 2 cm, its heading to 1 degree and
  its tilt under 3 degrees;
- turning on the spot: the box turns by the gait's angle to 10 % and stays within 3 cm of its
  place;
- throughout: no foot below the ground (1e-9 m), every foot on the ground pushes and a stuck one
  stays inside its cone, the two tripods alternate (each foot free in each period, the tripods'
  feet never free together), every touchdown an impact, every contact problem on the cones
  solved to the solver's tolerance (1e-10).
"""
from __future__ import annotations

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

GAIT = dict(period_s=1.2, duty=0.6, step_height_m=0.05, box_height_m=1.0)


@pytest.fixture(scope="module")
def hexapod():
    return legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))


def yaw_tilt(q):
    w, x, y, z = q.T
    return 2 * np.arctan2(z, w), 2 * np.arcsin(np.clip(np.hypot(x, y), 0, 1))


def contact_invariants(h, w):
    mu_s = h.desc.mu_static
    assert w["foot_m"][:, :, 2].min() > -1e-9
    on = w["foot_state"] > 0
    N = w["foot_force_n"][:, :, 2]
    assert np.all(N[on] > -1e-6)
    stuck = w["foot_state"] == 1
    Ft = np.hypot(w["foot_force_n"][:, :, 0], w["foot_force_n"][:, :, 1])
    assert np.all(Ft[stuck] <= mu_s * N[stuck] + 1e-6)
    free = w["foot_state"] == 0
    # the tripods alternate: legs 0, 2, 4 and 1, 3, 5 never all free at once, each foot swings
    assert not np.any(free[:, [0, 2, 4]].all(axis=1) & free[:, [1, 3, 5]].all(axis=1))
    assert np.all(free.any(axis=0))


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_walks_straight(hexapod, integrator):
    w = hexapod.walk(**GAIT, step_length_m=0.12, t_end_s=2.4, integrator=integrator)
    yaw, tilt = yaw_tilt(w["box_quat"])
    planned = 2 * 0.12 / GAIT["duty"]
    x, y, z = w["box_m"][-1]
    print(f"straight ({integrator}): box at ({x:.4f}, {y:.4f}, {z:.4f}) m (planned x {planned:.3f}), heading "
          f"{np.degrees(np.abs(yaw).max()):.2f} deg, tilt {np.degrees(tilt.max()):.2f} deg, height "
          f"{w['box_m'][:, 2].min():.4f} .. {w['box_m'][:, 2].max():.4f} m, {w['impacts'][-1]} impacts, "
          f"{w['events'].sum()} events")
    assert abs(x - planned) < 0.1 * planned and abs(y) < 0.02
    assert np.abs(w["box_m"][:, 2] - GAIT["box_height_m"]).max() < 0.02
    assert np.degrees(np.abs(yaw).max()) < 1 and np.degrees(tilt.max()) < 3
    assert w["impacts"][-1] >= 6  # at least one touchdown per swing
    contact_invariants(hexapod, w)
    cone = w["cone"]
    print(f"  the contact problems on the cones: {cone}")
    assert cone["solved"] >= w["impacts"][-1] and cone["max_residual"] <= 1e-10


def test_turns_on_the_spot(hexapod):
    w = hexapod.walk(**GAIT, step_length_m=0.0, turn_rad=0.15, t_end_s=2.4)
    yaw, tilt = yaw_tilt(w["box_quat"])
    planned = 2 * 0.15 / GAIT["duty"]
    print(f"turning: yaw {yaw[-1]:.4f} rad (planned {planned:.3f}), box moved "
          f"{np.hypot(*w['box_m'][-1, :2]):.4f} m, tilt {np.degrees(tilt.max()):.2f} deg, {w['impacts'][-1]} impacts")
    assert abs(yaw[-1] - planned) < 0.1 * planned
    assert np.hypot(*w["box_m"][-1, :2]) < 0.03 and np.degrees(tilt.max()) < 3
    contact_invariants(hexapod, w)


def test_bench_command_writes_its_checks_and_animation(tmp_path):
    """`legsim-bench hexapod` (the demo's last part): its checks pass and it writes the walk's
    plot and its 3D animation (a GIF of about one frame per 0.1 s: Pillow merges equal ones)."""
    from PIL import Image

    from legsim_bench.hexapod_walk import run_walk
    from legsim_bench.scene import find_root

    ok, rows, files = run_walk(find_root(None), tmp_path, periods=1)
    assert ok, rows
    names = sorted(p.name for p in files)
    assert names == ["hexapod_walk.gif", "hexapod_walk.png"]
    with Image.open(tmp_path / "hexapod_walk.gif") as im:
        assert 10 <= im.n_frames <= 13  # 1.2 s at 10 frames a second, both ends
