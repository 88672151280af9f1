"""What each scene option costs: time per step with each disable flag, and firmware size.

    legsim-bench options [--quick] [--no-firmware] [--out DIR | --update-results]
    python -m legsim_bench.benchmarks.options_cost [--quick] [--no-firmware] [--out DIR]   (from bench/)

1. Run-time switches (``legsim_options.disable``, legsim.h): for each
   integrator and build (double, float), the time per step of the same scene
   with nothing disabled, with each flag on its own, and with all of them
   together. The scene: the stand pose, gravity, 50 N on the upper actuator,
   0 N on the lower, 50 N up on the foot (the model's force element
   ``foot_load``), h = 1 ms, 100 steps from a fresh sim per repetition (one
   ``legsim_step`` call timed with ``perf_counter_ns``); repetitions are
   interleaved over the flag sets, median and quartiles. Turning a flag on
   changes the physics (no gravity, no actuator force...), hence possibly the
   Newton iteration counts: the mean iterations per step are reported too.

2. Compile-time switches: the firmware of the ``cortex-m4f`` preset
   (CMakePresets.json, arm-none-eabi, float) configured into temporary
   directories with each ``LEGSIM_WITH_*`` off in turn, and
   ``arm-none-eabi-size`` of the firmware image (firmware_core/mcu,
   ``leg_m4f.elf``, linked with --gc-sections) and of the core library
   (``liblegsim_core.a``, the sum over its objects). Without the preset, the
   static library is built with the toolchain file directly.

Outputs: options.md and options.csv in ``--out`` (default out/bench-results/;
``--update-results``: the committed bench/results/; ``--quick`` writes
options_quick.*).
"""
from __future__ import annotations

import argparse
import csv
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import legsim

from . import core as lc
from . import results
from .workprecision import describe_source

REPO_ROOT = lc.REPO_ROOT
FLAGS = tuple(legsim.DISABLE)  # legsim.h's enum legsim_disable
SWITCHES = ("LEGSIM_WITH_GENERALIZED_ALPHA", "LEGSIM_WITH_RK4", "LEGSIM_WITH_STATICS",
            "LEGSIM_WITH_INVERSE_DYNAMICS", "LEGSIM_WITH_FORCE_ELEMENTS")
H = 1e-3
N_STEPS = 100
FOOT_LOAD = (0.0, 50.0)


# ---------------------------------------------------------------- run time
def scene_core(precision, integrator, disable):
    c = legsim.Sim(precision=precision, integrator=integrator, step=H, disable=disable)
    c.assemble_pose("stand")
    c.command_force(0, 50.0)
    c.command_force(1, 0.0)
    c.set_force(0, FOOT_LOAD)
    return c


def flag_sets():
    sets = [("none", ())] + [(f, (f,)) for f in FLAGS] + [("all", FLAGS)]
    return sets


def time_flags(precisions, integrators, reps, log) -> list:
    rows = []
    cases = [(p, i, name, fl) for p in precisions for i in integrators for name, fl in flag_sets()]
    samples = {k: [] for k in range(len(cases))}
    iters = {}
    status = {}
    for r in range(reps):
        for k, (prec, integ, name, fl) in enumerate(cases):
            c = scene_core(prec, integ, fl)
            try:
                samples[k].append(lc.timed_step(c, N_STEPS) * 1e-9 / N_STEPS)
                status[k] = "ok"
            except legsim.LegsimError as e:
                status[k] = e.status_name
            if r == 0:
                # iterations per step (a separate, untimed run)
                c2 = scene_core(prec, integ, fl)
                its = []
                for _ in range(N_STEPS):
                    if lc.step_status(c2, 1) != legsim.Status.OK:
                        break
                    its.append(c2.report().iterations)
                iters[k] = float(np.mean(its)) if its else float("nan")
        if r in (0, reps - 1):
            log(f"  round {r + 1}/{reps}")
    for k, (prec, integ, name, fl) in enumerate(cases):
        s = samples[k]
        rows.append({"precision": prec, "integrator": integ, "disabled": name,
                     "status": status.get(k, "?"),
                     "us_median": 1e6 * float(np.median(s)) if s else float("nan"),
                     "us_p25": 1e6 * float(np.percentile(s, 25)) if s else float("nan"),
                     "us_p75": 1e6 * float(np.percentile(s, 75)) if s else float("nan"),
                     "us_min": 1e6 * float(np.min(s)) if s else float("nan"),
                     "iters": iters.get(k, float("nan")), "reps": len(s)})
    for row in rows:
        base = next(x for x in rows if x["precision"] == row["precision"]
                    and x["integrator"] == row["integrator"] and x["disabled"] == "none")
        row["saved_us"] = base["us_median"] - row["us_median"]
        row["saved_pct"] = 100.0 * row["saved_us"] / base["us_median"]
    return rows


