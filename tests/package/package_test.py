#!/usr/bin/env python3
"""The core as an installed package, used as a user would (tests/package/CMakeLists.txt).

    package_test.py install   --cmake CMAKE --build BUILD_DIR --prefix PREFIX --libdir lib --nm NM
                              [--fresh DIR ...] [--runtime --version X.Y.Z --readelf READELF
                              --programs legsim_cli [hil_sim]]
    package_test.py readme    --readme README.md --consumer tests/package/consumer
    package_test.py pkgconfig --readme README.md --consumer DIR --prefix PREFIX --libdir lib --work DIR
    package_test.py cross     --cmake CMAKE --build CROSS_BUILD_DIR --source SOURCE_DIR
                              --readme README.md --consumer DIR --work DIR

install    `cmake --install BUILD_DIR --prefix PREFIX` into a fresh PREFIX, then checks that
           the installed headers are plain C (they include only each other, stddef.h and
           stdint.h: no Eigen, no C++ header) and that the static libraries need nothing
           from the C++ runtime (their undefined symbols, less those they define).
           --fresh: consumer build directories to remove with the old PREFIX.
           --runtime (a host build): the shared libraries are versioned (liblegsim.so.X.Y.Z,
           SONAME liblegsim.so.X.Y), the programs, models, scenes and DBC are installed,
           and the installed legsim_cli runs an installed robot scene.
readme     the C and CMake blocks of the README's "## Using the core" are the consumer's
           main.c and CMakeLists.txt, byte for byte (the test compiles what the README shows).
pkgconfig  runs the README's `cc ... $(pkg-config --cflags --libs legsim)` line in a fresh
           WORK directory holding main.c, with PKG_CONFIG_PATH=PREFIX/LIBDIR/pkgconfig, then
           runs the program (which checks its own results and exits non-zero if they are wrong).
cross      installs a cross build (a cortex-m4f or cortex-m7 preset) into WORK/sysroot/usr,
           builds the consumer for the target against it, once with CMake (the preset's
           toolchain file, CMAKE_FIND_ROOT_PATH=WORK/sysroot) and once with the README's
           pkg-config line (the cross compiler for cc), and runs both on the build's QEMU
           board (semihosting; cross/qemu_reset.c starts newlib's crt0). Exits 77 (skip)
           without arm-none-eabi-gcc or qemu-system-arm, as the MCU tests do.
Python 3.11+, standard library only. Exits non-zero with a message on failure.
"""
from __future__ import annotations

import argparse
import difflib
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

SECTION = "## Using the core"
HEADERS_ALLOWED = {"stddef.h", "stdint.h", "legsim/legsim.h", "legsim/config.h", "legsim/models.h",
                   "legsim/robot_models.h", "legsim/version.h"}
# Undefined symbols that only the C++ runtime (libstdc++/libsupc++, the unwinder) provides.
CXX_RUNTIME = re.compile(r"^(_Z|__cxa_|__gxx_|_Unwind_|__dynamic_cast)")
PKG_CONFIG_LINE = re.compile(r"^cc .*\$\(pkg-config --cflags --libs legsim\).*$", re.M)


