"""MCU cost: builds the Cortex-M4F (float) and Cortex-M7 (double) firmware images of
the leg, and the Cortex-M7 image of the two-leg robot, with their CMake presets, runs each on QEMU's MPS2 board with -icount shift=0
(virtual time = instructions), and writes mcu.md: flash and RAM
bytes, instructions per step of each integrator, and the largest difference of
every printed value from the host build of the same program (legsim_leg_report_host or
legsim_robot_report_host, built by the host preset) within float or double tolerance;
then the Cortex-M4F image once more for each build choice of CHOICES (link-time
optimization, optimization levels of all or of the per-step files), so the preset's
choice stands beside what it was chosen against.

    legsim-bench mcu [--out DIR | --update-results] [--build-root build] [--no-choices]

Every build goes to <build-root>/<preset> (the host twin to <build-root>/host, the
choices to <build-root>/cortex-m4f-<n>).

mcu.md goes to out/bench-results/ by default; --update-results replaces the committed
bench/results/mcu.md.
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from pathlib import Path

from . import results

TARGETS = [  # preset, board, image, tolerance against the host (its real type), host twin
    ("cortex-m4f", "mps2-an386", "leg_m4f.elf", 1e-4, "legsim_leg_report_host"),
    ("cortex-m7", "mps2-an500", "leg_m7.elf", 1e-9, "legsim_leg_report_host"),
    ("cortex-m7-robot", "mps2-an500", "robot_m7.elf", 1e-6, "legsim_robot_report_host"),
]
# The M4F image's build choices (cache variables on top of the cortex-m4f preset).
_HOT = "legsim_kernels.cpp;src/system/linear_solve.cpp;src/system/step.cpp;src/system/guard.cpp;src/system/dynamics.cpp;" \
       "src/system/integrator_rk4.cpp;src/system/integrator_generalized_alpha.cpp;src/api/common.cpp;src/api/model.cpp;" \
       "src/api/state.cpp;src/api/step.cpp;src/api/analyses.cpp"
CHOICES = [  # name, cache variables
    ("preset (-Os, LTO; -O2 for the API, the dynamics solve and the integrators)", {}),
    ("-Os everywhere, LTO", {"LEGSIM_MCU_HOT_SOURCES": ""}),
    ("-Os, no LTO", {"CMAKE_INTERPROCEDURAL_OPTIMIZATION": "OFF"}),
    ("-O2, LTO", {"CMAKE_C_FLAGS_RELEASE": "-O2 -DNDEBUG", "CMAKE_CXX_FLAGS_RELEASE": "-O2 -DNDEBUG"}),
    ("-O2, no LTO", {"CMAKE_C_FLAGS_RELEASE": "-O2 -DNDEBUG", "CMAKE_CXX_FLAGS_RELEASE": "-O2 -DNDEBUG",
                     "CMAKE_INTERPROCEDURAL_OPTIMIZATION": "OFF"}),
    ("-Os, LTO, kernels and linear solves -O2 too", {"LEGSIM_MCU_HOT_SOURCES": _HOT}),
    ("-Os, LTO, kernels off", {"LEGSIM_KERNELS": "OFF"}),
]
NUMBER = re.compile(r"^-?\d+(\.\d+)?(e[-+]?\d+)?$", re.I)


def _root() -> Path:
    env = os.environ.get("LEGSIM_ROOT")
    if env:
        return Path(env)
    for p in [Path.cwd(), *Path.cwd().parents, *Path(__file__).resolve().parents]:
        if (p / "models" / "leg.toml").is_file() and (p / "CMakePresets.json").is_file():
            return p
    sys.exit("mcu: cannot find the legsim repository (set LEGSIM_ROOT)")


def _run(cmd, cwd, **kw):
    r = subprocess.run(cmd, cwd=cwd, text=True, capture_output=True, **kw)
    if r.returncode != 0:
        sys.exit(f"mcu: {' '.join(map(str, cmd))} failed ({r.returncode}):\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
    return r


def _values(text: str) -> dict[str, list[float]]:
    """The report's numeric lines, keyed by their leading words (stand/step lines only)."""
    out = {}
    for line in text.splitlines():
        f = line.split()
        if not f or f[0] not in ("stand", "step") or "insns" in line:
            continue
        words = [w for w in f if not NUMBER.match(w)]
        nums = [float(w) for w in f if NUMBER.match(w)]
        if f[1] == "q" or (len(f) > 2 and f[2] == "q"):  # body index is part of the key
            idx = 2 if f[1] == "q" else 3
            words.append(f[idx])
            nums = [float(w) for w in f[idx + 1:]]
        out[" ".join(words)] = nums
    return out


