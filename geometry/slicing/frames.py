"""The shaft's own frame: x along its axis, y and z across (plain numpy, no CAD import)."""

from __future__ import annotations

import numpy as np

__all__ = ["axis_frame"]


def axis_frame(direction) -> np.ndarray:
    """Rows: an orthonormal right-handed basis (x, y, z) whose x is ``direction``.

    Any unit vector normal to the axis serves as z; the coordinate axis most
    orthogonal to the direction gives a well-conditioned one, so a part drawn
    along a coordinate axis keeps the other two.
    """
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    helper = np.eye(3)[int(np.argmin(np.abs(d)))]
    z = np.cross(d, helper)
    z /= np.linalg.norm(z)
    return np.vstack([d, np.cross(z, d), z])
