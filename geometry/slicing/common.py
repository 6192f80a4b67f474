"""What the B-rep slicer and the mesh slicer share (plain numpy, no CAD import).

The shaft axis (:class:`AxisSpec`, :func:`axis_from_inertia`), the checks every
section must pass (:func:`check_one_piece`, :func:`check_section`), the
stations (:func:`merge_stations`, :func:`subdivide`), the columns a section
table is filled with (:class:`Columns`, :func:`warped`) and the mass check
against the body's own integrals (:class:`MassCheck`, :func:`axial_moment`,
:func:`with_mass_check`). Lengths are whatever the caller works in, except
where a docstring says SI.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from flexshaft.errors import ModelError
from flexshaft.sections import SectionTable, shear_definition_ratio

from .polygons import polygon_moments, roundness

__all__ = [
    "SliceOptions",
    "SYMMETRY_TOL",
    "MAX_OFFSET",
    "MIN_FILL",
    "COLUMNS",
    "AxisSpec",
    "MassCheck",
    "Columns",
    "axis_from_inertia",
    "check_one_piece",
    "check_section",
    "merge_stations",
    "subdivide",
    "warped",
    "axial_moment",
    "with_mass_check",
]

#: Two principal moments within this relative difference count as equal (an axis of symmetry).
SYMMETRY_TOL = 0.05
#: A section's centroid may sit at most this fraction of its outer radius off the axis.
MAX_OFFSET = 0.10
#: A section must fill at least this fraction of its circumscribed circle about the axis.
MIN_FILL = 0.60
#: The per-interval columns of a section table a slicer fills.
COLUMNS = ("area", "ip", "iy", "iz", "iyz", "j", "shear_area_y", "shear_area_z", "yc", "zc")


@dataclass(frozen=True)
class AxisSpec:
    """The shaft axis: a point on it and its direction (SI, m)."""

    origin: tuple[float, float, float]
    direction: tuple[float, float, float]
    found: bool = False

    @staticmethod
    def of(value: object, *, name: str = "part") -> AxisSpec:
        """Read an axis from ``AxisSpec``, ``(origin, direction)`` or a mapping with those keys."""
        if isinstance(value, AxisSpec):
            return value
        try:
            if isinstance(value, dict):
                unknown = set(value) - {"origin", "direction"}
                if unknown:
                    raise ModelError(
                        "unknown key",
                        component=name,
                        field=f"axis.{sorted(unknown)[0]}",
                        valid="origin (m), direction",
                    )
                origin, direction = value.get("origin", (0.0, 0.0, 0.0)), value["direction"]
            else:
                origin, direction = value
            o = np.asarray(origin, float).reshape(3)
            d = np.asarray(direction, float).reshape(3)
        except (KeyError, ValueError, TypeError):
            raise ModelError(
                "is not an axis",
                component=name,
                field="axis",
                value=value,
                has_value=True,
                valid="{origin = [x, y, z] (m), direction = [dx, dy, dz]}",
            ) from None
        if not (np.all(np.isfinite(o)) and np.all(np.isfinite(d))) or np.linalg.norm(d) == 0.0:
            raise ModelError(
                "needs a finite origin and a non-zero direction",
                component=name,
                field="axis",
                value=value,
                has_value=True,
                valid="finite numbers, direction not all zero",
            )
        d = d / np.linalg.norm(d)
        return AxisSpec(tuple(o.tolist()), tuple(d.tolist()))


@dataclass(frozen=True)
class SliceOptions:
    """How :func:`geometry.slicing.sections` slices, handed to the B-rep and the mesh slicer.

    Attributes are :func:`~geometry.slicing.sections`' arguments of the same names: the axis (None:
    found), Poisson's ratio, the part's name, the sub-intervals of a varying interval, the polygon
    resolution of the largest circle (B-rep only) and the progress callback.
    """

    axis: object = None
    nu: float = 0.29
    name: str = "part"
    taper_divisions: int = 6
    points_per_circle: int = 128
    progress: object = None


@dataclass(frozen=True)
class MassCheck:
    """The section table's integrals against the solid's own mass properties (SI).

    ``volume`` in m³ and ``axial_moment`` = ∫ r² dV about the shaft axis in m⁵
    (times the density it is the axial mass moment of inertia).
    """

    volume_table: float
    volume_solid: float
    axial_moment_table: float
    axial_moment_solid: float

    @property
    def volume_error(self) -> float:
        """Relative error of the table's volume (and mass)."""
        return self.volume_table / self.volume_solid - 1.0

    @property
    def axial_moment_error(self) -> float:
        """Relative error of the table's axial inertia."""
        return self.axial_moment_table / self.axial_moment_solid - 1.0


