"""Exact area moments of polygonal sections (shapely polygons in the y–z plane).

Used for mesh (STL) sections, which are polygons exactly, and to measure how
far a polygonised CAD section is from the exact one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PolygonMoments", "ring_moments", "polygon_moments", "roundness"]


@dataclass(frozen=True)
class PolygonMoments:
    """Area, centroid and centroidal second moments of a plane section (units of its coordinates).

    Also what :func:`geometry.slicing.brep.face_props` returns for an exact B-rep face.
    """

    area: float
    yc: float
    zc: float
    iy: float
    iz: float
    iyz: float

    @property
    def ip_axis(self) -> float:
        """Polar moment about the origin (the shaft axis)."""
        return self.iy + self.iz + self.area * (self.yc**2 + self.zc**2)


def ring_moments(ring: np.ndarray) -> np.ndarray:
    """Signed [A, ∫y, ∫z, ∫y², ∫z², ∫yz] of a closed ring (counter-clockwise positive).

    Green's theorem on each edge; exact for straight-sided polygons.
    """
    y, z = np.asarray(ring, float).T
    y1, z1 = np.roll(y, -1), np.roll(z, -1)
    cross = y * z1 - y1 * z
    return np.array(
        [
            cross.sum() / 2.0,
            ((y + y1) * cross).sum() / 6.0,
            ((z + z1) * cross).sum() / 6.0,
            ((y * y + y * y1 + y1 * y1) * cross).sum() / 12.0,
            ((z * z + z * z1 + z1 * z1) * cross).sum() / 12.0,
            ((y * z1 + 2 * y * z + 2 * y1 * z1 + y1 * z) * cross).sum() / 24.0,
        ]
    )


def polygon_moments(exterior: np.ndarray, holes: list[np.ndarray] = ()) -> PolygonMoments:
    """Moments of a polygon given as an exterior ring and hole rings (any orientation)."""
    total = _oriented(exterior, +1)
    for h in holes:
        total = total - _oriented(h, +1)
    a, sy, sz, qyy, qzz, qyz = total  # ∫y, ∫z, ∫y², ∫z², ∫yz
    yc, zc = sy / a, sz / a
    # iy bends about y, so it integrates z²; parallel-axis shift to the centroid.
    return PolygonMoments(area=a, yc=yc, zc=zc, iy=qzz - a * zc**2, iz=qyy - a * yc**2, iyz=qyz - a * yc * zc)


def _oriented(ring: np.ndarray, sign: int) -> np.ndarray:
    m = ring_moments(ring)
    return m if np.sign(m[0]) == sign else -m


def roundness(exterior: np.ndarray, area_enclosed: float) -> tuple[float, float]:
    """(r_max, fill): the farthest exterior point from the axis and area / (π r_max²)."""
    r_max = float(np.max(np.hypot(exterior[:, 0], exterior[:, 1])))
    return r_max, area_enclosed / (np.pi * r_max**2)
