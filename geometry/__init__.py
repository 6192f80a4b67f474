"""CAD side of flexshaft: parametric shaft parts, STEP/STL I/O, axial slicing into section tables.

The only package that imports build123d, OCP, trimesh and sectionproperties,
each inside the module that needs it; importing ``geometry`` itself is cheap.
It knows nothing of dynamics: its product is a
:class:`flexshaft.sections.SectionTable`.

Modules: :mod:`~geometry.units` (the one mm <-> m conversion),
:mod:`~geometry.parts` and :mod:`~geometry.testbench` (build123d parts),
:mod:`~geometry.cadio` (files), :mod:`~geometry.slicing` (``sections()``),
:mod:`~geometry.mesh_slicing`, :mod:`~geometry.brep`, :mod:`~geometry.polygons`,
:mod:`~geometry.warping` (sectionproperties, cached).
"""

from .units import MM_PER_M

__all__ = ["MM_PER_M"]