def fail(msg: str) -> None:
    print(f"FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def run(cmd: list[str], **kw) -> subprocess.CompletedProcess:
    print("+", " ".join(cmd), flush=True)
    return subprocess.run(cmd, **kw)


# ---- install ----------------------------------------------------------------
def symbols(nm: str, lib: Path, *flags: str) -> set[str]:
    out = subprocess.run([nm, "-g", *flags, str(lib)], capture_output=True, text=True, check=True)
    # "<addr> T name", "         U name"; member headers "file.o:" and blank lines skipped
    return {line.split()[-1] for line in out.stdout.splitlines() if line and not line.endswith(":")}


def cmd_install(a: argparse.Namespace) -> None:
    prefix = Path(a.prefix)
    for old in [prefix, *map(Path, a.fresh)]:
        shutil.rmtree(old, ignore_errors=True)
    if run([a.cmake, "--install", a.build, "--prefix", str(prefix)]).returncode != 0:
        fail(f"cmake --install {a.build} failed (is the build complete? cmake --build {a.build})")

    headers = sorted(prefix.glob("include/legsim/*.h"))
    names = {h.name for h in headers}
    if not {"legsim.h", "config.h", "models.h"} <= names:
        fail(f"installed headers {sorted(names)}: expected legsim.h, config.h and models.h")
    for h in headers:
        for inc in re.findall(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', h.read_text(), re.M):
            if inc not in HEADERS_ALLOWED:
                fail(f"{h} includes {inc}: the installed headers must be plain C, "
                     f"self-contained (allowed: {sorted(HEADERS_ALLOWED)})")
    print(f"headers: {', '.join(sorted(names))}: plain C")

    libs = [prefix / a.libdir / f"liblegsim_{n}.a" for n in ("core", "models")]
    for lib in libs:
        if not lib.is_file():
            fail(f"{lib} not installed")
    defined = set().union(*(symbols(a.nm, lib, "--defined-only") for lib in libs))
    undefined = set().union(*(symbols(a.nm, lib, "-u") for lib in libs)) - defined
    cxx = sorted(s for s in undefined if CXX_RUNTIME.match(s))
    if cxx:
        fail("the static libraries need the C++ runtime, so a C program cannot link them "
             f"with cc and -lm alone: {', '.join(cxx)}")
    print(f"static libraries need from outside: {', '.join(sorted(undefined))} (no C++ runtime)")
    if a.runtime:
        check_runtime(a, prefix)


def soname(readelf: str, lib: Path) -> str:
    out = subprocess.run([readelf, "-d", str(lib)], capture_output=True, text=True, check=True)
    m = re.search(r"\(SONAME\).*\[(.+)\]", out.stdout)
    return m.group(1) if m else ""


def check_runtime(a: argparse.Namespace, prefix: Path) -> None:
    """The host's runtime part: versioned shared libraries, the programs, the data, and the
    installed CLI running an installed scene (no build or source tree on its paths)."""
    major, minor, _ = a.version.split(".")
    for name in ("legsim", "legsim_f32"):
        real = prefix / a.libdir / f"lib{name}.so.{a.version}"
        link = prefix / a.libdir / f"lib{name}.so"
        if not real.is_file() or not link.is_symlink():
            fail(f"expected {real} and the link {link} (VERSION/SOVERSION of {name})")
        want = f"lib{name}.so.{major}.{minor}"
        if soname(a.readelf, real) != want:
            fail(f"{real}: SONAME {soname(a.readelf, real)!r}, expected {want!r}")
    print(f"shared libraries: liblegsim.so.{a.version}, SONAME liblegsim.so.{major}.{minor}")
    for prog in a.programs:
        if not os.access(prefix / "bin" / prog, os.X_OK):
            fail(f"{prefix / 'bin' / prog} not installed")
    data = prefix / "share" / "legsim"
    for f in ("models/leg.toml", "models/robot.toml", "scenes/robot_swing.toml",
              "scenes/models/robot_slope_slide.toml", "can/legsim.dbc"):
        if not (data / f).is_file():
            fail(f"{data / f} not installed")
    print(f"programs: {', '.join(a.programs)}; data: models, scenes, can/legsim.dbc")
    # the installed CLI on an installed robot scene (its model found relative to the scene)
    out = prefix / "robot_stand_statics.json"
    r = run([str(prefix / "bin" / "legsim_cli"), str(data / "scenes" / "robot_stand_statics.toml"),
             "--out", str(out)], cwd=prefix, capture_output=True, text=True)
    if r.returncode != 0 or not out.is_file():
        fail(f"installed legsim_cli on the installed robot_stand_statics.toml: exit "
             f"{r.returncode}\n{r.stdout}{r.stderr}")
    print("installed legsim_cli ran the installed scenes/robot_stand_statics.toml")


# ---- readme -------------------------------------------------------------------
def readme_section(readme: Path) -> str:
    text = readme.read_text()
    start = text.find(f"\n{SECTION}\n")
    if start < 0:
        fail(f"{readme}: no section '{SECTION}'")
    end = text.find("\n## ", start + 1)
    return text[start:end if end >= 0 else len(text)]


def fenced_blocks(section: str, lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```$", section, re.M | re.S)


def cmd_readme(a: argparse.Namespace) -> None:
    section = readme_section(Path(a.readme))
    for lang, name in (("c", "main.c"), ("cmake", "CMakeLists.txt")):
        blocks = fenced_blocks(section, lang)
        path = Path(a.consumer) / name
        want = path.read_text()
        if want not in blocks:
            shown = blocks[0] if blocks else ""
            diff = "".join(difflib.unified_diff(want.splitlines(True), shown.splitlines(True),
                                                str(path), f"README ```{lang} block"))
            fail(f"the README's '{SECTION}' shows no ```{lang} block equal to {path}; keep "
                 f"them the same (the test builds {path}):\n{diff}")
        print(f"README ```{lang} block == {path}")
    lines = PKG_CONFIG_LINE.findall(section)
    if len(lines) != 1:
        fail(f"the README's '{SECTION}' has {len(lines)} lines "
             "'cc ... $(pkg-config --cflags --libs legsim) ...': expected one")
    print(f"README pkg-config line: {lines[0]}")


# ---- pkgconfig ----------------------------------------------------------------------
def cmd_pkgconfig(a: argparse.Namespace) -> None:
    if not shutil.which("pkg-config"):
        fail("no pkg-config on PATH: install Debian's pkgconf (tools/setup.sh does)")
    lines = PKG_CONFIG_LINE.findall(readme_section(Path(a.readme)))
    if len(lines) != 1:
        fail(f"expected one pkg-config line in the README's '{SECTION}', found {len(lines)}")
    line = lines[0]
    exe = re.search(r"-o\s+(\S+)", line)
    if not exe:
        fail(f"the README's pkg-config line names no output (-o): {line}")

    work = Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    shutil.copy(Path(a.consumer) / "main.c", work / "main.c")
    env = dict(os.environ, PKG_CONFIG_PATH=str(Path(a.prefix) / a.libdir / "pkgconfig"))
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "legsim"], env=env,
                           capture_output=True, text=True)
    if flags.returncode != 0:
        fail(f"pkg-config --cflags --libs legsim: {flags.stderr.strip()}")
    print(f"pkg-config --cflags --libs legsim: {flags.stdout.strip()}")
    if run(["sh", "-c", line], cwd=work, env=env).returncode != 0:
        fail(f"the README's line did not build: {line}")
    rc = run([str(work / exe.group(1))], cwd=work).returncode
    if rc != 0:
        fail(f"{exe.group(1)} exited with {rc}")


# ---- cross ----------------------------------------------------------------------
SKIP = 77


def cache_value(build: Path, name: str) -> str:
    m = re.search(rf"^{name}:[A-Z]+=(.*)$", (build / "CMakeCache.txt").read_text(), re.M)
    if not m:
        fail(f"{build}/CMakeCache.txt has no {name}")
    return m.group(1)


def qemu_run(qemu: str, board: str, elf: Path) -> None:
    cmd = [qemu, "-M", board, "-nographic", "-monitor", "none", "-serial", "none",
           "-semihosting-config", "enable=on,target=native", "-kernel", str(elf)]
    try:
        rc = run(cmd, timeout=120).returncode
    except subprocess.TimeoutExpired:
        fail(f"{elf.name} did not finish on QEMU {board} within 120 s")
    if rc != 0:
        fail(f"{elf.name} on QEMU {board} exited with {rc}")


def cmd_cross(a: argparse.Namespace) -> None:
    build, work, consumer = Path(a.build), Path(a.work), Path(a.consumer)
    gcc, qemu = shutil.which("arm-none-eabi-gcc"), shutil.which("qemu-system-arm")
    if not gcc or not qemu:
        print("SKIP: needs arm-none-eabi-gcc and qemu-system-arm (tools/setup.sh installs them)")
        sys.exit(SKIP)
    manifest = dict(line.split("=", 1) for line in
                    (build / "legsim_mcu_manifest.txt").read_text().splitlines() if "=" in line)
    board, cpu = manifest["board"], manifest["cpu"]
    toolchain = Path(a.source) / "cmake" / "toolchains" / f"arm-none-eabi-{cpu}.cmake"
    cpu_flags = cache_value(build, "CMAKE_C_FLAGS")

    shutil.rmtree(work, ignore_errors=True)
    sysroot = work / "sysroot"
    if run([a.cmake, "--install", str(build), "--prefix", str(sysroot / "usr")]).returncode != 0:
        fail(f"cmake --install {build} --prefix {sysroot}/usr failed")
    reset = work / "qemu_reset.o"
    if run([gcc, *cpu_flags.split(), "-c", "-o", str(reset),
            str(Path(__file__).parent / "cross" / "qemu_reset.c")]).returncode != 0:
        fail("qemu_reset.c did not compile")
    # full newlib (its printf prints floats, nano's does not), semihosting I/O
    link = f"--specs=rdimon.specs -Wl,--section-start=.vectors=0 {reset}"

    # CMake: the consumer project as it stands, for the target, found in the sysroot.
    cmake_dir = work / "cmake"
    steps = [[a.cmake, "-S", str(consumer), "-B", str(cmake_dir), "-G", a.generator,
              f"-DCMAKE_TOOLCHAIN_FILE={toolchain}", f"-DCMAKE_FIND_ROOT_PATH={sysroot}",
              "-DCMAKE_BUILD_TYPE=Release",
              # set here, CMAKE_C_FLAGS replaces the toolchain's (the CPU and float ABI)
              f"-DCMAKE_C_FLAGS={cpu_flags} -Wall -Wextra -pedantic -Werror",
              f"-DCMAKE_EXE_LINKER_FLAGS={link}"],
             [a.cmake, "--build", str(cmake_dir)]]
    for step in steps:
        if run(step).returncode != 0:
            fail(f"the consumer did not build for {cpu} with CMake against {sysroot}")
    qemu_run(qemu, board, cmake_dir / "leg_app")

    # pkg-config: the README's line with the cross compiler for cc.
    lines = PKG_CONFIG_LINE.findall(readme_section(Path(a.readme)))
    if len(lines) != 1:
        fail(f"expected one pkg-config line in the README's '{SECTION}', found {len(lines)}")
    line = f"{gcc} {cpu_flags} {link} {lines[0][len('cc '):]}"
    exe = re.search(r"-o\s+(\S+)", lines[0])
    if not exe:
        fail(f"the README's pkg-config line names no output (-o): {lines[0]}")
    pc_dir = work / "pkgconfig"
    pc_dir.mkdir()
    shutil.copy(consumer / "main.c", pc_dir / "main.c")
    libdir = cache_value(build, "CMAKE_INSTALL_LIBDIR")
    env = dict(os.environ, PKG_CONFIG_LIBDIR=str(sysroot / "usr" / libdir / "pkgconfig"))
    env.pop("PKG_CONFIG_PATH", None)
    if run(["sh", "-c", line], cwd=pc_dir, env=env).returncode != 0:
        fail(f"the consumer did not build for {cpu} with pkg-config: {line}")
    qemu_run(qemu, board, pc_dir / exe.group(1))
    print(f"the consumer ran on QEMU {board} ({cpu}), built with CMake and with pkg-config")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    i = sub.add_parser("install")
    i.add_argument("--cmake", required=True)
    i.add_argument("--build", required=True)
    i.add_argument("--prefix", required=True)
    i.add_argument("--libdir", required=True, help="CMAKE_INSTALL_LIBDIR, relative")
    i.add_argument("--nm", required=True)
    i.add_argument("--fresh", nargs="*", default=[], help="directories to remove first")
    i.add_argument("--runtime", action="store_true",
                   help="a host build: also check the shared libraries, programs and data")
    i.add_argument("--version", default="", help="with --runtime: the project's version")
    i.add_argument("--readelf", default="readelf")
    i.add_argument("--programs", nargs="*", default=["legsim_cli"])
    r = sub.add_parser("readme")
    r.add_argument("--readme", required=True)
    r.add_argument("--consumer", required=True)
    c = sub.add_parser("pkgconfig")
    c.add_argument("--readme", required=True)
    c.add_argument("--consumer", required=True)
    c.add_argument("--prefix", required=True)
    c.add_argument("--libdir", required=True, help="CMAKE_INSTALL_LIBDIR, relative")
    c.add_argument("--work", required=True)
    x = sub.add_parser("cross")
    x.add_argument("--cmake", required=True)
    x.add_argument("--build", required=True, help="a cross build (tests/mcu/<preset>)")
    x.add_argument("--source", required=True, help="the project's source tree")
    x.add_argument("--readme", required=True)
    x.add_argument("--consumer", required=True)
    x.add_argument("--work", required=True)
    x.add_argument("--generator", default="Ninja")
    a = p.parse_args()
    {"install": cmd_install, "readme": cmd_readme, "pkgconfig": cmd_pkgconfig,
     "cross": cmd_cross}[a.cmd](a)


if __name__ == "__main__":
    main()
