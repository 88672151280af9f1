"""The bench's model-file reader refuses what the core's reader refuses (firmware_core/host/
toml_limits.hpp): anything but a regular file (a FIFO must not block it) and files over 1 MiB."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.reference.model_file import MAX_BYTES, ModelFileError, read_model_file  # noqa: E402


def test_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "leg.toml"
    os.mkfifo(fifo)
    # in a child: a reader that blocked on the FIFO would hang the test run, not fail it
    code = ("import sys; sys.path.insert(0, sys.argv[2]);"
            "from legsim_bench.reference.model_file import read_model_file, ModelFileError\n"
            "try:\n    read_model_file(sys.argv[1])\nexcept ModelFileError as e:\n    print(e)")
    out = subprocess.run([sys.executable, "-c", code, str(fifo), str(ROOT / "bench")],
                         capture_output=True, text=True, timeout=30)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"{fifo}: cannot read the model file: not a regular file"


def test_a_folder_and_a_large_file_are_refused(tmp_path):
    with pytest.raises(ModelFileError, match="not a regular file"):
        read_model_file(tmp_path)
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * MAX_BYTES + "\n")
    with pytest.raises(ModelFileError, match=f"larger than {MAX_BYTES} bytes"):
        read_model_file(big)
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"name = \"\xff\"\n")
    with pytest.raises(ModelFileError, match="not UTF-8"):
        read_model_file(bad)


def test_the_robot_file_reads_as_before():
    d = read_model_file(ROOT / "models" / "robot.toml")
    assert len(d["leg"]) == 2 and d["ground"]["mu_static"] > 0
