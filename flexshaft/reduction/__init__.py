"""Craig–Bampton reduction of part models into flexible bodies.

:func:`craig_bampton` of a 1D or a solid part model (interface DOFs + fixed-interface modes +
residual vectors, the orthonormalised free-free basis), :class:`ModalDamping` (damping per mode, per
band or Rayleigh), :func:`select_modes` (mode enable/disable) and :func:`cb_check` (rigid-body mass,
static exactness, effective mass), for both kinds of part.
"""

from .check import CBCheck, cb_check
from .craig_bampton import FlexibleBody, craig_bampton
from .modaldamping import ModalDamping
from .selection import ModalBody, select_modes

__all__ = [
    "FlexibleBody",
    "craig_bampton",
    "ModalDamping",
    "ModalBody",
    "select_modes",
    "CBCheck",
    "cb_check",
]