# ---------------------------------------------------------------- firmware size
def _size_tool() -> str | None:
    return shutil.which("arm-none-eabi-size")


def parse_size(out: str) -> dict:
    """Sum of text/data/bss over the lines of `size` (Berkeley format)."""
    tot = {"text": 0, "data": 0, "bss": 0}
    for line in out.splitlines():
        m = re.match(r"\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+[0-9a-f]+\s+(.*)$", line)
        if m:
            tot["text"] += int(m.group(1))
            tot["data"] += int(m.group(2))
            tot["bss"] += int(m.group(3))
    return tot


def build_firmware(switch_off: str | None, log, keep: bool = False, source=REPO_ROOT) -> dict:
    """Configure and build the cortex-m4f preset with one switch off; sizes."""
    source = Path(source)
    size = _size_tool()
    d = Path(tempfile.mkdtemp(prefix="legsim-m4f-"))
    args = [f"-D{switch_off}=OFF"] if switch_off else []
    presets = (source / "CMakePresets.json").is_file() and \
        "cortex-m4f" in (source / "CMakePresets.json").read_text()
    row = {"switch_off": switch_off or "(none: all on)", "how": "", "status": "ok"}
    try:
        if presets:
            # without link-time optimization: an LTO archive's objects hold no machine code
            # to size (the library's .text would read 0)
            cfg = ["cmake", "--preset", "cortex-m4f", "-B", str(d),
                   "-DCMAKE_INTERPROCEDURAL_OPTIMIZATION=OFF"] + args
            row["how"] = "cmake --preset cortex-m4f -DCMAKE_INTERPROCEDURAL_OPTIMIZATION=OFF"
        else:
            tc = source / "cmake" / "toolchains" / "arm-none-eabi-cortex-m4f.cmake"
            cfg = ["cmake", "-S", str(source), "-B", str(d), "-G", "Ninja",
                   f"-DCMAKE_TOOLCHAIN_FILE={tc}", "-DCMAKE_BUILD_TYPE=Release",
                   "-DLEGSIM_USE_FLOAT=ON", "-DLEGSIM_BUILD_HOST=OFF"] + args
            row["how"] = "toolchain file"
        r = subprocess.run(cfg, cwd=source, capture_output=True, text=True)
        if r.returncode != 0:
            row["status"] = "configure failed: " + (r.stderr.strip().splitlines() or ["?"])[-1]
            return row
        r = subprocess.run(["cmake", "--build", str(d), "-j2"], capture_output=True, text=True)
        if r.returncode != 0:
            # the image may not build without a feature it uses: the library alone then
            row["status"] = "image build failed: " + (
                [l for l in r.stdout.splitlines() if "error" in l.lower()] or ["?"])[0][:160]
            r2 = subprocess.run(["cmake", "--build", str(d), "-j2", "--target", "legsim_core"],
                                capture_output=True, text=True)
            if r2.returncode != 0:
                row["status"] += "; library build failed too"
                return row
        lib = d / "firmware_core" / "liblegsim_core.a"
        if size and lib.is_file():
            s = parse_size(subprocess.run([size, str(lib)], capture_output=True, text=True).stdout)
            row.update({f"lib_{k}": v for k, v in s.items()})
        imgs = sorted((d / "firmware_core" / "mcu").glob("*.elf")) if (d / "firmware_core" / "mcu").is_dir() else []
        if size and imgs:
            s = parse_size(subprocess.run([size, str(imgs[0])], capture_output=True, text=True).stdout)
            row.update({f"img_{k}": v for k, v in s.items()})
            row["image"] = imgs[0].name
        log(f"  {row['switch_off']}: lib text {row.get('lib_text', '?')}, image text "
            f"{row.get('img_text', '?')} ({row['status']})")
        return row
    finally:
        if not keep:
            shutil.rmtree(d, ignore_errors=True)


