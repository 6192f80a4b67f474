"""Part files that crash, hang or mislead their parsers (issue 33): a STEP of 200 000 nested parentheses
(OCCT's recursive parser overflowed its stack: SIGSEGV, nothing on stderr), half a STEP, bytes of
another kind named .step, a BREP of garbage, an open STL, a binary STL whose header claims 2**32 - 1
triangles. Every part file is parsed in an isolated child: each is one error line naming the file."""

from __future__ import annotations

import os
import struct
from pathlib import Path

from tests.flexshaft.catalogue import Case
from tests.flexshaft.catalogue.inputs import _cad_model
from tests.geometry.cad_files import deep_step, good_step

READ_STEP = "cannot be read as STEP"


def _deep(argv_of):
    def setup(d: Path) -> list[str]:
        deep_step(d / "deep.step")
        return argv_of(d)

    return setup


def _deep_in_model(d: Path) -> list[str]:
    (d / "m.toml").write_text(_cad_model("deep.step"))
    return ["modes", "m.toml", "--no-cache"]


def _cut_step(d: Path) -> list[str]:
    good = good_step(d / "whole.step").read_bytes()
    (d / "cut.step").write_bytes(good[: len(good) // 2])
    return ["sections", "cut.step"]


def _png_as_step(d: Path) -> list[str]:
    (d / "png.step").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 40)
    return ["sections", "png.step"]


def _garbage_brep(d: Path) -> list[str]:
    (d / "bad.brep").write_bytes(b"DBRep_DrawableShape\n\nCASCADE Topology V1\n" + os.urandom(4000))
    return ["sections", "bad.brep"]


def _open_stl(d: Path) -> list[str]:
    import numpy as np
    import trimesh

    mesh = trimesh.creation.cylinder(radius=50.0, height=400.0)
    mesh.update_faces(np.arange(len(mesh.faces)) != 0)
    mesh.export(d / "open.stl")
    return ["sections", "open.stl", "--unit", "mm"]


def _claiming_stl(d: Path) -> list[str]:
    # binary STL: 80-byte header, uint32 count, 50 bytes a triangle: 2 by the size, 4 294 967 295 by the
    # header (200 GB of triangles)
    (d / "claim.stl").write_bytes(b"claim".ljust(80) + struct.pack("<I", 2**32 - 1) + bytes(100))
    return ["sections", "claim.stl", "--unit", "mm"]


CASES = {
    "sections of a STEP of 200 000 nested parentheses": Case(
        _deep(lambda d: ["sections", "deep.step"]),
        says=("deep.step", READ_STEP, "crashed", "valid"),
        budget_s=60,
    ),
    "the deep STEP as a model's CAD part": Case(
        _deep(_deep_in_model), says=("deep.step", READ_STEP, "crashed", "valid"), budget_s=60
    ),
    "half a STEP file": Case(_cut_step, says=("cut.step", "valid"), budget_s=60),
    "PNG bytes named .step": Case(_png_as_step, says=("png.step", "valid"), budget_s=60),
    "a BREP of garbage": Case(
        _garbage_brep, says=("bad.brep", "cannot be read as BREP", "valid"), budget_s=60
    ),
    "an open STL": Case(_open_stl, says=("open.stl", "not watertight", "valid"), budget_s=60),
    "a binary STL claiming 2**32 - 1 triangles": Case(
        _claiming_stl, says=("claim.stl", "valid"), budget_s=60
    ),
}