def _field(text: str, *words: str) -> list[str]:
    for line in text.splitlines():
        f = line.split()
        if f[: len(words)] == list(words):
            return f
    return []


def configure_parser(p: argparse.ArgumentParser) -> None:
    results.add_output_options(p)
    p.add_argument("--build-root", default=None, help="where the presets build (default build/)")
    p.add_argument("--no-choices", action="store_true",
                   help="skip the table of the Cortex-M4F image's build choices")


def run(args) -> int:
    root = _root()
    out = results.output_dir(args, root)
    before = results.snapshot(root)
    build_root = Path(args.build_root) if args.build_root else root / "build"
    twins: dict[str, dict[str, list[float]]] = {}

    def host_values(twin: str) -> dict[str, list[float]]:
        if twin not in twins:
            hdir = build_root / "host"
            exe = hdir / "tests" / "mcu" / twin
            print(f"mcu: building the host twin {twin}", flush=True)
            # this Python (the bench's: cantools, pytest) for the build's generators and tests
            _run(["cmake", "--preset", "host", "-B", str(hdir), f"-DPython3_EXECUTABLE={sys.executable}"],
                 root)
            _run(["cmake", "--build", str(hdir), "--target", twin], root)
            twins[twin] = _values(_run([str(exe)], root).stdout)
        return twins[twin]

    rows = []
    for preset, board, image, tol, twin in TARGETS:
        rows.append(measure(root, build_root / preset, preset, board, image, tol, host_values(twin)))
    choices = []
    if not args.no_choices:
        preset, board, image, tol, twin = TARGETS[0]
        for n, (name, cache) in enumerate(CHOICES):
            r = measure(root, build_root / f"{preset}-{n}", preset, board, image, tol,
                        host_values(twin), cache)
            r["choice"], r["cache"] = name, cache
            choices.append(r)
    out.mkdir(parents=True, exist_ok=True)
    text = report(rows, before, results.snapshot(root), choices)
    (out / "mcu.md").write_text(text)
    print(text)
    return 0 if all(r["ok"] for r in rows + choices) else 1


def measure(root: Path, bdir: Path, preset: str, board: str, image: str, tol: float,
            host: dict[str, list[float]], cache: dict[str, str] | None = None) -> dict:
    """Configure bdir from preset (a build choice: afresh, with its cache variables), build,
    size the image and run it on QEMU; compare its values with the host twin's."""
    defs = [f"-D{k}={v}" for k, v in (cache or {}).items()]
    print(f"mcu: building {preset} in {bdir} {' '.join(defs)}", flush=True)
    if cache is not None and bdir.exists():  # a choice: configured from scratch
        _run(["cmake", "-E", "rm", "-rf", str(bdir)], root)
    _run(["cmake", "--preset", preset, "-B", str(bdir), *defs], root)
    _run(["cmake", "--build", str(bdir)], root)
    elf = bdir / "firmware_core" / "mcu" / image
    size = _run(["arm-none-eabi-size", str(elf)], root).stdout.splitlines()[1].split()
    text_b, data_b, bss_b = (int(x) for x in size[:3])
    print(f"mcu: running {image} on {board}", flush=True)
    qemu = subprocess.run(
        ["qemu-system-arm", "-M", board, "-nographic", "-monitor", "none", "-serial", "none",
         "-semihosting-config", "enable=on,target=native", "-icount", "shift=0",
         "-kernel", str(elf)], cwd=root, text=True, capture_output=True, timeout=300)
    printed = qemu.stdout + qemu.stderr  # semihosting writes to QEMU's stderr
    got = _values(printed)
    worst, worst_key, compared = 0.0, "", 0
    for key, vals in host.items():
        if key not in got:
            continue
        for a, b in zip(vals, got[key]):
            compared += 1
            if abs(a - b) > worst:
                worst, worst_key = abs(a - b), key
    insns = {f[1]: int(f[4]) for f in (_field(printed, "step", i, "insns_per_step")
                                      for i in ("rk4", "generalized_alpha")) if f}
    sim = _field(printed, "sim_size")
    stack = _field(printed, "stack", "used")
    return dict(preset=preset, board=board, image=image, exit=qemu.returncode,
                text=text_b, data=data_b, bss=bss_b, sim=sim[1] if sim else "?",
                stack=f"{stack[2]} of {stack[4]}" if stack else "?", insns=insns,
                worst=worst, worst_key=worst_key, compared=compared, tol=tol,
                ok=qemu.returncode == 0 and compared > 0 and worst <= tol)