def firmware_sizes(log, switches=SWITCHES, source=REPO_ROOT) -> list:
    if not shutil.which("arm-none-eabi-gcc") or not _size_tool():
        log("  arm-none-eabi-gcc / arm-none-eabi-size not found: firmware sizes skipped")
        return []
    rows = [build_firmware(None, log, source=source)]
    for s in switches:
        rows.append(build_firmware(s, log, source=source))
    base = rows[0]
    for r in rows:
        for pre in ("lib", "img"):
            if f"{pre}_text" in r and f"{pre}_text" in base:
                r[f"{pre}_text_saved"] = base[f"{pre}_text"] - r[f"{pre}_text"]
    return rows


# ---------------------------------------------------------------- output
def write_outputs(out: Path, stem: str, rows, fw, info, reps, elapsed, source="",
                  info_end=None) -> None:
    with open(out / f"{stem}.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["kind", "precision", "integrator", "disabled_or_switch_off", "status",
                    "us_per_step_median", "us_p25", "us_p75", "us_min", "saved_us", "saved_pct",
                    "newton_iters_per_step", "reps", "lib_text", "lib_data", "lib_bss",
                    "img_text", "img_data", "img_bss"])
        for r in rows:
            w.writerow(["runtime", r["precision"], r["integrator"], r["disabled"], r["status"],
                        f"{r['us_median']:.4f}", f"{r['us_p25']:.4f}", f"{r['us_p75']:.4f}",
                        f"{r['us_min']:.4f}", f"{r['saved_us']:.4f}", f"{r['saved_pct']:.2f}",
                        f"{r['iters']:.3f}", r["reps"], "", "", "", "", "", ""])
        for r in fw:
            w.writerow(["firmware", "float", "", r["switch_off"], r["status"], "", "", "", "", "",
                        "", "", "", r.get("lib_text", ""), r.get("lib_data", ""),
                        r.get("lib_bss", ""), r.get("img_text", ""), r.get("img_data", ""),
                        r.get("img_bss", "")])
    L = []
    a = L.append
    a("# Skip what a scene does not need: cost of each option")
    a("")
    a(f"Generated by `legsim-bench options` (bench/legsim_bench/benchmarks/options_cost.py) in {elapsed:.0f} s.")
    a("")
    L.extend(results.machine_section(info, info_end))
    a("## Run-time disable flags (legsim_options.disable)")
    a("")
    a(f"Scene: stand pose, gravity, upper actuator 50 N, lower 0 N, foot load {FOOT_LOAD} N, "
      f"h = {H:g} s, {N_STEPS} steps per timed `legsim_step` call, fresh sim each time, {reps} "
      "repetitions interleaved over the flag sets; microseconds per step, median [p25, p75]. "
      "'saved' is relative to nothing disabled in the same build and integrator. A flag "
      "changes the physics too (e.g. no gravity: the leg barely moves), so the Newton "
      "iterations per step are shown: part of a saving can come from fewer iterations rather "
      "than skipped work. (For RK4 the report's iterations are those of its last position "
      "projection, which runs only when the residual exceeds newton_tol.) legsim.h has no "
      "flag for velocity or acceleration outputs: qd is the state, and both integrators need "
      "qdd (an earlier LEGSIM_DISABLE_ACCELERATIONS skipped no work and was dropped from the "
      "core).")
    a("")
    for prec in dict.fromkeys(r["precision"] for r in rows):
        for integ in dict.fromkeys(r["integrator"] for r in rows):
            sub = [r for r in rows if r["precision"] == prec and r["integrator"] == integ]
            if not sub:
                continue
            a(f"### {lc.INTEGRATOR_LABEL[integ]}, {prec}")
            a("")
            a("| disabled | us per step | [p25, p75] | saved (us) | saved (%) | Newton iterations per step | status |")
            a("|---|---|---|---|---|---|---|")
            for r in sub:
                a(f"| {r['disabled']} | {r['us_median']:.3f} | [{r['us_p25']:.3f}, {r['us_p75']:.3f}] | "
                  f"{r['saved_us']:+.3f} | {r['saved_pct']:+.1f} | {r['iters']:.2f} | {r['status']} |")
            a("")
    a("## Compile-time switches: firmware size (cortex-m4f, float, arm-none-eabi, bytes)")
    a("")
    if not fw:
        a("Not measured: no arm-none-eabi toolchain here (or `--no-firmware`).")
    else:
        a(f"Built with `{fw[0]['how']} -B <tmp> -D<switch>=OFF`; `arm-none-eabi-size` of the "
          "core library `liblegsim_core.a` (sum over its objects: all the code the switch "
          "strips) and of the firmware image `leg_m4f.elf` (linked with --gc-sections: only "
          "what the image's program reaches, so a switch for a function the image does not "
          f"call saves nothing there). Source: {source}.")
        a("")
        a("| switch off | library .text | .data | .bss | .text saved | image .text | .data | .bss | image .text saved | status |")
        a("|---|---|---|---|---|---|---|---|---|---|")
        for r in fw:
            a(f"| {r['switch_off']} | {r.get('lib_text', '—')} | {r.get('lib_data', '—')} | "
              f"{r.get('lib_bss', '—')} | {r.get('lib_text_saved', '—')} | {r.get('img_text', '—')} | "
              f"{r.get('img_data', '—')} | {r.get('img_bss', '—')} | {r.get('img_text_saved', '—')} | "
              f"{r['status']} |")
    a("")
    (out / f"{stem}.md").write_text("\n".join(L) + "\n")