def axis_from_inertia(inertia: np.ndarray, centre: np.ndarray, *, name: str = "part") -> AxisSpec:
    """The symmetry axis from a centroidal ∫(r²·1 − r rᵀ) dV matrix (m⁵) and the centroid (m)."""
    w, v = np.linalg.eigh(inertia)
    rel = lambda a, b: abs(a - b) / max(a, b)  # noqa: E731
    d01, d12 = rel(w[0], w[1]), rel(w[1], w[2])
    moments = ", ".join(f"{m:.4g}" for m in w)
    if d01 <= SYMMETRY_TOL and d12 <= SYMMETRY_TOL:
        raise ModelError(
            f"has no preferred axis (principal moments {moments} m⁵ all about equal)",
            component=name,
            field="axis",
            valid="give the axis explicitly: {origin = [x, y, z] (m), direction = [dx, dy, dz]}",
        )
    if min(d01, d12) > SYMMETRY_TOL:
        raise ModelError(
            f"is not a shaft: no axis of near-rotational symmetry (principal moments {moments} m⁵)",
            component=name,
            field="geometry",
            valid=f"a straight shaft: two principal moments within {SYMMETRY_TOL:.0%}",
        )
    d = v[:, 2] if d01 < d12 else v[:, 0]
    # Keep a part drawn along +x (or +y, +z) pointing the way it was drawn.
    d = d if d[int(np.argmax(np.abs(d)))] > 0 else -d
    return AxisSpec(tuple(np.asarray(centre, float).tolist()), tuple(d.tolist()), found=True)


def check_one_piece(pieces: int, where: str, name: str) -> None:
    """Refuse a section that is empty or falls apart (``pieces`` connected regions, not one)."""
    if pieces != 1:
        what = "is empty" if not pieces else f"has {pieces} separate pieces"
        raise ModelError(
            f"is not a straight shaft: {where} {what}",
            component=name,
            field="geometry",
            valid="one connected section at every station along the axis",
        )


def check_section(exterior: np.ndarray, offset: float, where: str, name: str) -> None:
    """Refuse a section that is not near-round about the axis (a bent, eccentric or flat body).

    ``exterior`` is the outer ring in (y, z), m; ``offset`` the centroid's
    distance from the axis, m.
    """
    enclosed = abs(polygon_moments(exterior).area)
    r_max, fill = roundness(exterior, enclosed)
    if offset > MAX_OFFSET * r_max or fill < MIN_FILL:
        raise ModelError(
            f"is not a straight shaft about its axis: {where} has its centroid {offset:.4g} m "
            f"({offset / r_max:.0%} of its outer radius {r_max:.4g} m) off the axis and fills "
            f"{fill:.0%} of its circle",
            component=name,
            field="geometry",
            valid=f"a straight, near-axisymmetric shaft (centroid within {MAX_OFFSET:.0%} of the "
            f"radius, fill >= {MIN_FILL:.0%}); give `axis` if the found one is wrong",
        )


def merge_stations(xs: np.ndarray, tol: float) -> np.ndarray:
    """Sorted axial positions with every one closer than ``tol`` to the last one kept dropped."""
    keep = [xs[0]]
    for x in xs[1:]:
        if x - keep[-1] > tol:
            keep.append(x)
    return np.asarray(keep)


def subdivide(stations: np.ndarray, pieces) -> np.ndarray:
    """Slice stations: the breakpoints, with the interval after ``stations[i]`` cut into ``pieces[i]``."""
    xs = [stations[0]]
    for a, b, k in zip(stations[:-1], stations[1:], pieces):
        xs.extend(np.linspace(a, b, k + 1)[1:])
    return np.asarray(xs)


class Columns:
    """The columns of a section table (:data:`COLUMNS`, SI) and its methods, filled interval by interval."""

    def __init__(self, n: int) -> None:
        self.values = {c: np.empty(n) for c in COLUMNS}
        self.method: list[str] = []

    def set(self, i: int, method: str, values: dict[str, float]) -> None:
        """Interval ``i``'s values (every column) and how they were found."""
        self.method.append(method)
        for c, v in values.items():
            self.values[c][i] = v

    def table(self, x: np.ndarray, *, nu: float, name: str) -> SectionTable:
        """The section table of these columns at stations ``x`` (m)."""
        return SectionTable(x=x, method=tuple(self.method), nu=nu, name=name, **self.values)


def warped(polygon, *, nu: float, area: float, ip_axis: float) -> dict[str, float]:
    """J and shear areas (Cowper's definition) of a section from the warping analysis of its polygon.

    ``polygon`` is a shapely polygon in m about the axis; the result is scaled
    to the section's exact ``area`` (m²) and polar moment ``ip_axis`` (m⁴),
    which removes the polygon's faceting error to first order
    (:func:`geometry.slicing.warping.corrected`).
    """
    from .warping import corrected, warping_properties  # sectionproperties only when needed

    w = corrected(warping_properties(polygon, nu=nu), area, ip_axis)
    to_cowper = shear_definition_ratio(nu)
    return dict(j=w.j, shear_area_y=w.shear_area_y * to_cowper, shear_area_z=w.shear_area_z * to_cowper)


def axial_moment(volume, centre, inertia):
    """∫ r² dV about the x axis: the centroidal matrix's xx term plus the parallel-axis shift (any units)."""
    return inertia[0, 0] + volume * (centre[1] ** 2 + centre[2] ** 2)


def with_mass_check(
    table: SectionTable, *, volume_solid: float, axial_moment_solid: float, axis: AxisSpec, source: str
) -> SectionTable:
    """The table with its ``meta``: ``mass_check``, ``axis`` and ``source``.

    ``mass_check`` is a :class:`MassCheck` of the table against the body's own
    volume (m³) and ∫ r² dV about the axis (m⁵); ``axis`` the axis used;
    ``source`` where the sections came from (``"brep"``, ``"mesh"``).
    """
    check = MassCheck(
        volume_table=table.volume,
        volume_solid=volume_solid,
        axial_moment_table=float(np.dot(table.ip, table.lengths)),
        axial_moment_solid=axial_moment_solid,
    )
    return replace(table, meta={"mass_check": check, "axis": axis, "source": source})
