"""Parametric shaft parts as build123d solids (SI metres in, one solid in millimetres out).

- :mod:`~geometry.parts.primitives`: the segment and bolt-circle data; turned
  bodies (stepped and flanged shafts, flanges, coupling hubs) with their bolt
  holes; prismatic shafts (polygon, spline); fusing parts;
- :mod:`~geometry.parts.features`: cuts into a finished shaft (keyways, flats);
- :mod:`~geometry.parts.testbench`: the 9 MW test bench's parts built from
  them (import it explicitly: ``from geometry.parts import testbench``).

The builders of the first two are re-exported here, so
``from geometry import parts; parts.stepped_shaft(...)`` works.
"""

from .features import flats, keyway
from .primitives import (
    BoltCircle,
    Segment,
    bolt_holes,
    check_bolt_pattern,
    coupling_hub,
    flange,
    flanged_shaft,
    fuse,
    polygon_shaft,
    spline_shaft,
    stepped_shaft,
)

__all__ = [
    "Segment",
    "BoltCircle",
    "stepped_shaft",
    "flanged_shaft",
    "flange",
    "bolt_holes",
    "check_bolt_pattern",
    "fuse",
    "keyway",
    "flats",
    "coupling_hub",
    "polygon_shaft",
    "spline_shaft",
]
