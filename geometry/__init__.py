"""CAD side of flexshaft: parametric shaft parts, CAD files, axial slicing into section tables, solid
meshes.

The only package that imports build123d, OCP, trimesh, sectionproperties and gmsh,
each inside the module that needs it; importing ``geometry``,
``geometry.slicing`` or ``geometry.cadio`` is cheap. It knows nothing of
dynamics: its products are a :class:`flexshaft.sections.SectionTable` and a
:class:`flexshaft.elements.tetmesh.TetMesh`, and of flexshaft it uses only ``errors``,
``validation``, ``sections``, ``atomic``, ``inputs``, ``limits`` and ``isolate`` (gmsh runs in a
forked child).

Laid out as its data flow::

    units.py      the one mm <-> m conversion
    parts/        build123d parts from SI dimensions
      primitives.py   segments, bolt circles; turned and flanged bodies, fusing
      prismatic.py    polygon and spline shafts
      features.py     cuts into a finished shaft: keyways, flats
      testbench.py    the 9 MW test bench's parts
    cadio.py      STEP/BREP/STL/OBJ/PLY files in and out
    slicing/      a solid or mesh -> a section table: sections()
      common.py       what both slicers share (axis, checks, columns, mass check)
      solid.py        the B-rep slicer, with brep.py (OCCT reads) and frames.py
      mesh.py         the mesh slicer
      polygons.py     exact moments of polygon sections
      warping.py      St-Venant J and shear areas (sectionproperties, cached)
    tetmesh.py    a solid -> curved 10-node tetrahedra (gmsh, the solid extra, in a forked child)
    meshsize.py   its size field and the element count estimated before meshing
"""

from .units import MM_PER_M

__all__ = ["MM_PER_M"]
