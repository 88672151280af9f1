"""The bench's layout: its modules import one another without a circle, counting every import,
those inside functions too (so that none is there to dodge a circle), and each imports alone.
"""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PKG = ROOT / "bench" / "legsim_bench"


def _modules() -> dict[str, Path]:
    out = {}
    for p in sorted(PKG.rglob("*.py")):
        parts = list(p.relative_to(PKG.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = p
    return out


def _is_package(path: Path) -> bool:
    return path.name == "__init__.py"


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The bench modules `name` imports, anywhere in it (a package's import runs its __init__)."""
    pkg = name if _is_package(path) else name.rpartition(".")[0]
    found: set[str] = set()

    def add(mod: str) -> None:
        parts = mod.split(".")
        for i in range(1, len(parts) + 1):        # importing a.b.c runs a, a.b and a.b.c
            m = ".".join(parts[:i])
            if m in modules and m != name:
                found.add(m)

    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for a in node.names:
                add(a.name)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[:len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            add(mod)
            for a in node.names:                  # from pkg import submodule
                add(f"{mod}.{a.name}")
    return found


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(n: str) -> list[str] | None:
        state[n] = 1
        stack.append(n)
        for m in sorted(graph[n]):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if m not in state:
                c = visit(m)
                if c:
                    return c
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(graph):
        if n not in state:
            c = visit(n)
            if c:
                return c
    return None


def test_the_cycle_finder_finds_a_circle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_circle_counting_imports_inside_functions():
    modules = _modules()
    graph = {n: _imports(n, p, modules) for n, p in modules.items()}
    # a package's __init__ importing its own modules is no circle of theirs
    for n in modules:
        for k in range(1, n.count(".") + 1):
            parent = n.rsplit(".", k)[0]
            if n in graph[parent]:
                graph[n].discard(parent)
    assert "legsim_bench.verdict.checks" in graph and "legsim_bench.hil.runner" in graph
    assert _cycle(graph) is None, " -> ".join(_cycle(graph))


def test_the_wings_are_layered():
    """hil/ runs scenes and never judges them; reference/ depends on no other wing."""
    modules = _modules()
    for n, p in modules.items():
        deps = _imports(n, p, modules)
        if n.startswith("legsim_bench.hil"):
            assert not any(d.startswith(("legsim_bench.verdict", "legsim_bench.report")) for d in deps), (n, deps)
        if n.startswith("legsim_bench.reference"):
            assert all(d.startswith("legsim_bench.reference") or d == "legsim_bench" for d in deps), (n, deps)


@pytest.mark.parametrize("name", [n for n in _modules() if n.count(".") <= 2 and not n.endswith("__main__")
                                  and not n.startswith("legsim_bench.benchmarks.peers")])
def test_each_module_imports_alone(name):
    r = subprocess.run([sys.executable, "-c", f"import {name}"], capture_output=True, text=True,
                       cwd=ROOT, env={"PYTHONPATH": f"{ROOT / 'bench'}:{ROOT / 'python'}",
                                      "LEGSIM_ROOT": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr[-2000:]
