"""The bench on any python-can interface by python-can's own configuration (docs/can-hardware.md):
a config file or the environment (CAN_INTERFACE, CAN_CHANNEL, CAN_BITRATE) names the adapter,
its bit rates or its full CAN FD bit timing, and exactly that reaches can.Bus, with CAN FD on;
`--start-hil` starts hil_sim on the SocketCAN channel the configuration names and refuses
another interface. No adapter needed: can.Bus is observed, the bus is python-can's virtual one."""
from __future__ import annotations

import stat

import pytest

can = pytest.importorskip("can")
from can.interfaces.virtual import VirtualBus  # noqa: E402

from legsim_bench import cli  # noqa: E402
from legsim_bench.hil import can_link as cl  # noqa: E402
from legsim_bench.hil import runner  # noqa: E402
from legsim_bench.hil.can_link import HilLink, bus_config  # noqa: E402


@pytest.fixture
def canrc(monkeypatch, tmp_path):
    """write(text) -> path: python-can's only configuration file for the test."""
    for k in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(k, raising=False)
    monkeypatch.setattr(can, "rc", {})
    path = tmp_path / "can.ini"

    def write(text: str):
        path.write_text("[default]\n" + text)
        monkeypatch.setattr(can.util, "CONFIG_FILES", [str(path)])
        return path
    return write


@pytest.fixture
def opened(monkeypatch):
    """The keyword arguments HilLink gives can.Bus (a virtual bus stands in for the adapter)."""
    seen = []

    def bus(**kwargs):
        seen.append(kwargs)
        return VirtualBus(channel="hw-stand-in")
    monkeypatch.setattr(cl.can, "Bus", bus)
    return seen


def test_kvaser_bit_rates_from_the_config_file(canrc, opened):
    canrc("interface = kvaser\nchannel = 0\nbitrate = 1000000\ndata_bitrate = 4000000\n")
    with HilLink(timeout=0.1) as link:
        assert "kvaser channel 0, CAN FD" in link.description
    kw = opened[0]
    assert (kw["interface"], kw["channel"], kw["bitrate"], kw["data_bitrate"], kw["fd"]) == \
        ("kvaser", 0, 1_000_000, 4_000_000, True)
    # only hil_sim's frames are let in (a busy bus stays out of the bench's queue)
    assert sorted(f["can_id"] for f in kw["can_filters"]) == sorted(cl.HIL_IDS)


def test_pcan_fd_bit_timing_from_the_config_file(canrc, opened):
    canrc("interface = pcan\nchannel = PCAN_USBBUS1\nf_clock = 80000000\n"
          "nom_brp = 1\nnom_tseg1 = 63\nnom_tseg2 = 16\nnom_sjw = 16\n"
          "data_brp = 1\ndata_tseg1 = 11\ndata_tseg2 = 4\ndata_sjw = 4\n")
    HilLink(timeout=0.1).close()
    timing = opened[0]["timing"]
    assert isinstance(timing, can.BitTimingFd)
    assert (timing.nom_bitrate, timing.data_bitrate) == (1_000_000, 5_000_000)
    assert timing.nom_sample_point == pytest.approx(80.0) and timing.data_sample_point == pytest.approx(75.0)


def test_the_environment_overrides_the_file(canrc, monkeypatch):
    canrc("interface = kvaser\nchannel = 0\nbitrate = 1000000\n")
    monkeypatch.setenv("CAN_BITRATE", "500000")
    monkeypatch.setenv("CAN_CHANNEL", "1")
    cfg = bus_config()
    assert (cfg["interface"], str(cfg["channel"]), cfg["bitrate"], cfg["fd"]) == ("kvaser", "1", 500_000, True)


def test_start_hil_refuses_a_configured_adapter_that_is_not_socketcan(canrc, capsys, tmp_path):
    path = canrc("interface = pcan\nchannel = PCAN_USBBUS1\n")
    rc = cli.main(["record", "--start-hil", "--out", str(tmp_path), "free_fall"])
    err = capsys.readouterr().err
    assert rc == 2 and "runs hil_sim on socketcan, not on pcan" in err and str(path) in err


def test_start_hil_takes_the_configured_socketcan_channel(canrc, capsys, monkeypatch, tmp_path):
    """hil_sim is started on can0 named by the file (a stand-in binary; its argv is taken where
    the bench starts it, not from the child, which may not have run yet when it is stopped);
    the bench then opens socketcan can0 and says where the channel came from."""
    path = canrc("interface = socketcan\nchannel = can0\n")
    fake = tmp_path / "hil_sim"
    fake.write_text("#!/bin/sh\nexec sleep 30\n")
    fake.chmod(fake.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("LEGSIM_HIL_SIM", str(fake))
    started = []
    popen = runner.subprocess.Popen

    def record_argv(argv, *a, **kw):
        started.append(list(argv))
        return popen(argv, *a, **kw)
    monkeypatch.setattr(runner.subprocess, "Popen", record_argv)
    rc = cli.main(["record", "--start-hil", "--timeout", "0.2", "--no-progress", "--out",
                   str(tmp_path / "out"), "free_fall"])
    out, err = capsys.readouterr()
    hil = [argv for argv in started if argv[0] == str(fake)]   # (legsim_cli reads the scene)
    assert len(hil) == 1 and hil[0][1:3] == ["--channel", "can0"]
    assert "hil_sim started on can0" in out
    # no SocketCAN (or no can0) here: the bus cannot open and says which and from where
    if rc == 2:
        assert f"socketcan channel can0, CAN FD (interface: --start-hil, channel: {path})" in err
    else:  # a machine with a real can0 and nobody answering
        assert f"(interface: --start-hil, channel: {path})" in out
