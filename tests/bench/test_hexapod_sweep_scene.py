"""The paper's Section V sweep through legsim_cli (scenes/hexapod_section5.toml, scenes/README.md
"Section V"): its JSON against the Python API run independently (legsim.Hexapod.reaction_sweep
on the same grid), its parts concatenating into the whole, and bad scenes refused."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from built import legsim_cli

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))


SCENE = ROOT / "scenes" / "hexapod_section5.toml"



def _run(scene):
    r = subprocess.run([str(legsim_cli()), str(scene)], capture_output=True, text=True, timeout=300)
    return r, (json.loads(r.stdout) if r.returncode == 0 else None)


def _variant(tmp_path, name, extra, drop=()):
    text = "".join(line for line in SCENE.read_text().splitlines(keepends=True)
                   if not any(line.startswith(k + " ") for k in drop))
    text = text.replace('model = "../models/hexapod.toml"', f'model = "{ROOT / "models" / "hexapod.toml"}"')
    p = tmp_path / f"{name}.toml"
    p.write_text(text + extra)
    return p


def test_the_scene_is_the_python_api(tmp_path):
    legsim = pytest.importorskip("legsim")
    r, d = _run(SCENE)
    assert r.returncode == 0, r.stderr
    sw = d["sweep"]
    h = legsim.Hexapod.from_toml(ROOT / "models" / "hexapod.toml")
    py = h.reaction_sweep(leg=0, stance=(0, 2, 4), box_height_m=sw["box_height_m"], distance_m=sw["distance_m"],
                          n_distance=sw["n_distance"], heading_rad=sw["heading_rad"], n_heading=sw["n_heading"])
    assert len(d["points"]) == len(py["index"]) == 60 and d["summary"]["standing"] == 60
    legs = d["legs"]
    for k, p in enumerate(d["points"]):
        assert p["index"] == py["index"][k] and p["status_code"] == "LEGSIM_OK"
        # the JSON's numbers are the shortest round trip: equal to the library's bit for bit
        assert p["distance"] == py["distance_m"][k] and p["heading"] == py["heading_rad"][k]
        assert np.array_equal([p["feet"][n]["force"] for n in legs], py["foot_force_n"][k])
        assert np.array_equal(p["actuator_forces"], py["actuator_force_n"][k])
        assert np.array_equal(p["lengths"], py["length_m"][k]) and p["margin"] == py["margin_m"][k]
    forces = np.array([p["actuator_forces"] for p in d["points"]])
    assert np.array_equal(d["summary"]["max_actuator_force"], np.abs(forces).max(axis=(0, 1)))


def test_parts_concatenate_into_the_whole(tmp_path):
    whole = _run(SCENE)[1]["points"]
    parts = []
    for k in (1, 2, 3):
        r, d = _run(_variant(tmp_path, f"part{k}", f"part = [{k}, 3]\n"))
        assert r.returncode == 0, r.stderr
        assert d["sweep"]["part"] == [k, 3]
        parts += d["points"]
    assert parts == whole


@pytest.mark.parametrize("name,extra,drop,message", [
    ("not_in_stance", 'leg = "right_middle"\n', ("leg",), "'leg' must be one of the 'stance'"),
    ("unknown_leg", 'leg = "tail"\n', ("leg",), "the file has no leg 'tail'"),
    ("digit_name", 'stance = ["right_front", "right_rear", "7"]\n', ("stance",), "the file has no leg '7'"),
    ("index_7", "leg = 7\n", ("leg",), "'leg' must be a leg's name or an index 0..5 (got 7)"),
    ("unknown_key", "grid = 3\n", (), "unknown key 'grid'"),
    ("bad_part", "part = [4, 3]\n", (), "'part' must be [k, n]"),
    ("two_legs", 'stance = ["right_front", "right_rear"]\n', ("stance",), "'stance' must list 3 to 6 legs"),
    ("nan_distance", "distance = [0.4, nan]\n", ("distance",), "'distance'[1] is not finite"),
    ("far_heading", "heading = [-4.0, 0.3]\n", ("heading",), "'heading'[0] must be in"),
    ("too_many", "n_distance = 2000\nn_heading = 1000\n", ("n_distance", "n_heading"), "at most 1000000 points"),
])
def test_bad_scenes_are_refused(tmp_path, name, extra, drop, message):
    r, _ = _run(_variant(tmp_path, name, extra, drop))
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert r.stdout == ""
