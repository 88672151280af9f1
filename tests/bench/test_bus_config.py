"""Which CAN bus the bench opens, and that it says so: python-can's configuration (arguments,
environment CAN_INTERFACE/CAN_CHANNEL, a config file, else socketcan on vcan0) and where each
value came from, printed by `record`/`run` when the bus opens. No SocketCAN needed: python-can's
virtual interface."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

can = pytest.importorskip("can")

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.hil.can_link  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench import cli  # noqa: E402
from legsim_bench.hil.can_link import HilLink, bus_config, bus_origin, describe_bus  # noqa: E402


@pytest.fixture
def no_config(monkeypatch):
    """No python-can configuration from this machine: no environment, no files, no can.rc."""
    for k in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(k, raising=False)
    monkeypatch.setattr(can.util, "CONFIG_FILES", [])
    monkeypatch.setattr(can, "rc", {})


def described(interface=None, channel=None, given_by=None) -> str:
    cfg = bus_config(interface, channel)
    return describe_bus(cfg, bus_origin(interface, channel, cfg, given_by))


def test_arguments(no_config):
    assert described("virtual", "leg") == \
        "virtual channel leg, CAN FD (interface: --interface, channel: --channel)"


def test_default_is_socketcan_on_vcan0(no_config):
    assert described() == "socketcan channel vcan0, CAN FD (interface: default, channel: default)"


def test_environment(no_config, monkeypatch):
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", "from-env")
    assert described() == \
        "virtual channel from-env, CAN FD (interface: CAN_INTERFACE, channel: CAN_CHANNEL)"
    # an argument wins over the environment, and says so
    assert described(channel="arg") == \
        "virtual channel arg, CAN FD (interface: CAN_INTERFACE, channel: --channel)"


def test_config_file(no_config, monkeypatch, tmp_path):
    rc = tmp_path / "canrc"
    rc.write_text("[default]\ninterface = virtual\nchannel = from-file\n")
    monkeypatch.setattr(can.util, "CONFIG_FILES", [str(rc)])
    assert described() == f"virtual channel from-file, CAN FD (interface: {rc}, channel: {rc})"


def test_start_hil_names_itself(no_config):
    assert described("socketcan", "vcan0", {"interface": "--start-hil", "channel": "--start-hil"}) \
        == "socketcan channel vcan0, CAN FD (interface: --start-hil, channel: --start-hil)"


def test_the_link_keeps_its_description(no_config):
    with HilLink("virtual", "described", dbc=ROOT / "can" / "legsim.dbc", timeout=0.1) as link:
        assert link.description == \
            "virtual channel described, CAN FD (interface: --interface, channel: --channel)"


def test_record_prints_the_bus_it_opened(capsys, no_config, tmp_path):
    rc = cli.main(["record", "--interface", "virtual", "--channel", f"nobody-{id(tmp_path)}",
                   "--timeout", "0.2", "--no-progress", "--out", str(tmp_path), "free_fall"])
    out = capsys.readouterr().out
    assert rc == 1  # nobody answers
    bus_lines = [l for l in out.splitlines() if l.startswith("bus: ")]
    assert bus_lines == [f"bus: virtual channel nobody-{id(tmp_path)}, CAN FD "
                         "(interface: --interface, channel: --channel)"]


def test_a_bus_that_cannot_open_is_named(capsys, no_config, monkeypatch, tmp_path):
    monkeypatch.setenv("CAN_CHANNEL", "no-such-can")
    rc = cli.main(["record", "--interface", "socketcan", "--timeout", "0.2", "--no-progress",
                   "--out", str(tmp_path), "free_fall"])
    err = capsys.readouterr().err
    if rc == 1:
        pytest.fail("a socketcan bus on no-such-can opened")
    assert rc == 2
    assert "cannot open the CAN bus socketcan channel no-such-can, CAN FD (interface: " \
           "--interface, channel: CAN_CHANNEL)" in err
