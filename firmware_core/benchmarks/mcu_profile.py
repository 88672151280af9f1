#!/usr/bin/env python3
"""Where a firmware image's instructions go, per function, under QEMU (no profiler needed).

    firmware_core/benchmarks/mcu_profile.py IMAGE.elf [--board mps2-an386] [--from legsim_step]
        [--to newton] [--per 100] [--top 25]

Runs the image with `-icount shift=0 -d in_asm,exec,nochain` (QEMU logs each translated
block's instructions once and each block's every execution), counts the instructions
executed between the first block of a function whose name contains --from and the first
of one whose name contains --to (the leg image: its RK4 steps, before the
generalized-alpha ones), and attributes them to the functions of the image's symbol table
(`arm-none-eabi-nm -S`: inlined code counts to the function it was inlined into). Divided
by --per (the leg image runs 100 steps of each integrator). The range also holds what the
image does between steps (printing): compare with the image's own insns_per_step.
Python 3 standard library; needs qemu-system-arm and arm-none-eabi-nm.
"""
import argparse
import bisect
import collections
import re
import subprocess
import sys
import tempfile


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("elf")
    ap.add_argument("--board", default="mps2-an386", help="QEMU machine (mps2-an500: Cortex-M7)")
    ap.add_argument("--from", dest="start", default="legsim_step")
    ap.add_argument("--to", dest="end", default="newton")
    ap.add_argument("--per", type=float, default=100)
    ap.add_argument("--top", type=int, default=25)
    a = ap.parse_args()

    nm = subprocess.run(["arm-none-eabi-nm", "-C", "-S", "--size-sort", a.elf], capture_output=True, text=True,
                        check=True).stdout
    funcs = sorted((int(p[0], 16) & ~1, int(p[1], 16), p[3]) for p in (l.split(None, 3) for l in nm.splitlines())
                   if len(p) == 4 and p[2] in "tTwW")
    starts = [f[0] for f in funcs]

    def function_of(addr):
        i = bisect.bisect_right(starts, addr) - 1
        return funcs[i][2] if i >= 0 and addr < funcs[i][0] + funcs[i][1] else "?"

    with tempfile.NamedTemporaryFile(suffix=".log") as log:
        subprocess.run(["qemu-system-arm", "-M", a.board, "-nographic", "-monitor", "none", "-serial", "none",
                        "-semihosting-config", "enable=on,target=native", "-icount", "shift=0",
                        "-d", "in_asm,exec,nochain", "-D", log.name, "-kernel", a.elf],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=600, check=False)
        size, name_of = {}, {}  # block start -> instructions, its symbol as QEMU names it
        counts, counting, seen_start = collections.Counter(), False, False
        block, n, sym = None, 0, None
        for line in open(log.name, errors="replace"):
            if line.startswith("IN: "):
                block, n, sym = None, 0, line[4:].strip()
            elif sym is not None and (m := re.match(r"0x([0-9a-f]{8}):", line)):
                block = int(m.group(1), 16) if block is None else block
                n += 1
                size[block], name_of[block] = n, sym
            elif m := re.match(r"Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/", line):
                sym = None
                pc = int(m.group(1), 16)
                qemu_name = name_of.get(pc, "")
                if not seen_start and a.start in qemu_name:
                    seen_start = counting = True
                elif counting and a.end in qemu_name:
                    break
                if counting:
                    counts[function_of(pc)] += size.get(pc, 0)
    if not seen_start:
        sys.exit(f"mcu_profile.py: no block of a function named like '{a.start}' ran")
    total = sum(counts.values())
    print(f"{a.elf}: {total / a.per:,.0f} instructions per {a.per:g} from '{a.start}' to '{a.end}'\n")
    print("| instructions | share | function |\n|---|---|---|")
    for fn, c in counts.most_common(a.top):
        print(f"| {c / a.per:,.0f} | {100 * c / total:.1f} % | `{fn[:90]}` |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
