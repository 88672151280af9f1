"""Calls made of several C calls are all or nothing too, and a refused input is named.

``Sim.assemble_on_ground`` assembles the pose's guess, then the stance: a refused stance
(lengths out of stroke or unreachable, a bad ``feet_mid``, a bad ``lengths`` argument)
must leave q, qd, the time and the contacts as they were. An out-of-range force names
the argument, its value and its range.
"""
from __future__ import annotations

import ctypes
import re

import numpy as np
import pytest

import legsim
from legsim import sim as sim_module

from conftest import ROOT

ROBOT = ROOT / "models" / "robot.toml"


def _robot() -> legsim.Sim:
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip(f"{lib.path} is built without room for the robot")
    return legsim.Sim(str(ROBOT), integrator="rk4", step=1e-3)


def _snapshot(s: legsim.Sim):
    return s.q.copy(), s.qd.copy(), s.time, s.step_count, s.contacts().copy()


def _same(a, b) -> None:
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert a[2] == b[2] and a[3] == b[3]
    assert list(a[4]["state"]) == list(b[4]["state"])
    assert np.array_equal(a[4]["position"], b[4]["position"])


@pytest.fixture
def moving_robot() -> legsim.Sim:
    """Stood on the ground, then 20 steps with both lower actuators pushing: q differs from
    every pose guess, qd != 0, both feet stuck."""
    s = _robot()
    s.assemble_on_ground()
    for a in ("right.lower", "left.lower"):
        s.command_force(a, 50.0)
    s.step(20)
    assert np.abs(s.qd).max() > 1e-4
    assert list(s.contacts()["state"]) == ["stuck", "stuck"]
    return s


@pytest.mark.parametrize("kwargs, error", [
    ({"lengths": [0.30, 0.30, 0.30, 0.30]}, legsim.OutOfStrokeError),
    ({"feet_mid": 1e9}, legsim.BadInputError),
    ({"feet_mid": float("nan")}, legsim.BadInputError),
    ({"lengths": [0.66, 0.62]}, ValueError),
    ({"pose": "no_such_pose"}, ValueError),
])
def test_refused_assemble_on_ground_changes_nothing(moving_robot, kwargs, error):
    before = _snapshot(moving_robot)
    with pytest.raises(error):
        moving_robot.assemble_on_ground(**kwargs)
    _same(_snapshot(moving_robot), before)
    # and the sim steps on from there as if the call had not been made
    twin = _robot()
    twin.assemble_on_ground()
    for a in ("right.lower", "left.lower"):
        twin.command_force(a, 50.0)
    twin.step(20)
    moving_robot.step(5)
    twin.step(5)
    assert np.array_equal(moving_robot.q, twin.q)


def _storage(s: legsim.Sim) -> bytes:
    """The whole sim: every byte of its storage (the sim keeps nothing outside it)."""
    return ctypes.string_at(s.handle.value, s.library.sim_size)


def _everything(s: legsim.Sim) -> dict:
    """Everything the sim tells through its public calls (raw bytes where it has them)."""
    out = {"state": s.state_bytes(), "qdd": s.qdd.tobytes(), "time": s.time,
           "steps": s.step_count, "report": repr(s.report()), "stroke": s.stroke_event_mask(),
           "constraints": s.constraints()[0].tobytes(),
           "lengths": b"".join(a.tobytes() for a in s.actuator_lengths()),
           "forces": s.actuator_forces().tobytes(), "multipliers": s.multipliers().tobytes(),
           "reactions": s.reactions().tobytes(), "contacts": s.contacts().tobytes(),
           "options": s.options}
    return out


# Each refusal at its own stage: the argument check before any C call, the pose's assembly
# (pose is applied first), the stance's range check, the stance's solve. A refused call at
# the stance's stages has already run the pose's assembly (q moved, feet made free) inside.
@pytest.mark.parametrize("kwargs, error", [
    ({"lengths": [0.66, 0.62]}, ValueError),
    ({"pose": "no_such_pose"}, ValueError),
    ({"feet_mid": 1e9}, legsim.BadInputError),
    ({"feet_mid": float("nan")}, legsim.BadInputError),
    ({"lengths": [0.30, 0.30, 0.30, 0.30]}, legsim.OutOfStrokeError),
    ({"lengths": [0.30, 0.30, 0.30, 0.30], "pose": None}, legsim.OutOfStrokeError),
])
def test_refused_assemble_on_ground_leaves_the_whole_state(moving_robot, kwargs, error):
    """The full state, not a few fields: every byte of the sim's storage and every public
    output are the same after the refused call as before it (and the storage is compared
    before any public read after the call)."""
    moving_robot.command_length("left.upper", 0.62)  # a command of each kind in the state
    moving_robot.step(1)
    seen = _everything(moving_robot)
    storage = _storage(moving_robot)  # after the reads: legsim_constraints uses scratch in it
    with pytest.raises(error):
        moving_robot.assemble_on_ground(**kwargs)
    assert _storage(moving_robot) == storage
    after = _everything(moving_robot)
    for key in seen:
        assert after[key] == seen[key], key


def test_assemble_on_ground_bad_feet_mid_is_named(moving_robot):
    with pytest.raises(legsim.BadInputError, match=r"feet_mid = 1e\+09 m is outside its "
                                                   r"range \[-1000, 1000\] m"):
        moving_robot.assemble_on_ground(feet_mid=1e9)


def test_out_of_range_force_is_named():
    s = legsim.Sim(integrator="rk4", step=1e-3)  # the compiled-in leg
    s.assemble_pose("stand")
    fmax = s.model.max_forces[0]
    with pytest.raises(legsim.BadInputError) as e:
        s.command_force("upper", 3 * fmax)
    msg = str(e.value)
    assert "force_n of actuator 'upper'" in msg
    assert f"{3 * fmax:g} N" in msg and f"[{-fmax:g}, {fmax:g}] N" in msg
    with pytest.raises(legsim.BadInputError, match=r"force_n of actuator 'lower' = nan N"):
        s.command_force("lower", float("nan"))


def test_out_of_range_load_is_named():
    s = _robot()
    s.assemble_on_ground()
    if s.n_forces == 0:
        pytest.fail("models/robot.toml has force elements (its foot loads)")
    with pytest.raises(legsim.BadInputError, match=r"value\[1\] = -2e\+06 N or N m is outside "
                                                   r"its range \[-1e\+06, 1e\+06\]"):
        s.set_force(0, [0.0, -2e6])


def test_range_mirror_matches_legsim_h():
    h = (ROOT / "firmware_core" / "include" / "legsim" / "legsim.h").read_text()
    for name, value in (("LEGSIM_MAX_COORD", sim_module.MAX_COORD),
                        ("LEGSIM_MAX_FORCE_N", sim_module.MAX_FORCE_N)):
        m = re.search(rf"^#define {name}\s+(\S+)", h, re.M)
        assert m and float(m.group(1)) == value, name
