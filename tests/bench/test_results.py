"""The benchmarks' common options and result files (bench/legsim_bench/results.py): where they
write (out/bench-results/ unless told, bench/results/ only with --update-results), option
names with one meaning (--out/-o everywhere, --step-sizes vs --n-steps, the old --steps
refused with the new name), and the machine section (CPU, cores, load before/after, date,
commit) in every result file.

The runs of `stress`, `options` and `workprecision` here are tiny (a few seconds): they need
liblegsim.so and are skipped, with that reason, only when it is not built.
"""
from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.benchmarks.results  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench import cli
from legsim_bench.benchmarks import results  # noqa: E402

BENCH_MODULES = {name: module for name, (module, _) in cli.BENCHMARKS.items()}
MACHINE_LINES = (r"^## Machine$", r"^- CPU: .+, \d+ cores; ", r"^- load average \(1, 5, 15 min\) "
                 r"before / after: [\d.]+ [\d.]+ [\d.]+ / [\d.]+ [\d.]+ [\d.]+$",
                 r"^- date: \d{4}-\d\d-\d\dT\d\d:\d\d:\d\d to \d{4}-", r"^- commit: \S+")


def parser_of(name: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=f"legsim-bench {name}")
    importlib.import_module(BENCH_MODULES[name]).configure_parser(p)
    return p


def refused(p: argparse.ArgumentParser, argv: list[str], capsys) -> str:
    with pytest.raises(SystemExit) as e:
        p.parse_args(argv)
    assert e.value.code == 2
    return capsys.readouterr().err


# ---- options --------------------------------------------------------------------------------

def test_every_benchmark_has_out_and_update_results(monkeypatch, tmp_path, capsys):
    assert set(BENCH_MODULES) >= {"workprecision", "options", "stress", "mcu"}
    monkeypatch.setenv("LEGSIM_ROOT", str(ROOT))
    for name in BENCH_MODULES:
        p = parser_of(name)
        default = results.output_dir(p.parse_args([]))
        assert default == ROOT / "out" / "bench-results", name
        assert default != ROOT / "bench" / "results"
        assert results.output_dir(p.parse_args(["-o", str(tmp_path)])) == tmp_path
        assert results.output_dir(p.parse_args(["--out", str(tmp_path)])) == tmp_path
        assert results.output_dir(p.parse_args(["--update-results"])) == ROOT / "bench" / "results"
        err = refused(p, ["--out", str(tmp_path), "--update-results"], capsys)
        assert "not allowed with" in err


def test_step_sizes_and_step_counts_have_their_own_names(capsys):
    wp = parser_of("workprecision")
    assert wp.parse_args(["--step-sizes", "1e-3", "1e-4"]).step_sizes == [1e-3, 1e-4]
    err = refused(wp, ["--steps", "1e-3"], capsys)
    assert "--steps was renamed: use --step-sizes" in err
    st = parser_of("stress")
    assert st.parse_args(["--n-steps", "5000"]).n_steps == 5000
    err = refused(st, ["--steps", "5000"], capsys)
    assert "--steps was renamed: use --n-steps" in err
    # neither spelling of the other command is taken by mistake
    refused(st, ["--step-sizes", "1e-3"], capsys)
    refused(wp, ["--n-steps", "10"], capsys)


def test_the_old_spelling_is_refused_through_the_command_line(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["stress", "--steps", "10"])
    assert e.value.code == 2
    assert "use --n-steps" in capsys.readouterr().err


# ---- the machine section ----------------------------------------------------------------------

def test_machine_section_names_cpu_cores_load_date_and_commit():
    before = results.snapshot(ROOT)
    after = results.snapshot(ROOT)
    assert before["cores"] == os.cpu_count() and before["cpu"]
    assert re.match(r"^[0-9a-f]{7,}( with uncommitted changes)?$", before["commit"]), before["commit"]
    lines = results.machine_section(before, after)
    for pat in MACHINE_LINES:
        assert any(re.match(pat, line) for line in lines), (pat, lines)


def test_commit_outside_a_repository_says_so(tmp_path):
    assert results.commit(tmp_path).startswith("unknown")
    (tmp_path / "COMMIT").write_text("0123456789abcdef0123\n")
    assert results.commit(tmp_path) == "0123456789ab (exported tree)"


def _run_or_skip(capsys, argv) -> str:
    rc = cli.main(argv)
    out = capsys.readouterr()
    said = out.err + out.out
    if rc == 2 and "liblegsim" in said and ("not found" in said or "not built" in said):
        pytest.skip("liblegsim.so is not built (cmake --build build/host, or set LEGSIM_LIB_DIR)")
    assert rc == 0, out.out + out.err
    return out.out


@pytest.mark.parametrize("argv, produced", [
    (["stress", "--quick", "--n-steps", "500", "--seeds", "1", "--segments", "3"], "stress_quick.md"),
    (["options", "--quick", "--reps", "3"], "options_quick.md"),
    (["workprecision", "--quick", "--no-peers", "--no-callgrind", "--scenes", "upper_step_50N",
      "--step-sizes", "1e-2", "--target-s", "0.01", "--min-reps", "1", "--max-reps", "1"],
     "workprecision_quick.md"),
])
def test_each_benchmark_result_carries_the_machine_section(capsys, tmp_path, argv, produced):
    out = _run_or_skip(capsys, [*argv, "-o", str(tmp_path)])
    assert str(tmp_path / produced) in out
    text = (tmp_path / produced).read_text().splitlines()
    for pat in MACHINE_LINES:
        assert sum(bool(re.match(pat, line)) for line in text) == 1, (pat, produced)


def test_mcu_report_carries_the_machine_section():
    # the QEMU run needs arm-none-eabi and qemu-system-arm: the report is checked on a row
    from legsim_bench.benchmarks import mcu_cost
    row = dict(preset="cortex-m4f", board="mps2-an386", image="leg_m4f.elf", exit=0, text=30000,
               data=2928, bss=8592, sim="7512", stack="2112 of 3072", insns={"rk4": 60221},
               worst=7.6e-7, worst_key="step rk4 q 2", compared=78, tol=1e-4, ok=True)
    text = mcu_cost.report([row], results.snapshot(ROOT), results.snapshot(ROOT)).splitlines()
    for pat in MACHINE_LINES:
        assert sum(bool(re.match(pat, line)) for line in text) == 1, pat
    line = next(l for l in text if l.startswith("| `leg_m4f.elf`"))
    assert "| 32,928 | 11,520 |" in line and "| 60,221 | ? |" in line and line.endswith("| yes |")
