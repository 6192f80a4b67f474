"""Element matrices: pure functions of element properties, SI units; the 10-node tetrahedron's
matrices assembled over a solid mesh (:mod:`.tet10`)."""

from .tet10 import SolidMatrices, solid_matrices
from .timoshenko import (
    timoshenko_consistent_mass,
    timoshenko_gyroscopic,
    timoshenko_lumped_mass,
    timoshenko_stiffness,
)
from .torsion import (
    torsion_consistent_inertia,
    torsion_lumped_inertia,
    torsion_stiffness,
)

__all__ = ["torsion_stiffness", "torsion_consistent_inertia", "torsion_lumped_inertia"]
__all__ += ["timoshenko_stiffness", "timoshenko_consistent_mass", "timoshenko_lumped_mass"]
__all__ += ["timoshenko_gyroscopic"]
__all__ += ["SolidMatrices", "solid_matrices"]
