"""Parametric shaft parts as build123d solids (SI metres in, one solid in millimetres out).

- :mod:`~geometry.parts.primitives`: the segment and bolt-circle data; turned
  bodies (stepped and flanged shafts, flanges, coupling hubs) with their bolt
  holes; fusing parts;
- :mod:`~geometry.parts.prismatic`: prismatic shafts (polygon, spline);
- :mod:`~geometry.parts.features`: cuts into a finished shaft (keyways, flats);
- :mod:`~geometry.parts.testbench`: the 9 MW test bench's parts built from
  them (import it explicitly: ``from geometry.parts import testbench``).

The builders of the first three are re-exported here, so
``from geometry import parts; parts.stepped_shaft(...)`` works.
"""

from . import features, primitives, prismatic
from .features import *  # noqa: F403 - the builders, listed once: in each module's __all__
from .primitives import *  # noqa: F403
from .prismatic import *  # noqa: F403

# the builders of the three modules (what `geometry.parts:NAME` in a model file may name)
__all__ = [*primitives.__all__, *prismatic.__all__, *features.__all__]
