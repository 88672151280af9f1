"""The leg's inverse kinematics (legsim_assemble_foot, Python Sim.assemble_foot) against the
bench's independent model of the leg (legsim_bench.reference.model.LegModel: closed-form poses
from the actuator lengths):

- over a grid of lengths inside the strokes, the reference's foot for those lengths, given to
  the core from its stand pose, gives back the lengths to 1e-9 m and the reference's pose;
- a foot out of reach is refused (the state unchanged); one that needs a length past a stroke
  is refused with OutOfStrokeError; a robot (its feet are contacts) with BadInputError.
"""
from __future__ import annotations

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

from legsim_bench.reference.model import LegModel  # noqa: E402
from model_files import LEG_TOML, ROBOT  # noqa: E402


@pytest.fixture(scope="module")
def leg():
    return LegModel.from_toml(LEG_TOML), legsim.Model.from_toml(str(LEG_TOML))


def test_foot_gives_back_the_lengths(leg):
    ref, model = leg
    lo = np.array([a.stroke[0] for a in ref.actuators]) + 0.02
    hi = np.array([a.stroke[1] for a in ref.actuators]) - 0.02
    worst_len = worst_q = 0.0
    n = 0
    for l0 in np.linspace(lo[0], hi[0], 5):
        for l1 in np.linspace(lo[1], hi[1], 5):
            try:
                th = ref.theta_from_lengths([l0, l1], near=ref.stand_theta())
            except ValueError:
                continue  # lengths the leg cannot take together
            foot = ref.foot(th)
            s = legsim.Sim(model)
            s.assemble_pose("stand")
            try:
                s.assemble_foot(foot)
            except legsim.errors.LegsimError:
                continue  # the stand's branch does not reach it
            worst_len = max(worst_len, float(np.max(np.abs(s.actuator_lengths()[0] - [l0, l1]))))
            worst_q = max(worst_q, float(np.max(np.abs(np.asarray(s.q) - ref.absolute_q(th)))))
            assert np.max(np.abs(s.foot() - foot)) < 1e-10
            n += 1
    print(f"{n} feet: lengths within {worst_len:.2e} m, poses within {worst_q:.2e}")
    assert n >= 15
    assert worst_len < 1e-9 and worst_q < 1e-9


def test_refusals(leg, tmp_path):
    ref, model = leg
    s = legsim.Sim(model)
    q0 = s.assemble_pose("stand").copy()
    with pytest.raises(legsim.errors.LegsimError):
        s.assemble_foot([3.0, -3.0])  # far out of reach
    assert np.array_equal(s.q, q0)
    # the foot of an upper length of 0.45 m, on a copy whose upper stroke starts at 0.50 m
    th = ref.theta_from_lengths([0.45, ref.lengths(ref.stand_theta())[1]], near=ref.stand_theta())
    foot = ref.foot(th)
    s.assemble_foot(foot)  # the whole stroke: reached
    assert abs(s.actuator_lengths()[0][0] - 0.45) < 1e-9
    text = LEG_TOML.read_text()
    assert text.count("stroke = [0.40, 0.80]") == 1
    (tmp_path / "leg.toml").write_text(text.replace("stroke = [0.40, 0.80]", "stroke = [0.50, 0.80]"))
    narrow = legsim.Sim(legsim.Model.from_toml(str(tmp_path / "leg.toml")))
    q1 = narrow.assemble_pose("stand").copy()
    with pytest.raises(legsim.errors.OutOfStrokeError):
        narrow.assemble_foot(foot)
    assert np.array_equal(narrow.q, q1)
    robot = legsim.Sim(legsim.Model.from_toml(str(ROBOT)))
    with pytest.raises(legsim.errors.BadInputError):
        robot.assemble_foot([0.0, 0.0])
