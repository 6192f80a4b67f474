"""A mesh beyond what the machine can hold is refused before it is built, with the estimate: 1D parts' element
counts, and a solid part's DOFs estimated before gmsh meshes it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time

import pytest

import flexshaft as fs
from flexshaft.parts.beammesh import MAX_MESH_ELEMENTS, torsion_mesh
from flexshaft.parts.model import MAX_FULL_ELEMENTS
from flexshaft.sections import table_from_segments
from tests.conftest import gmsh_loads, solid_shaft_model, without_progress

TABLE = table_from_segments([{"length": 1.0, "od": 0.1}], name="s")


@pytest.mark.parametrize("h", [1e-9, 1e-300])
def test_a_tiny_element_length_is_refused_with_the_count(h):
    # 1 m / 1e-9 m = 1e9 elements (the 23.7 GB); 1e-300 used to overflow and be ignored.
    with pytest.raises(fs.ModelError, match=r"max_element_length = .* m: would cut the part into 1e\+"):
        torsion_mesh(TABLE, fs.STEEL, max_element_length=h)


def test_the_limits_themselves_build():
    # Right at the torsion limit the mesh builds (arrays of 4e6 floats); one 6-DOF element more than its
    # limit is refused before the 12 × 12 blocks are made.
    mesh = torsion_mesh(TABLE, fs.STEEL, max_element_length=1.0 / MAX_MESH_ELEMENTS)
    assert mesh.n_elements == MAX_MESH_ELEMENTS
    too_many = f"would make a 6-DOF part model of {MAX_FULL_ELEMENTS + 1} elements"
    with pytest.raises(fs.ModelError, match=too_many):
        fs.part_model(TABLE, fs.STEEL, dofs="full", max_element_length=1.0 / (MAX_FULL_ELEMENTS + 1))


TINY_SOLID = solid_shaft_model("0.1", "1 mm")


@pytest.mark.skipif(not gmsh_loads(), reason="the solid extra (gmsh) is not installed")
def test_a_tiny_solid_mesh_size_is_refused_in_one_line_before_meshing(tmp_path):
    # 1 mm on a 1 m shaft of 0.1 m: ~5e7 elements, which gmsh ran for minutes at 2-4 GB before it
    # ended in an empty mesh and "unexpected ValueError ... (a flexshaft defect)". The bound:
    # refused within 30 s (the command's start, building the part and gmsh's reading of it take ~5 s).
    model = tmp_path / "tiny.toml"
    model.write_text(TINY_SOLID)
    started = time.monotonic()
    run = subprocess.run(
        [sys.executable, "-m", "flexshaft", "twist", str(model)],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "FLEXSHAFT_CACHE_DIR": str(tmp_path / "cache")},
    )
    took = time.monotonic() - started
    assert run.returncode == 2 and run.stdout == ""
    # the error in one line (before it, on a busy machine, only progress lines)
    lines = without_progress(run.stderr).splitlines()
    assert len(lines) == 1, run.stderr
    line = lines[0]
    where = f"flexshaft: error: {model}: [[chain]] #2 'shaft': "
    assert line.startswith(where + "mesh_size = 0.001 m: would mesh into about")
    assert "above the ceiling of 2000000 DOFs of a solid part" in line
    size = float(re.search(r"valid: a mesh_size of at least ([0-9.e+-]+) m", line).group(1))
    assert 0.001 < size < 0.1
    assert took < 30.0, f"{took:.1f} s"
