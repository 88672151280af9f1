#!/usr/bin/env python3
"""The project's version is the same everywhere it is written (tests/package: package_version).

    version_test.py --source SOURCE_DIR --build BUILD_DIR --readelf READELF

project(VERSION) of CMakeLists.txt is the source; these must agree with it:
  BUILD/generated_version/legsim/version.h  LEGSIM_VERSION_MAJOR/MINOR/PATCH and _STRING
  python/pyproject.toml                     [project] version
  python/legsim/__init__.py                 __version__
  CHANGELOG.md                              the first released section, "## [X.Y.Z]"
  BUILD/firmware_core/liblegsim.so          file liblegsim.so.X.Y.Z, SONAME liblegsim.so.X.Y
  can/legsim.dbc                            its general comment (CM_ "..."): "legsim X.Y.Z"
Exits non-zero naming each disagreement.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tomllib
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", required=True, type=Path)
    ap.add_argument("--build", required=True, type=Path)
    ap.add_argument("--readelf", default="readelf")
    a = ap.parse_args()
    src, build = a.source, a.build
    m = re.search(r"^project\(legsim\s+VERSION\s+(\d+)\.(\d+)\.(\d+)\b",
                  (src / "CMakeLists.txt").read_text(), re.M)
    if not m:
        sys.exit("FAIL: no project(legsim VERSION X.Y.Z) in CMakeLists.txt")
    major, minor, patch = m.groups()
    version = f"{major}.{minor}.{patch}"
    found: dict[str, str] = {}

    h = (build / "generated_version" / "legsim" / "version.h").read_text()
    macros = dict(re.findall(r"^#define (LEGSIM_VERSION_\w+) (\S+)$", h, re.M))
    found["legsim/version.h"] = (f"{macros.get('LEGSIM_VERSION_MAJOR')}."
                                 f"{macros.get('LEGSIM_VERSION_MINOR')}."
                                 f"{macros.get('LEGSIM_VERSION_PATCH')}")
    found["legsim/version.h LEGSIM_VERSION_STRING"] = macros.get(
        "LEGSIM_VERSION_STRING", "").strip('"')
    found["python/pyproject.toml"] = tomllib.loads(
        (src / "python" / "pyproject.toml").read_text())["project"]["version"]
    init = re.search(r'^__version__ = "([^"]+)"', (src / "python" / "legsim" / "__init__.py")
                     .read_text(), re.M)
    found["python/legsim/__init__.py"] = init.group(1) if init else "(none)"
    rel = re.search(r"^## \[(\d+\.\d+\.\d+)\]", (src / "CHANGELOG.md").read_text(), re.M)
    found["CHANGELOG.md"] = rel.group(1) if rel else "(no released section)"

    for name in ("legsim", "legsim_f32"):
        lib = build / "firmware_core" / f"lib{name}.so.{version}"
        if not lib.is_file():
            found[f"lib{name}.so file"] = "(no " + lib.name + ")"
            continue
        out = subprocess.run([a.readelf, "-d", str(lib)], capture_output=True, text=True,
                             check=True).stdout
        so = re.search(r"\(SONAME\).*\[lib\w+\.so\.(\d+\.\d+)\]", out)
        found[f"lib{name}.so SONAME"] = (so.group(1) + f".{patch}") if so else "(no SONAME)"

    dbc = (src / "can" / "legsim.dbc").read_text()
    general = re.search(r'^CM_ "(.*?)";', dbc, re.M | re.S)
    dbc_version = re.search(r"\blegsim (\d+\.\d+\.\d+)\b", general.group(1)) if general else None
    found["can/legsim.dbc comment"] = (dbc_version.group(1) if dbc_version
                                       else '(no "legsim X.Y.Z" in its general comment)')

    bad = {k: v for k, v in found.items() if v != version}
    for k, v in found.items():
        print(f"{k:45} {v}{'' if v == version else '   <- differs'}")
    if bad:
        sys.exit(f"FAIL: project(VERSION) is {version}; these differ: {', '.join(bad)}")
    print(f"all agree: {version}")


if __name__ == "__main__":
    main()
