#!/usr/bin/env python3
"""legsim_cli refuses a scene too long to write, or streams it: memory stays flat.

Issue 10: a scene of 1e9 steps with a sample at every step grew the CLI by about 60 MB/s
until memory ran out. Runs legsim_cli on a long scene, output drained and dropped:
- refused: exit status 2 with a message and nothing written passes (the scene asks for
  more than the CLI writes);
- running: reads the process's resident memory (VmRSS, /proc) once the run is under way
  and again a few seconds later, and fails when it grew by more than --max-growth-mb,
  or by more than 4 MB + a quarter of what it wrote meanwhile, when the CLI exits before
  the second reading (a long run cannot be done by then) or when it wrote nothing. The run is stopped at the end.
"""
import argparse
import subprocess
import sys
import threading
import time


def rss_kb(pid):
    with open(f'/proc/{pid}/status', encoding='ascii') as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1])
    raise RuntimeError('no VmRSS')


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('cli')
    ap.add_argument('scene')
    ap.add_argument('--warmup-s', type=float, default=1.0)
    ap.add_argument('--measure-s', type=float, default=4.0)
    ap.add_argument('--max-growth-mb', type=float, default=16.0)
    args = ap.parse_args()

    proc = subprocess.Popen([args.cli, args.scene, '--format', 'csv'], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    written = [0]

    def drain():
        while True:
            chunk = proc.stdout.read(1 << 16)
            if not chunk:
                return
            written[0] += len(chunk)

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    try:
        time.sleep(args.warmup_s)
        if proc.poll() is not None:
            reader.join()
            err = proc.stderr.read().decode().strip()
            if proc.returncode == 2 and err and written[0] == 0:
                print(f'refused, nothing written: {err}')
                return 0
            print(f'legsim_cli exited early ({proc.returncode}), {written[0]} bytes written: {err}')
            return 1
        before, out_before = rss_kb(proc.pid), written[0]
        time.sleep(args.measure_s)
        if proc.poll() is not None:
            print(f'legsim_cli exited early ({proc.returncode}): {proc.stderr.read().decode()}')
            return 1
        after, out_after = rss_kb(proc.pid), written[0]
    finally:
        proc.kill()
        proc.wait()
    growth_mb = (after - before) / 1024
    out_mb = (out_after - out_before) / 1e6
    print(f'VmRSS {before / 1024:.1f} MB -> {after / 1024:.1f} MB ({growth_mb:+.1f} MB) in '
          f'{args.measure_s:g} s while writing {out_mb:.1f} MB of samples')
    if out_after <= out_before:
        print('no samples written while measuring')
        return 1
    # A kept sample takes about as much memory as its CSV row: growth that follows the output
    # means the samples are kept.
    if growth_mb > args.max_growth_mb or growth_mb > 0.25 * out_mb + 4:
        print(f'memory grew by more than min({args.max_growth_mb:g} MB, 4 MB + a quarter of the '
              'output): the samples are kept, not streamed')
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
