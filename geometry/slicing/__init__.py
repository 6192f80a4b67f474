"""Slice a shaft along its axis into a :class:`~flexshaft.sections.SectionTable`.

:func:`sections` takes a build123d solid, a watertight mesh or a part file and
hands it to the slicer for its kind. Importing this package loads no CAD
library; each slicer imports its own when it runs.

Modules, in the order data flows through them:

- :mod:`~geometry.slicing.common`: what both slicers share (the axis, the
  section checks, the stations, the table's columns, the mass check);
- :mod:`~geometry.slicing.solid`: the B-rep slicer (build123d/OCCT), with
  :mod:`~geometry.slicing.brep` (low-level B-rep reads, mm) and
  :mod:`~geometry.slicing.frames` (the shaft frame);
- :mod:`~geometry.slicing.mesh`: the mesh slicer (trimesh, STL/OBJ/PLY);
- :mod:`~geometry.slicing.polygons`: exact moments of polygon sections;
- :mod:`~geometry.slicing.warping`: St-Venant J and shear areas of
  non-circular sections (sectionproperties, cached).
"""

from __future__ import annotations

import os
from collections.abc import Callable

from flexshaft.sections import SectionTable

from .common import MAX_OFFSET, MIN_FILL, SYMMETRY_TOL, AxisSpec, MassCheck, SliceOptions

__all__ = ["AxisSpec", "MassCheck", "sections", "SYMMETRY_TOL", "MAX_OFFSET", "MIN_FILL"]


def sections(
    shape,
    *,
    axis=None,
    nu: float = 0.29,
    name: str = "part",
    taper_divisions: int = 6,
    points_per_circle: int = 128,
    progress: Callable[[int, int], None] | None = None,
    unit: str | None = None,
) -> SectionTable:
    """The section table of a straight shaft solid.

    Parameters
    ----------
    shape : build123d Shape, trimesh.Trimesh, str or Path
        One closed solid (build123d's millimetres, as build123d makes them),
        a watertight mesh in metres (see :func:`geometry.cadio.read_mesh`), or
        a part file to read with :func:`geometry.cadio.read_cad`.
    axis : AxisSpec, (origin, direction) or mapping, optional
        The shaft axis in SI metres. If omitted it is found
        (:func:`~geometry.slicing.solid.find_axis`: the principal axes of
        inertia, made exact by the turned faces) and the stations start at 0
        at the part's lower end.
    nu : float
        Poisson's ratio for the shear areas.
    name : str
        The part's name for the table and for messages.
    taper_divisions : int
        Sub-intervals for an interval whose section varies (chamfer, fillet).
    points_per_circle : int
        Polygon resolution of the largest circle in a section given to the
        warping analysis.
    progress : callable, optional
        Called as ``progress(done, total)`` after each slice.
    unit : str, optional
        Length unit of a mesh file given as a path.

    Returns
    -------
    SectionTable
        With ``meta["mass_check"]`` a :class:`MassCheck` and ``meta["axis"]``
        the axis used.

    Raises
    ------
    ModelError
        Not one closed solid; no axis of symmetry; a section that is split,
        empty or too far from round about the axis (a bent or eccentric body).
    """
    if isinstance(shape, (str, os.PathLike)):
        from ..cadio import read_cad

        shape = read_cad(shape, unit=unit)
    options = SliceOptions(axis, nu, name, taper_divisions, points_per_circle, progress)
    if type(shape).__module__.split(".")[0] == "trimesh":
        from .mesh import mesh_sections

        return mesh_sections(shape, options)
    from .solid import solid_sections

    return solid_sections(shape, options)
