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
