"""Shared fixtures of the Python API tests (tests/python).

They need the host build's shared libraries (liblegsim.so, liblegsim_f32.so: the
targets legsim and legsim_f32), found as the package finds them ($LEGSIM_LIB_DIR,
else build/host/firmware_core/). Without them the tests are skipped with that
reason (a failure under LEGSIM_NO_SKIP=1, see tests/conftest.py).
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
if importlib.util.find_spec("legsim") is None:  # not installed: the package of this tree
    sys.path.insert(0, str(ROOT / "python"))

import legsim  # noqa: E402


ROBOT = ROOT / "models" / "robot.toml"


def robot_sim(**kw) -> legsim.Sim:
    """The two-leg robot of models/robot.toml (skipped where the library has no room for it)."""
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip(f"{lib.path} is built without room for the robot")
    return legsim.Sim(str(ROBOT), **kw)


def compass_desc(lib, mu: float, g: float = 9.81):
    """A compass: two 1 kg, 1 m rods A and B (inertia 1/12 kg m^2) hinged at their tops
    (point -0.5 m on each), a foot at each rod's other end (+0.5 m), mu_s = mu_k = mu; the
    ModelDesc of `lib` (skipped where the library has no room for two contacts)."""
    if lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip(f"{lib.path} is built without two contacts")
    d = lib.ModelDesc()
    d.name = b"compass"
    d.gravity_mps2[1] = -g
    d.n_bodies = 2
    for i, nm in enumerate((b"A", b"B")):
        d.body[i].name = nm
        d.body[i].length_m = 1.0
        d.body[i].mass_kg = 1.0
        d.body[i].inertia_kgm2 = 1.0 / 12.0
        d.contact[i].name = b"foot" + nm
        d.contact[i].body = i
        d.contact[i].point[0], d.contact[i].point[1] = 0.5, 0.0
    d.n_joints = 1
    d.joint[0].name = b"hinge"
    d.joint[0].kind = 1  # LEGSIM_JOINT_REVOLUTE: point on body 0 = point on body 1
    d.joint[0].body[0], d.joint[0].body[1] = 0, 1
    d.joint[0].point[0][0] = d.joint[0].point[1][0] = -0.5
    d.foot_body = -1
    d.n_contacts = 2
    d.ground.mu_static = mu
    d.ground.mu_kinetic = mu
    return d


def _need(precision: str) -> None:
    if not legsim.library_available(precision):
        pytest.skip(f"{legsim.LIB_NAMES[precision]} is not built (cmake --build build/host, "
                    "or set LEGSIM_LIB_DIR)")


@pytest.fixture(autouse=True)
def _double_library():
    _need("double")


@pytest.fixture(params=["double", "float"])
def precision(request) -> str:
    """Each precision whose library is built."""
    _need(request.param)
    return request.param


@pytest.fixture
def root() -> Path:
    return ROOT


@pytest.fixture
def model_toml() -> Path:
    return ROOT / "models" / "leg.toml"


@pytest.fixture
def stand():
    """make(model=None, **Sim keywords): a sim assembled in the stand pose."""
    def make(model=None, **kw) -> legsim.Sim:
        s = legsim.Sim(model, **kw)
        s.assemble_pose("stand")
        return s
    return make
