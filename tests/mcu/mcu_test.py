#!/usr/bin/env python3
"""MCU tests driven by CTest (tests/mcu/CMakeLists.txt).

  build    configure + build a cross preset (cortex-m4f, cortex-m7) in a sub-build dir
  symbols  the libraries reference no heap function and the image defines none
  qemu     run the image on QEMU: exit 0, stand pose = known values = host twin

--manifest picks the image: legsim_mcu_manifest.txt (the leg's, default) or
legsim_mcu_robot_manifest.txt (the two-leg robot's, preset cortex-m7-robot);
qemu --facts leg|robot: the known values checked (the leg's stand pose, or the
robot's feet stuck on the ground line).

Exit 0: pass, 1: fail, 77: skipped (arm toolchain or QEMU not installed).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

SKIP = 77

# Known stand pose of models/leg.toml (thigh at 60 deg, shank vertical).
STAND_FACTS = {
    ("joint", "C_rod_thigh"): (0.4330127, -0.25),
    ("joint", "D"): (0.4330127, -0.45),
    ("foot",): (0.4330127, -0.85),
    ("phi", 0): 0.7137244,  # upper cylinder (phi1)
    ("phi", 2): 1.0471976,  # thigh (phi3)
    ("phi", 3): 0.7661626,  # lower cylinder (phi4)
}

# What no library object may reference and no image may contain: the heap, the
# C++ allocation operators, exception objects, and exit-handler registration
# (newlib's atexit list can allocate).
HEAP_NAMES = {
    "malloc", "free", "calloc", "realloc", "reallocarray", "memalign", "aligned_alloc",
    "posix_memalign", "valloc", "pvalloc", "_malloc_r", "_free_r", "_calloc_r",
    "_realloc_r", "_memalign_r", "_sbrk", "_sbrk_r", "sbrk",
    "atexit", "__register_exitproc", "__cxa_atexit", "__aeabi_atexit",
    "__cxa_allocate_exception", "__cxa_free_exception",
    "__cxa_allocate_dependent_exception", "__cxa_free_dependent_exception",
    "__cxa_throw", "__cxa_rethrow",
}
# operator new / new[] (_Znw*, _Zna*), delete / delete[] (_Zdl*, _Zda*),
# array-cookie helpers (__cxa_vec_new*, __cxa_vec_delete*)
HEAP_PATTERN = re.compile(r"^(_Zn[wa]|_Zd[la]|__cxa_vec_(new|delete))")


def is_heap_symbol(name):
    return name in HEAP_NAMES or bool(HEAP_PATTERN.match(name))


def log(msg):
    print(msg, flush=True)


def tool(name, hint_dir=None):
    if hint_dir:
        cand = os.path.join(hint_dir, name)
        if os.access(cand, os.X_OK):
            return cand
    return shutil.which(name)


def read_manifest(build_dir, name="legsim_mcu_manifest.txt"):
    path = os.path.join(build_dir, name)
    if not os.path.exists(path):
        log(f"FAIL: {path} missing: the cross build made no firmware image. Is "
            "firmware_core/mcu added by the top-level CMakeLists.txt when "
            "CMAKE_CROSSCOMPILING? Did mcu_build_* pass?")
        sys.exit(1)
    out = {}
    with open(path) as f:
        for line in f:
            if "=" in line:
                k, v = line.rstrip("\n").split("=", 1)
                out[k] = v
    return out


# ---- build ---------------------------------------------------------------
def cmd_build(args):
    gcc = tool("arm-none-eabi-gcc")
    if not gcc:
        log("SKIP: arm-none-eabi-gcc not found (apt-get install gcc-arm-none-eabi "
            "libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib)")
        return SKIP
    # the host's compiler settings must not leak into the cross build
    env = {k: v for k, v in os.environ.items()
           if k not in ("CC", "CXX", "ASM", "CFLAGS", "CXXFLAGS", "ASMFLAGS", "CPPFLAGS",
                        "LDFLAGS", "CMAKE_TOOLCHAIN_FILE", "CMAKE_BUILD_TYPE",
                        "CMAKE_GENERATOR", "CMAKE_GENERATOR_PLATFORM",
                        "CMAKE_GENERATOR_TOOLSET")}
    steps = [
        [args.cmake, "--preset", args.preset, "-B", args.build_dir],
        [args.cmake, "--build", args.build_dir, "-j", "2"],
    ]
    for cmd in steps:
        log("$ " + " ".join(cmd))
        r = subprocess.run(cmd, cwd=args.source, env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
        sys.stdout.write(r.stdout)
        if r.returncode != 0:
            log(f"FAIL: exit status {r.returncode}")
            return 1
    m = read_manifest(args.build_dir, args.manifest)
    if not os.path.exists(m["image"]):
        log(f"FAIL: {m['image']} was not built")
        return 1
    log(f"OK: {args.preset}: {m['image']} ({m['board']}, {m['cpu']})")
    return 0


# ---- symbols -------------------------------------------------------------
def nm_lines(nm, *args):
    r = subprocess.run([nm, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        log(f"FAIL: {nm} {' '.join(args)}: {r.stderr.strip()}")
        sys.exit(1)
    return r.stdout.splitlines()


def cmd_symbols(args):
    # (without the toolchain, mcu_build_* skipped and there is nothing to check)
    if not tool("arm-none-eabi-gcc") or not tool("arm-none-eabi-nm"):
        log("SKIP: arm-none-eabi-gcc / arm-none-eabi-nm not found (apt-get install "
            "gcc-arm-none-eabi binutils-arm-none-eabi)")
        return SKIP
    m = read_manifest(args.build_dir, args.manifest)
    nm = m.get("nm") or ""
    if not (nm and os.access(nm, os.X_OK)):
        nm = tool("arm-none-eabi-nm")
    bad = []
    for key in ("lib_core", "lib_models"):
        lib = m[key]
        # -A: "archive:member: symbol" lines, so a finding names its object file
        undefined = nm_lines(nm, "-A", "-u", lib)
        defined = nm_lines(nm, "-A", "--defined-only", lib)
        n_undef = 0
        for line in undefined:
            parts = line.split()
            if len(parts) >= 2 and parts[-2] == "U":
                n_undef += 1
                if is_heap_symbol(parts[-1]):
                    bad.append(f"{line.split(':')[1] if ':' in line else lib}: references {parts[-1]}")
        for line in defined:
            parts = line.split()
            if len(parts) >= 3 and is_heap_symbol(parts[-1]):
                bad.append(f"{lib}: defines {parts[-1]}")
        log(f"{os.path.basename(lib)}: {n_undef} undefined references checked")
    image = m["image"]
    n_def = 0
    for line in nm_lines(nm, "--defined-only", image):
        parts = line.split()
        if len(parts) < 3:
            continue
        n_def += 1
        name = parts[-1]
        if is_heap_symbol(name):
            bad.append(f"{os.path.basename(image)}: defines {name}")
        elif name.startswith("__wrap_"):
            # kept only if something called it: a heap call reached the trap
            bad.append(f"{os.path.basename(image)}: contains {name} "
                       f"(something calls {name[len('__wrap_'):]})")
    log(f"{os.path.basename(image)}: {n_def} defined symbols checked")
    if bad:
        log("FAIL: heap use:\n  " + "\n  ".join(bad))
        return 1
    log("OK: no malloc/free/calloc/realloc, operator new/delete, __cxa_* allocation "
        "or atexit symbols")
    return 0


# ---- qemu ------------------------------------------------------------------
def parse_report(text):
    """Lines of leg_report.h into a dict keyed by tuples."""
    rep = {"raw": text}
    for line in text.splitlines():
        f = line.split()
        if not f:
            continue
        try:
            if f[0] == "legsim-mcu":
                rep["real"] = f[f.index("real") + 1]
            elif f[0] == "model":
                rep["model"] = f[1]
            elif f[0] == "sim_size":
                rep["sim_size"], rep["storage"] = int(f[1]), int(f[3])
            elif f[0] == "stand" and f[1] == "status":
                rep["stand_status"] = int(f[2])
            elif f[0] in ("stand", "step"):
                prefix = (f[0],) if f[0] == "stand" else (f[0], f[1])
                rest = f[len(prefix):]
                if rest[0] == "q":
                    rep[prefix + ("q", int(rest[1]))] = tuple(float(x) for x in rest[2:5])
                elif rest[0] == "foot":
                    rep[prefix + ("foot",)] = (float(rest[1]), float(rest[2]))
                elif rest[0] == "contact":  # name: state N T x y
                    rep[prefix + ("contact", rest[1])] = tuple(float(x) for x in rest[2:7])
                elif rest[0] == "joint":
                    rep[prefix + ("joint", rest[1])] = (float(rest[2]), float(rest[3]))
                elif rest[0] == "status":
                    rep[prefix + ("status",)] = (int(rest[1]), int(rest[3]))
                elif rest[0] == "insns_per_step":
                    rep[prefix + ("insns",)] = int(rest[2])
                elif rest[0] == "disabled":
                    rep[prefix + ("disabled",)] = True
            elif f[0] == "done":
                rep["done"] = int(f[2])
            elif f[0] == "stack":
                rep["stack"] = (int(f[2]), int(f[4]))
        except (ValueError, IndexError):
            pass
    return rep


# largest share of the stack the high-water mark may reach
STACK_LIMIT = 0.90


def close(a, b, tol):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def cmd_qemu(args):
    qemu = tool("qemu-system-arm")
    if not qemu:
        log("SKIP: qemu-system-arm not found (apt-get install qemu-system-arm)")
        return SKIP
    if not tool("arm-none-eabi-gcc"):
        log("SKIP: arm-none-eabi-gcc not found, so no image was built")
        return SKIP
    m = read_manifest(args.build_dir, args.manifest)
    cmd = [qemu, "-M", m["board"], "-nographic", "-monitor", "none", "-serial", "none",
           "-semihosting-config", "enable=on,target=native", "-icount", "shift=0",
           "-kernel", m["image"]]
    log("$ " + " ".join(cmd))
    try:
        # QEMU writes the semihosting console to stderr (no chardev given): take both
        r = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=args.timeout)
    except subprocess.TimeoutExpired as e:
        log((e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes)
            else (e.stdout or ""))
        log(f"FAIL: no exit after {args.timeout} s")
        return 1
    sys.stdout.write(r.stdout)
    failures = []
    if r.returncode != 0:
        failures.append(f"image exit status {r.returncode} (0 expected)")
    mcu = parse_report(r.stdout)

    host_out = subprocess.run([args.host_report], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, timeout=args.timeout)
    host = parse_report(host_out.stdout)
    if host_out.returncode != 0 or host.get("done") != 0:
        log(host_out.stdout)
        failures.append(f"host twin exit status {host_out.returncode}")

    single = "float" in (mcu.get("real"), host.get("real"))
    # float: ~1e-7 resolution and a 1e-5 Newton tolerance; double: the facts are
    # rounded to 1e-7, host and image agree to rounding
    tol_fact = 5e-5 if single else 1e-6
    tol_stand = 5e-5 if single else 1e-8
    tol_step = 5e-4 if single else 1e-6

    if mcu.get("done") != 0:
        failures.append(f"report status {mcu.get('done')} (0 expected)")
    if mcu.get("stand_status") != 0:
        failures.append("stand pose not assembled")
    # the high-water mark is found by painting the stack: a mark at (or near) the
    # whole stack means the painted margin was used up, i.e. a likely overflow
    stack = mcu.get("stack")
    if stack is None:
        failures.append("stack: the image printed no 'stack used N of M' line")
    elif stack[0] >= STACK_LIMIT * stack[1]:
        failures.append(f"stack: high-water mark {stack[0]} of {stack[1]} bytes "
                        f"(>= {STACK_LIMIT:.0%}: likely overflow; shrink the frames or "
                        "raise the stack size)")

    def check(what, got, want, tol):
        if got is None:
            failures.append(f"{what}: missing from the image's output")
            return
        got = got if isinstance(got, tuple) else (got,)
        want = want if isinstance(want, tuple) else (want,)
        if not close(got, want, tol):
            failures.append(f"{what}: image {got}, expected {want} (tol {tol:g})")

    if args.facts == "robot":
        # both feet stuck (state 1) on the ground line y = 0 (models/robot.toml: level,
        # through the origin), at the stand and after the steps
        feet = [(k, v) for k, v in mcu.items() if isinstance(k, tuple) and k[-2] == "contact"]
        if len(feet) != 6:
            failures.append(f"{len(feet)} contact lines, 6 expected (2 feet x stand, rk4, "
                            "generalized_alpha)")
        for key, v in feet:
            if v[0] != 1:
                failures.append(f"{' '.join(key)}: state {v[0]:g}, 1 (stuck) expected")
            check(" ".join(key) + " on the ground (y)", v[4], 0.0, tol_fact)
        # the stand: each foot under its hip (+-0.20 m, models/robot.toml) at the leg's
        # stand foot x (STAND_FACTS) on its side
        for name, sign in (("right.foot", 1.0), ("left.foot", -1.0)):
            v = mcu.get(("stand", "contact", name))
            check(f"stand {name} x", v[3] if v else None,
                  sign * (0.20 + STAND_FACTS[("foot",)][0]), tol_fact)
    # the known stand pose
    for key, want in (STAND_FACTS.items() if args.facts == "leg" else ()):
        if key[0] == "phi":
            q = mcu.get(("stand", "q", key[1]))
            check(f"stand phi of body {key[1]}", q[2] if q else None, want, tol_fact)
        else:
            check("stand " + " ".join(map(str, key)), mcu.get(("stand",) + key), want, tol_fact)

    # everything the host twin printed, stand pose and after the steps
    compared = 0
    for key, want in host.items():
        if not isinstance(key, tuple) or key[-1] in ("insns", "disabled"):
            continue
        if key[0] == "step" and (("step", key[1], "disabled") in mcu
                                 or ("step", key[1], "disabled") in host):
            continue
        got = mcu.get(key)
        if key[-1] == "status":
            if got != want:
                failures.append(f"{' '.join(map(str, key))}: image {got}, host {want}")
            continue
        check(" ".join(map(str, key)) + " vs host", got, want,
              tol_stand if key[0] == "stand" else tol_step)
        compared += 1

    ipc = ", ".join(f"{k[1]} {v} insns/step" for k, v in mcu.items()
                    if isinstance(k, tuple) and k[-1] == "insns")
    log(f"summary: {m['cpu']} on {m['board']}: sim_size {mcu.get('sim_size')} of storage "
        f"{mcu.get('storage')}, stack {mcu.get('stack')}, {ipc}; {compared} values "
        f"compared with the host (real {host.get('real')})")
    if failures:
        log("FAIL:\n  " + "\n  ".join(failures))
        return 1
    log("OK")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    b = sub.add_parser("build")
    b.add_argument("--preset", required=True)
    b.add_argument("--source", required=True)
    b.add_argument("--build-dir", required=True)
    b.add_argument("--cmake", default="cmake")
    b.add_argument("--manifest", default="legsim_mcu_manifest.txt")
    s = sub.add_parser("symbols")
    s.add_argument("--build-dir", required=True)
    s.add_argument("--manifest", default="legsim_mcu_manifest.txt")
    q = sub.add_parser("qemu")
    q.add_argument("--build-dir", required=True)
    q.add_argument("--host-report", required=True)
    q.add_argument("--manifest", default="legsim_mcu_manifest.txt")
    q.add_argument("--facts", choices=("leg", "robot"), default="leg")
    q.add_argument("--timeout", type=float, default=120.0)
    args = ap.parse_args()
    return {"build": cmd_build, "symbols": cmd_symbols, "qemu": cmd_qemu}[args.cmd](args)


if __name__ == "__main__":
    sys.exit(main())
