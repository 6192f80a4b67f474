"""The section table: the seam between geometry and mechanics.

:mod:`geometry` slices a solid into a :class:`SectionTable`; a shaft given by
its dimensions gets one from the closed forms here. Everything downstream
(stiffness, inertia, 1D elements) reads only this table. CSV files of tables
carry their units in every column name.
"""

from .table import (
    FORMAT_VERSION,
    AnnulusProperties,
    SectionSegment,
    SectionTable,
    annulus_properties,
    cowper_shear_factor,
    shear_definition_ratio,
    table_from_segments,
    tables_from_csv,
    tables_to_csv,
)

__all__ = [
    "SectionTable",
    "SectionSegment",
    "AnnulusProperties",
    "annulus_properties",
    "cowper_shear_factor",
    "shear_definition_ratio",
    "table_from_segments",
    "tables_to_csv",
    "tables_from_csv",
    "FORMAT_VERSION",
]
