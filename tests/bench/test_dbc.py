"""can/legsim.dbc is can/gen_dbc.py's output from can/legsim.dbc.in (each leg's frames written
once, for leg 0), and the generator makes a robot of any number of legs."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import cantools
import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("gen_dbc", ROOT / "can" / "gen_dbc.py")
gen_dbc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen_dbc)

TEMPLATE = (ROOT / "can" / "legsim.dbc.in").read_text()
LEG_FRAMES = ("ACT_CMD", "LOAD_CMD", "ST_POS", "ST_VEL", "ST_ACT", "ST_REACT_A", "ST_REACT_B", "ST_STATUS",
              "ST_CONTACT")


def _db(text: str):
    return cantools.database.load_string(text, database_format="dbc", strict=True)


def test_the_committed_dbc_is_the_generator_s_output():
    assert gen_dbc.generate(TEMPLATE) == (ROOT / "can" / "legsim.dbc").read_text(), \
        "can/legsim.dbc differs from its template: python3 can/gen_dbc.py -o can/legsim.dbc"


@pytest.mark.parametrize("legs", [1, 2])   # CONTROL holds the RESET lengths (float64) of 2 legs
def test_every_leg_has_leg_0_s_frames_at_its_own_ids(legs):
    db = _db(gen_dbc.generate(TEMPLATE, legs))
    for name in LEG_FRAMES:
        base = db.get_message_by_name(name)
        for k in range(1, legs):
            m = db.get_message_by_name(f"{name}_L{k}")
            assert m.frame_id == base.frame_id + 0x20 * k
            assert [s.name for s in m.signals] == [s.name for s in base.signals]
            assert [(s.start, s.length, s.is_float) for s in m.signals] == \
                [(s.start, s.length, s.is_float) for s in base.signals]
            hil = f"HIL_L{k}"
            if base.senders == ["HIL"]:            # hil_sim's state frames: sent by leg k's node
                assert m.senders == [hil]
            else:                                    # the bench's commands: received by it
                assert base.senders == ["BENCH"] and all(set(s.receivers) == {hil} for s in m.signals)
        with pytest.raises(KeyError):
            db.get_message_by_name(f"{name}_L{legs}")
    ctrl = db.get_message_by_name("CONTROL")
    names = [s.name for s in ctrl.signals]
    for k in range(legs):
        suffix = f"_L{k}" if k else ""
        assert ctrl.get_signal_by_name(f"Ctrl_Length_upper{suffix}").start == 192 + 128 * k
    assert ctrl.get_signal_by_name("Ctrl_FreeContacts").maximum == 2 ** legs - 1
    assert len(names) == len(set(names))
    assert sorted(n.name for n in db.nodes) == sorted(["BENCH", "HIL"] + [f"HIL_L{k}" for k in range(1, legs)])


def test_a_template_error_is_named():
    with pytest.raises(gen_dbc.TemplateError, match="no frame NOPE"):
        gen_dbc.generate("@legs right left\n@copy BO_ NOPE\n")
    with pytest.raises(gen_dbc.TemplateError, match="no legs"):
        gen_dbc.generate("VERSION \"1\"\n")
    with pytest.raises(gen_dbc.TemplateError, match="has no @}"):
        gen_dbc.generate("@legs right\n@each{\nx\n")


def test_the_link_takes_the_legs_and_actuators_from_the_dbc(tmp_path):
    from legsim_bench.hil import can_link as cl
    from legsim_bench.scene import load_scene

    assert (cl.ROBOT_LEGS, cl.ACTUATORS) == (2, ("upper", "lower"))
    p = tmp_path / "legsim.dbc"
    p.write_text(gen_dbc.generate(TEMPLATE, 3))
    assert cl._dbc_legs_and_actuators(p) == (3, ("upper", "lower"))
    assert [cl.leg_frame("ACT_CMD", k) for k in range(3)] == ["ACT_CMD", "ACT_CMD_L1", "ACT_CMD_L2"]
    # the runner's legs are the scene's model's
    assert load_scene("robot_fig7", ROOT).legs == 2 and load_scene("upper_step_50N", ROOT).legs == 1
