"""Slicing a shaft solid or mesh along its axis into a :class:`~flexshaft.sections.SectionTable`."""

from .solid import MAX_OFFSET, MIN_FILL, SYMMETRY_TOL, AxisSpec, MassCheck, find_axis, sections

__all__ = ["AxisSpec", "MassCheck", "sections", "find_axis", "SYMMETRY_TOL", "MAX_OFFSET", "MIN_FILL"]
