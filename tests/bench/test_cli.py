"""The legsim-bench command line without CAN: argument handling, exit codes, dry runs (the
reference model plays hil_sim), check of recordings, python-can's virtual bus with nobody on
it, and the lazily loaded benchmark commands."""
import json
import subprocess
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.cli  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench import cli  # noqa: E402


def run(capsys, *argv):
    rc = cli.main(list(argv))
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.fixture(scope="module")
def dry_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("dry")
    assert cli.main(["run", "--dry-run", "--no-plots", "--no-progress", "--out", str(out), "free_fall"]) == 0
    return out


def test_scenes_lists_the_shipped_ones(capsys):
    rc, out, _ = run(capsys, "scenes")
    assert rc == 0
    for name in ("free_fall", "upper_step_50N", "length_sinusoid", "static_hold_300N", "slot_variant",
                 "stroke_end", "bad_input"):
        assert name in out
    demo = next(l for l in out.splitlines() if l.startswith("upper_step_50N"))
    assert "demo" in demo


def test_scenes_verbose_shows_tolerances(capsys):
    rc, out, _ = run(capsys, "scenes", "-v")
    assert rc == 0 and "check position_m <= 1e-05" in out and "-> CMD_TIMEOUT" in out


def test_dry_run_writes_the_run(dry_dir):
    d = dry_dir / "free_fall"
    for f in ("recording.json", "samples.csv", "reference.csv", "checks.csv", "checks.json"):
        assert (d / f).is_file(), f
    assert not list(d.glob("*.png"))          # --no-plots
    rec = json.loads((d / "recording.json").read_text())
    assert rec["format"] == "legsim-bench-recording/1" and rec["dry_run"] and rec["complete"]
    assert json.loads((d / "checks.json").read_text())["passed"] is True


def test_check_passes_a_good_recording_and_fails_a_bad_one(capsys, dry_dir, tmp_path):
    rc, out, _ = run(capsys, "check", "--no-plots", "--out", str(tmp_path / "a"), str(dry_dir))
    assert rc == 0 and "free_fall: PASS" in out and "ALL PASS" in out
    assert (tmp_path / "a" / "free_fall" / "checks.json").is_file()
    rec = json.loads((dry_dir / "free_fall" / "recording.json").read_text())
    rec["samples"][-1]["q"][4] += 1e-3
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(rec))
    rc, out, _ = run(capsys, "check", "--no-plots", "--brief", "--out", str(tmp_path / "b"), str(bad))
    assert rc == 1
    assert "free_fall: FAIL" in out and "FAILED: free_fall" in out


def test_check_refuses_what_is_not_a_recording(capsys, tmp_path):
    rc, _, err = run(capsys, "check", str(tmp_path / "missing.json"))
    assert rc == 2 and "cannot read" in err
    p = tmp_path / "x.json"
    p.write_text('{"format": "something else"}')
    rc, _, err = run(capsys, "check", str(p))
    assert rc == 2 and "not a legsim-bench recording" in err
    rc, _, err = run(capsys, "check", str(tmp_path))
    assert rc == 2 and "no recording" in err


def test_usage_errors(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["run"])
    assert e.value.code == 2
    with pytest.raises(SystemExit) as e:
        cli.main(["frobnicate"])
    assert e.value.code == 2
    with pytest.raises(SystemExit) as e:
        cli.main(["scenes", "--bogus"])
    assert e.value.code == 2
    rc, _, err = run(capsys, "run", "--dry-run", "no_such_scene")
    assert rc == 2 and "no scene 'no_such_scene'" in err


