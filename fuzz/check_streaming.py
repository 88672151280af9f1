#!/usr/bin/env python3
"""legsim_cli streams a long run: its memory stays flat while it writes samples.

Runs legsim_cli on a scene of 1e9 steps with a sample at every step (issue 10: such a
scene grew the CLI by about 60 MB/s until memory ran out), output drained and dropped,
and reads the process's resident memory (VmRSS, /proc) once the run is under way and
again a few seconds later. Fails when it grew by more than --max-growth-mb, when the CLI
exits on its own before the second reading (a 1e9-step run cannot be done by then) or
when it wrote no samples. Either way the run is stopped at the end.
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
            print(f'legsim_cli exited early ({proc.returncode}): {proc.stderr.read().decode()}')
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
    if growth_mb > args.max_growth_mb:
        print(f'memory grew by more than {args.max_growth_mb:g} MB: the samples are kept, not streamed')
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
