"""The Python examples of README.md ("## Python API") and python/README.md run as
written, from the repository root, and print what their comments say."""
from __future__ import annotations

import contextlib
import doctest
import io
import re

import pytest


def _python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, re.S)


def _run(code: str, root, monkeypatch) -> list[str]:
    monkeypatch.chdir(root)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "<readme>", "exec"), {"__name__": "__readme__"})
    return out.getvalue().splitlines()


def test_top_readme_python_api_section(root, monkeypatch):
    text = (root / "README.md").read_text()
    assert "\n## Python API\n" in text
    section = text.split("\n## Python API\n", 1)[1].split("\n## ", 1)[0]
    blocks = _python_blocks(section)
    assert len(blocks) == 1
    lines = _run(blocks[0], root, monkeypatch)
    # the comment promises "N: [-93.93  1.387]"
    statics = [float(x) for x in lines[0].strip("[]").split()]
    assert statics == pytest.approx([-93.93, 1.387], abs=5e-3)
    assert "[-93.93  1.387]" in blocks[0]
    assert lines[-1] == "LEGSIM_ERR_UNREACHABLE"


def test_python_readme_example(root, monkeypatch):
    blocks = _python_blocks((root / "python" / "README.md").read_text())
    assert len(blocks) == 2
    lines = _run(blocks[0], root, monkeypatch)
    assert lines[0].startswith("stand: lengths [0.6614 0.6245] m")
    assert lines[1] == "statics: [-93.929   1.387] N"
    assert lines[2].startswith("t = 0.100 s")
    assert lines[-1].startswith("LEGSIM_ERR_UNREACHABLE - ")


def test_python_readme_robot_on_ground(root, monkeypatch):
    """The robot section: the working sequence, and the figures its text gives."""
    text = (root / "python" / "README.md").read_text()
    blocks = _python_blocks(text)
    assert len(blocks) == 2
    lines = _run(blocks[1], root, monkeypatch)
    assert lines == ["feet: ['stuck' 'stuck'] box (x, y, phi): [0. 1. 0.]",
                     "statics: [326.539   1.387 326.539   1.387] N",
                     "normal forces: [158.922 158.922] N",
                     "t = 0.200 s, box height 1.000000 m"]
    for shown in ("[326.539   1.387 326.539   1.387] N", "[158.922 158.922] N",
                  "box height 1.000000 m"):
        assert shown in text.split("## The robot on the ground")[1]
    # the README's claim that the pose alone has no equilibrium
    import legsim
    sim = legsim.Sim(str(root / "models" / "robot.toml"))
    sim.assemble_pose("stand")
    with pytest.raises(legsim.NoEquilibriumError):
        sim.statics()


def test_package_docstring_example(root, monkeypatch):
    import legsim
    monkeypatch.chdir(root)
    r = doctest.testmod(legsim, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert r.attempted >= 4 and r.failed == 0
