"""Where legsim finds its library, and that it needs no header to mirror it."""
from __future__ import annotations

import shutil

import numpy as np
import pytest

import legsim
from legsim import _lib


def test_explicit_path_file_or_directory(precision):
    p = legsim.find_library(precision)
    assert legsim.find_library(precision, p) == p
    assert legsim.find_library(precision, p.parent) == p
    assert p.name == legsim.LIB_NAMES[precision]


def test_lib_dir_is_the_only_place_looked_at_when_set(monkeypatch, tmp_path):
    monkeypatch.setenv("LEGSIM_LIB_DIR", str(tmp_path))
    with pytest.raises(legsim.LibraryNotFound) as e:
        legsim.find_library("double")
    assert str(tmp_path / "liblegsim.so") in str(e.value) and "LEGSIM_LIB_DIR" in str(e.value)
    assert not legsim.library_available("double")
    with pytest.raises(ValueError):
        legsim.find_library("half")


def test_a_copy_without_any_header_loads_from_its_own_facts(tmp_path, precision, root):
    """An installed-like library (a lone file, no legsim/config.h anywhere near):
    the layout comes from legsim_build_info and gives the same results."""
    src = legsim.find_library(precision)
    lone = tmp_path / "prefix" / "lib" / src.name
    lone.parent.mkdir(parents=True)
    shutil.copy2(src, lone)
    lib = legsim.load_library(precision, lone)
    assert lib.path == lone and lib.config_source == "legsim_build_info"
    assert not any(p.is_file() for p in _lib._config_h_candidates(lone, precision))
    a = legsim.Sim(root / "models" / "leg.toml", lib_path=lone)
    b = legsim.Sim(precision=precision)
    assert a.library is lib and a.precision == precision
    a.assemble_pose()
    b.assemble_pose()
    np.testing.assert_array_equal(a.statics(), b.statics())


def test_a_library_of_the_other_precision_is_refused(precision):
    other = {"double": "float", "float": "double"}[precision]
    if not legsim.library_available(other):
        pytest.skip(f"{legsim.LIB_NAMES[other]} is not built")
    wrong = legsim.find_library(other)
    with pytest.raises(legsim.LayoutMismatch, match="LEGSIM_USE_FLOAT"):
        _lib.Library(wrong, precision)


def test_installed_library_candidates_cover_the_usual_prefixes():
    c = [str(p) for p in _lib._installed_candidates("double")]
    assert "/usr/local/lib/liblegsim.so" in c and "/usr/lib/liblegsim.so" in c


def test_the_repository_build_tree_is_found_without_the_environment(monkeypatch, root):
    built = root / "build" / "host" / "firmware_core" / "liblegsim.so"
    if not built.is_file():
        pytest.skip("build/host is not built (this test checks the default location)")
    monkeypatch.delenv("LEGSIM_LIB_DIR", raising=False)
    monkeypatch.delenv("LEGSIM_ROOT", raising=False)
    assert legsim.find_library("double").resolve() == built.resolve()
