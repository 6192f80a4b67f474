"""A part's own surface as triangles in the shaft frame, for pictures of its modes.

The frame is the one the section table is in: x along the shaft axis (the same coordinate as the
table's stations), y and z across it, metres. A build123d solid is tessellated (chords within
``tolerance``); a mesh (trimesh, already in metres) is used as it is.
"""

from __future__ import annotations

import numpy as np

from ..units import from_cad, to_cad
from .common import AxisSpec
from .frames import axis_frame

__all__ = ["surface_in_frame"]


def surface_in_frame(
    shape, axis: AxisSpec, x_start: float, *, tolerance: float = 5e-4
) -> tuple[np.ndarray, np.ndarray]:
    """(points (n, 3) in m, triangles (k, 3) of point indices) of the shape's surface in the shaft frame.

    Parameters
    ----------
    shape : build123d shape or trimesh.Trimesh
        The part, as :func:`geometry.slicing.sections` sliced it.
    axis : AxisSpec
        The axis the table was sliced along (``table.meta["axis"]``), m.
    x_start : float
        The table's first station (``table.x[0]``), m: the part's end nearest the axis' start
        is put there, as the slicer puts it.
    tolerance : float
        Largest chord deviation of the tessellation, m (0.5 mm).
    """
    if type(shape).__module__.split(".")[0] == "trimesh":
        vertices = np.asarray(shape.vertices, dtype=float)
        triangles = np.asarray(shape.faces, dtype=np.int64)
    else:
        verts, tris = shape.tessellate(to_cad(tolerance), 0.3)
        vertices = from_cad(np.array([[v.X, v.Y, v.Z] for v in verts], dtype=float))
        triangles = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    local = (vertices - np.asarray(axis.origin, dtype=float)) @ axis_frame(axis.direction).T
    local[:, 0] += x_start - local[:, 0].min()
    return local, triangles
