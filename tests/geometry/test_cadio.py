"""Reading CAD files (geometry.cadio): what is refused, and how."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("build123d")

import flexshaft as fs  # noqa: E402
from geometry.cadio import read_cad, read_mesh  # noqa: E402


def test_open_stl_is_refused(tmp_path):
    import trimesh

    mesh = trimesh.creation.cylinder(radius=50.0, height=400.0)
    mesh.update_faces(np.arange(len(mesh.faces)) != 0)
    mesh.export(tmp_path / "open.stl")
    with pytest.raises(fs.ModelError, match=r"is not watertight \(3 open edges\)"):
        read_mesh(tmp_path / "open.stl", unit="mm")


def test_unreadable_files(tmp_path):
    (tmp_path / "bad.step").write_text("ISO-10303-21;\nthis is not a step file\n")
    with pytest.raises(fs.ModelError, match="cannot be read as STEP|holds no shape"):
        read_cad(tmp_path / "bad.step")
    with pytest.raises(fs.ModelError, match="file not found"):
        read_cad(tmp_path / "missing.step")
    with pytest.raises(fs.ModelError, match="unknown file type"):
        read_cad(tmp_path / "x.iges")
    (tmp_path / "bad.stl").write_bytes(b"\x00" * 30)
    with pytest.raises(fs.ModelError, match="cannot be read as a mesh|holds no triangles"):
        read_mesh(tmp_path / "bad.stl", unit="mm")


def test_a_broken_step_prints_nothing_on_stdout_and_one_error_line(tmp_path):
    # OCCT's parser prints its complaints (with colour codes) on file descriptor 1; they belong in the
    # one error line, not in the program's output. A subprocess sees the real descriptors.
    import subprocess
    import sys

    bad = tmp_path / "bad.step"
    bad.write_text("ISO-10303-21;\nHEADER;\ngarbage\n")
    cmd = [sys.executable, "-m", "flexshaft.cli", "sections", str(bad)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert len(proc.stderr.strip().splitlines()) == 1 and "bad.step" in proc.stderr


def test_a_step_file_takes_no_unit(tmp_path):
    from flexshaft.io.cad import cad_sections

    with pytest.raises(fs.ModelError, match="unit = 'mm': only a mesh file"):
        cad_sections("part.step", name="p", nu=0.29, unit="mm", base_dir=tmp_path)
