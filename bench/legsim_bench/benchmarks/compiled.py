"""The compiled drivers of the work-precision benchmark: build, run, count instructions.

Every engine runs the leg from a small C program of this package (drivers/): legsim_wp.c
links the legsim library the Python API uses (liblegsim.so, compiled-in model
legsim_model_leg_revolute), mujoco_wp.c the mujoco wheel's own libmujoco.so.* and headers
(site-packages/mujoco/include, lib). Both are compiled at run time into a directory under
out/ with the system C compiler ($CC, else cc, -O2): no third-party source in the
repository. Both time one function, run_steps() (the steps, nothing else; set-up outside
it), take the minimum over repetitions, and callgrind counts the same function
(``--toggle-collect=run_steps``).
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DRIVERS = Path(__file__).resolve().parent / "drivers"
CFLAGS = ("-O2", "-std=c11")

# legsim_disable flags (legsim.h)
DISABLE_REACTIONS = 1 << 2
DISABLE_STROKE_LIMITS = 1 << 5


class DriverError(RuntimeError):
    pass


def cc() -> str:
    """The C compiler the drivers are built with."""
    return os.environ.get("CC", "cc")


def _compile(src: Path, exe: Path, includes, libs, rpaths) -> Path:
    exe.parent.mkdir(parents=True, exist_ok=True)
    cmd = [cc(), *CFLAGS, *(f"-I{i}" for i in includes), str(src), *map(str, libs),
           *(f"-Wl,-rpath,{r}" for r in rpaths), "-lm", "-o", str(exe)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise DriverError(f"cannot compile {src.name}: {' '.join(cmd)}\n{r.stderr}")
    return exe


def legsim_config_dir(lib: Path) -> Path:
    """The directory holding legsim/config.h for this library (a build tree or a prefix)."""
    d = lib.parent
    for base in (d / "generated", d / "firmware_core" / "generated", d.parent / "generated",
                 d.parent / "include", d.parent.parent / "include"):
        if (base / "legsim" / "config.h").is_file():
            return base
    raise DriverError(f"no legsim/config.h found beside {lib}")


def build_legsim(out: Path, repo_root: Path, lib: Path | None = None) -> Path:
    """legsim_wp linked against ``lib`` (default: the library the Python API loads)."""
    if lib is None:
        import legsim
        lib = legsim.find_library("double")
    lib = Path(lib).resolve()
    return _compile(DRIVERS / "legsim_wp.c", out / "legsim_wp",
                    [repo_root / "firmware_core" / "include", legsim_config_dir(lib)],
                    [lib], [lib.parent])


def mujoco_dir() -> Path:
    import mujoco
    return Path(mujoco.__file__).resolve().parent


def mujoco_library() -> Path | None:
    libs = sorted(mujoco_dir().glob("libmujoco.so*"))
    return libs[0] if libs else None


def build_mujoco(out: Path) -> Path:
    """mujoco_wp against the wheel's libmujoco.so.* and include/ (no other MuJoCo)."""
    d = mujoco_dir()
    lib = mujoco_library()
    if lib is None or not (d / "include" / "mujoco" / "mujoco.h").is_file():
        raise DriverError(f"the mujoco wheel at {d} has no libmujoco.so.* or include/mujoco/")
    return _compile(DRIVERS / "mujoco_wp.c", out / "mujoco_wp", [d / "include"], [lib], [d])


# ---------------------------------------------------------------- running
@dataclass
class Run:
    """One driver invocation: ``argv`` after the mode (see the drivers' usage)."""
    exe: Path
    args: tuple

    def _call(self, mode: str, x) -> str:
        r = subprocess.run([str(self.exe), mode, *map(str, self.args), str(x)],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise DriverError(r.stderr.strip() or f"{self.exe.name} exited {r.returncode}")
        return r.stdout

    def trajectory(self, sample_dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(t, x): the driver's samples at t = 0, sample_dt, ..., T (x: q or qpos rows)."""
        a = np.loadtxt(self._call("traj", repr(sample_dt)).splitlines(), ndmin=2)
        return a[:, 0], a[:, 1:]

    def wall(self, reps: int) -> tuple[float, float, int]:
        """(minimum, mean) wall seconds of the whole run over ``reps``, and its steps."""
        best, mean, n = self._call("time", int(reps)).split()
        return float(best), float(mean), int(n)

    def instructions(self, n_steps: int, out_file: Path) -> tuple[int, int]:
        """(instructions in run_steps, steps counted) by valgrind callgrind."""
        vg = shutil.which("valgrind")
        if vg is None:
            raise DriverError("valgrind is not installed (Debian package valgrind)")
        out_file.parent.mkdir(parents=True, exist_ok=True)
        cmd = [vg, "--tool=callgrind", "--toggle-collect=run_steps",
               f"--callgrind-out-file={out_file}", str(self.exe), "count", *map(str, self.args),
               str(int(n_steps))]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise DriverError(f"callgrind failed: {r.stderr.strip()[-500:]}")
        counted = int(r.stdout.split()[-1])
        return callgrind_total(out_file.read_text()), counted


def callgrind_total(text: str) -> int:
    """Instructions (Ir) of a callgrind output file: its 'summary:' (or 'totals:') line."""
    m = re.search(r"^summary:\s+(\d+)", text, re.M) or re.search(r"^totals:\s+(\d+)", text, re.M)
    if m is None:
        raise DriverError("no summary line in the callgrind output")
    return int(m.group(1))