def _count(x) -> str:
    return f"{x:,}" if isinstance(x, int) else str(x)


def report(rows: list[dict], before: dict, after: dict, choices: list[dict] | None = None) -> str:
    """mcu.md: the machine section (results.machine_section), one row per image, and one
    row per build choice of the Cortex-M4F image."""
    lines = [
        "# MCU cost: the leg and the two-leg robot on Cortex-M under QEMU",
        "",
        "Generated by `legsim-bench mcu` (bench/legsim_bench/benchmarks/mcu_cost.py): "
        "GCC arm-none-eabi with the presets' flags (-Os, and -O2 for the API, the dynamics solve and "
        "the integrators: LEGSIM_MCU_HOT_SOURCES; the cortex-m4f preset also with link-time "
        "optimization), QEMU `-icount shift=0` (1 ns of virtual time per instruction; "
        "the images read a 25 MHz timer around each step: 40-instruction resolution). "
        "Instructions, not cycles.",
        "",
        *results.machine_section(before, after),
        "## Images",
        "",
        "| image | board | exit | flash (.text + .data) | RAM (.data + .bss) | sim size | stack used | "
        "RK4 instructions/step | generalized-alpha instructions/step | max difference from host "
        "(values compared) | tolerance | same results |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| `{r['image']}` | {r['board']} | {r['exit']} | {r['text'] + r['data']:,} | "
            f"{r['data'] + r['bss']:,} | {r['sim']} | {r['stack']} | "
            f"{_count(r['insns'].get('rk4', '?'))} | {_count(r['insns'].get('generalized_alpha', '?'))} | "
            f"{r['worst']:.2e} ({r['compared']}; worst: {r['worst_key']}) | {r['tol']:g} | "
            f"{'yes' if r['ok'] else 'NO'} |")
    lines += ["", "RAM includes the sim's static storage and the fixed stack (firmware_core/mcu/CMakeLists.txt); "
              "the targets for the Cortex-M4F image are 64 KB of flash and 16 KB of RAM, and (issue 8) no more "
              "flash or RAM than before the generated kernels (.text 38,136 B, RAM 11,520 B) with at most "
              "12,000 instructions per step. The robot's image runs "
              "the stand with both feet stuck, compared with the host to 1e-6 as tests/mcu/mcu_test.py does.", ""]
    if choices:
        lines += [
            "## Build choices of the Cortex-M4F image",
            "",
            "The cortex-m4f preset with other cache variables (CHOICES in mcu_cost.py; per-step files: "
            "LEGSIM_MCU_HOT_SOURCES, firmware_core/mcu/CMakeLists.txt). The toolchain's -fno-math-errno "
            "and -fconserve-stack are in every row.",
            "",
            "| choice | cache variables | flash (.text + .data) | RAM (.data + .bss) | stack used | "
            "RK4 instructions/step | generalized-alpha instructions/step | same results |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in choices:
            cache = ", ".join(f"`{k}={v}`" for k, v in r["cache"].items()) or "(none)"
            lines.append(
                f"| {r['choice']} | {cache} | {r['text'] + r['data']:,} | {r['data'] + r['bss']:,} | "
                f"{r['stack']} | {_count(r['insns'].get('rk4', '?'))} | "
                f"{_count(r['insns'].get('generalized_alpha', '?'))} | {'yes' if r['ok'] else 'NO'} |")
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="legsim-bench mcu", description=__doc__)
    configure_parser(ap)
    sys.exit(run(ap.parse_args()))
