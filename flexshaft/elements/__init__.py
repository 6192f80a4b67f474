"""Element matrices: pure functions of element properties, SI units."""

from .torsion import (
    torsion_consistent_inertia,
    torsion_lumped_inertia,
    torsion_stiffness,
)

__all__ = ["torsion_stiffness", "torsion_consistent_inertia", "torsion_lumped_inertia"]
