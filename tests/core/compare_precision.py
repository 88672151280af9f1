"""Runs the double and the float probe and checks that the float build stays
close to the double one: positions within 1e-4 m or rad, forces within 1e-3 relative."""
import subprocess
import sys


def read(exe):
    out = subprocess.run([exe], check=True, capture_output=True, text=True).stdout
    return [(k, float(v)) for k, v in (line.split() for line in out.splitlines())]


double, single = read(sys.argv[1]), read(sys.argv[2])
assert [k for k, _ in double] == [k for k, _ in single], "probes print different quantities"
worst_pos = worst_force = 0.0
for (key, d), (_, s) in zip(double, single):
    if key.startswith(("q", "foot")):
        worst_pos = max(worst_pos, abs(d - s))
    else:
        worst_force = max(worst_force, abs(d - s) / max(1.0, abs(d)))
print(f"float vs double: max position difference {worst_pos:.3g}, max relative force difference {worst_force:.3g}")
if worst_pos > 1e-4 or worst_force > 1e-3:
    sys.exit("float build too far from double")
