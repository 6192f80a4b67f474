"""CAD side of flexshaft: parametric shaft parts, STEP/STL I/O, axial slicing.

The only package that imports build123d or OCP (lazily). It knows nothing of
dynamics; its product is a section table handed to :mod:`flexshaft`.
Populated by the geometry issue; for now a skeleton.
"""

#: build123d works in millimetres; every dimension crosses into SI here, once.
MM_PER_M = 1000.0

__all__ = ["MM_PER_M"]