def _describe(src) -> str:
    return describe_source(Path(src))


def configure_parser(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.description = __doc__.split("\n\n")[0]
    p.add_argument("--quick", action="store_true", help="few repetitions, no firmware builds")
    p.add_argument("--no-firmware", action="store_true", help="skip the cortex-m4f size builds")
    p.add_argument("--reps", type=int, default=None, help="timing repetitions (default 301, quick 31)")
    p.add_argument("--source", default=str(REPO_ROOT),
                   help="source tree for the firmware builds (default: this repository)")
    results.add_output_options(p)
    return p


def run(args) -> int:
    t0 = time.time()
    quick = bool(args.quick)
    reps = args.reps or (31 if quick else 301)
    out = results.output_dir(args)
    out.mkdir(parents=True, exist_ok=True)

    def log(s):
        print(s, flush=True)

    if lc.library_missing("double"):
        return 2
    precs = [p for p in ("double", "float") if legsim.library_available(p)]
    info = results.snapshot()
    log(f"# run-time flags ({reps} repetitions)")
    rows = time_flags(precs, ("rk4", "galpha"), reps, log)
    for r in rows:
        log(f"  {r['precision']:6s} {r['integrator']:6s} {r['disabled']:15s} "
            f"{r['us_median']:7.3f} us/step  saved {r['saved_pct']:+6.1f} %  iters {r['iters']:.2f}")
    fw = []
    if not (quick or args.no_firmware):
        log("# firmware sizes (cortex-m4f)")
        fw = firmware_sizes(log, source=args.source)
    write_outputs(out, "options_quick" if quick else "options", rows, fw, info, reps,
                  time.time() - t0, source=_describe(args.source), info_end=results.snapshot())
    log(f"# wrote {out / ('options_quick' if quick else 'options')}.md/.csv")
    return 0


def main(argv=None) -> int:
    p = configure_parser(argparse.ArgumentParser(prog="legsim-bench options"))
    return run(p.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