def test_a_bad_scene_file_names_the_problem(capsys, tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('duration = 0.1\nvariant = "hinge"\n[checks]\nposition_m = 1e-5\n')
    rc, _, err = run(capsys, "run", "--dry-run", str(p))
    assert rc == 2 and str(p) in err and "variant" in err


def test_no_repository(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("LEGSIM_ROOT", str(tmp_path))
    rc, _, err = run(capsys, "scenes")
    assert rc == 2 and "LEGSIM_ROOT" in err


def test_a_bus_with_nobody_on_it_fails_cleanly(capsys, tmp_path):
    pytest.importorskip("can")
    rc, out, err = run(capsys, "run", "--interface", "virtual", "--channel", f"nobody-{id(tmp_path)}",
                       "--timeout", "0.3", "--no-plots", "--no-progress", "--out", str(tmp_path), "free_fall")
    assert rc == 1
    assert "INCOMPLETE" in out and "no answer" in out
    assert "run: all exchanges answered" in out and "FAIL" in out
    rec = json.loads((tmp_path / "free_fall" / "recording.json").read_text())
    assert rec["errors"] and not rec["complete"]


def test_start_hil_needs_socketcan_and_a_binary(capsys, monkeypatch, tmp_path):
    rc, _, err = run(capsys, "record", "--start-hil", "--interface", "virtual", "free_fall")
    assert rc == 2 and "socketcan" in err
    monkeypatch.setenv("LEGSIM_HIL_SIM", str(tmp_path / "no_hil_sim"))
    rc, _, err = run(capsys, "record", "--start-hil", "--out", str(tmp_path), "free_fall")
    assert rc == 2 and "hil_sim not found" in err


def test_demo_without_hil_sim_says_how_to_build_it(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("LEGSIM_HIL_SIM", str(tmp_path / "no_hil_sim"))
    rc, _, err = run(capsys, "demo", "--out", str(tmp_path))
    assert rc == 2 and "--build" in err


def test_benchmarks_load_lazily_and_get_their_own_options(capsys, monkeypatch):
    mod = types.ModuleType("legsim_bench._fake_bench")

    def configure_parser(p):
        p.add_argument("--quick", action="store_true")
        p.add_argument("--n", type=int, default=1)

    seen = {}

    def run_(args):
        seen.update(vars(args))
        return 7

    mod.configure_parser, mod.run = configure_parser, run_
    monkeypatch.setitem(sys.modules, "legsim_bench._fake_bench", mod)
    monkeypatch.setitem(cli.BENCHMARKS, "stress", ("legsim_bench._fake_bench", "fake"))
    assert cli.main(["stress", "--quick", "--n", "3"]) == 7
    assert seen == {"quick": True, "n": 3}
    with pytest.raises(SystemExit) as e:
        cli.main(["stress", "--help"])
    assert e.value.code == 0
    assert "--quick" in capsys.readouterr().out


def test_a_missing_benchmark_module_is_a_clear_error(capsys, monkeypatch):
    monkeypatch.setitem(cli.BENCHMARKS, "options", ("legsim_bench.no_such_module", "x"))
    rc, _, err = run(capsys, "options", "--anything")
    assert rc == 2 and "legsim_bench.no_such_module is missing" in err


def test_python_dash_m_works():
    r = subprocess.run([sys.executable, "-m", "legsim_bench", "--help"], capture_output=True, text=True,
                       cwd=ROOT, env={"PYTHONPATH": str(ROOT / "bench"), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0 and "legsim-bench" in r.stdout and "record" in r.stdout


def test_record_imports_no_scipy_nor_matplotlib():
    code = ("import sys; from legsim_bench import cli, recording, scene; "
            "from legsim_bench.hil import can_link, cli_run, runner; "
            "bad = [m for m in ('scipy', 'matplotlib', 'legsim_bench.verdict', 'legsim_bench.reference') "
            "if m in sys.modules]; "
            "print(bad); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                       env={"PYTHONPATH": str(ROOT / "bench"), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stdout + r.stderr


def test_the_demo_s_scenes_all_run_over_can():
    """The demo records its scenes in one run on the bus (tools/with-vcan) and checks the
    recordings: a scene it could only run in legsim_cli would have no recording."""
    from legsim_bench import cli

    scenes = cli._load_scenes(list(cli.DEMO_SCENES), ROOT)
    assert [sc.name for sc in scenes] == ["upper_step_50N", "robot_fig7"]
    assert all(sc.over_can for sc in scenes)


def test_log_and_sniff_without_frames_to_log_are_refused(capsys, tmp_path):
    """--log and --sniff need a bus: with --dry-run, or when no scene runs over CAN, they are
    refused (exit 2, nothing recorded) instead of doing nothing."""
    from legsim_bench.scene import load_scene

    for opts in (["--log", str(tmp_path / "t.log")], ["--sniff", str(tmp_path / "bus.asc")]):
        rc, _, err = run(capsys, "run", "--dry-run", "--no-plots", "--no-progress", "--out",
                         str(tmp_path / "dry"), *opts, "free_fall")
        assert rc == 2 and f"{opts[0]}: a --dry-run uses no bus" in err
        assert not (tmp_path / "dry").exists()
    assert not load_scene("statics_foot_300N", ROOT).over_can
    rc, _, err = run(capsys, "record", "--no-progress", "--out", str(tmp_path / "cli"),
                     "--log", str(tmp_path / "t.log"), "--sniff", str(tmp_path / "bus.asc"),
                     "statics_foot_300N")
    assert rc == 2 and "--log and --sniff: no scene given runs over CAN" in err
    assert not (tmp_path / "cli").exists() and not (tmp_path / "t.log").exists()


def test_check_log_names_a_recording_whose_scene_the_bench_cannot_run(capsys, tmp_path, dry_dir):
    """check --log takes the scene from the recording.json beside the trace: a scene the bench
    cannot run (here a variant CAN does not carry) is a clear error, exit 2."""
    rec = json.loads((dry_dir / "free_fall" / "recording.json").read_text())
    rec["scene_resolved"]["variant"] = "hinge"
    (tmp_path / "recording.json").write_text(json.dumps(rec))
    rc, _, err = run(capsys, "check", "--no-plots", "--log", str(tmp_path / "trace.log"))
    assert rc == 2
    assert f"{tmp_path / 'trace.log'}: the scene of {tmp_path / 'recording.json'} cannot be run" in err
    assert "over CAN the variant is Ctrl_Variant" in err
