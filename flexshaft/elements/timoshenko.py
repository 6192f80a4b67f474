"""The 2-node, 12-DOF Timoshenko beam element along x (shear-deformable, locking-free).

DOFs per node are ordered (ux, uy, uz, θx, θy, θz), element DOFs node 1 then
node 2; θx is torsion, rotations follow the right-hand rule about the axes,
so for a slender beam θz = +duy/dx and θy = −duz/dx.

The element is the interdependent-interpolation ("exact static") element of
J. S. Przemieniecki, *Theory of Matrix Structural Analysis*, McGraw-Hill
(1968), and Z. Friedman, J. B. Kosmatka, "An improved
two-node Timoshenko beam finite element", Computers & Structures 47 (1993)
473-481. The transverse displacement is cubic and the section rotation
quadratic, coupled so that the homogeneous static Timoshenko equations hold
exactly inside the element. It is therefore

- exact in statics for end loads, whatever the length of the element,
- free of shear locking (as κGA → ∞ it becomes the Hermite-cubic
  Euler–Bernoulli element), and
- given a mass matrix consistent with the same shape functions
  (translational and rotary inertia).

Per bending plane the shear parameter is Φ = 12 E I / (G·κA·L²), with κA the
shear area of the table: the x–y plane (uy, θz) bends about z, so it uses Iz
and the shear area for shear along y; the x–z plane (uz, θy) uses Iy and the
shear area along z. Axial (EA/L) and torsion (GJ/L, inertia ρ·Ip·L) are the
linear two-node bars of :mod:`flexshaft.elements.torsion`.

Assumptions: y and z are principal axes through the centroid, which lies on
the shaft axis; the product moment Iyz and the centroid offset (yc, zc) of a
section table are not used (an off-centre or unsymmetric section couples
the planes, which this element leaves out). No shear-centre terms. The
gyroscopic matrix of the spinning element is :func:`timoshenko_gyroscopic`.

All functions are vectorised: their arguments broadcast against each other
and the result has shape ``broadcast_shape + (12, 12)``; scalars give
``(12, 12)``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "timoshenko_stiffness",
    "timoshenko_consistent_mass",
    "timoshenko_lumped_mass",
    "timoshenko_gyroscopic",
]

#: Element DOFs of the axial bar, the torsion bar and the two bending planes.
_AXIAL = np.array([0, 6])
_TORSION = np.array([3, 9])
_XY = np.array([1, 5, 7, 11])  # uy1, θz1, uy2, θz2
_XZ = np.array([2, 4, 8, 10])  # uz1, θy1, uz2, θy2
# The x–z plane is the x–y plane with θ → −θ (θy = −duz/dx where θz = +duy/dx).
_XZ_SIGN = np.array([1.0, -1.0, 1.0, -1.0])
_XZ_FLIP = _XZ_SIGN[:, None] * _XZ_SIGN[None, :]

_BAR_K = np.array([[1.0, -1.0], [-1.0, 1.0]])
_BAR_M = np.array([[1.0 / 3.0, 1.0 / 6.0], [1.0 / 6.0, 1.0 / 3.0]])


def _arrays(*values) -> list[np.ndarray]:
    return list(np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in values)))


def _sym4(upper: dict[tuple[int, int], np.ndarray], shape: tuple[int, ...]) -> np.ndarray:
    """A symmetric (..., 4, 4) array from its upper-triangle entries."""
    out = np.empty(shape + (4, 4))
    for (i, j), v in upper.items():
        out[..., i, j] = v
        out[..., j, i] = v
    return out


def _phi(E, I, G, As, L):
    """Shear parameter Φ = 12 E I / (G κA L²), dimensionless (0 for an infinite shear area)."""
    return 12.0 * E * I / (G * As * L**2)


def _bending_stiffness(EI, phi, L) -> np.ndarray:
    """x–y plane stiffness on (v1, θ1, v2, θ2), N/m, N, N·m/rad (Friedman & Kosmatka 1993)."""
    c = EI / ((1.0 + phi) * L**3)
    L2 = L**2
    k = {
        (0, 0): 12.0 * c,
        (0, 1): 6.0 * L * c,
        (0, 2): -12.0 * c,
        (0, 3): 6.0 * L * c,
        (1, 1): (4.0 + phi) * L2 * c,
        (1, 2): -6.0 * L * c,
        (1, 3): (2.0 - phi) * L2 * c,
        (2, 2): 12.0 * c,
        (2, 3): -6.0 * L * c,
        (3, 3): (4.0 + phi) * L2 * c,
    }
    return _sym4(k, np.shape(c))


def _bending_mass(rhoA, rhoI, phi, L) -> np.ndarray:
    """x–y plane consistent mass on (v1, θ1, v2, θ2), kg, kg·m, kg·m² (Friedman & Kosmatka 1993).

    Translational part ∫ρA NvᵀNv dx plus rotary part ∫ρI NψᵀNψ dx of the
    interdependent shape functions.
    """
    p, p2 = phi, phi**2
    t = rhoA * L / (210.0 * (1.0 + p) ** 2)
    r = rhoI / (30.0 * (1.0 + p) ** 2 * L)
    L2 = L**2
    a = 70.0 * p2 + 147.0 * p + 78.0
    b = (35.0 * p2 + 77.0 * p + 44.0) * L / 4.0
    c = 35.0 * p2 + 63.0 * p + 27.0
    d = (35.0 * p2 + 63.0 * p + 26.0) * L / 4.0
    e = (7.0 * p2 + 14.0 * p + 8.0) * L2 / 4.0
    f = (7.0 * p2 + 14.0 * p + 6.0) * L2 / 4.0
    g = (3.0 - 15.0 * p) * L
    h = (10.0 * p2 + 5.0 * p + 4.0) * L2
    q = (5.0 * p2 - 5.0 * p - 1.0) * L2
    m = {
        (0, 0): t * a + r * 36.0,
        (0, 1): t * b + r * g,
        (0, 2): t * c - r * 36.0,
        (0, 3): -t * d + r * g,
        (1, 1): t * e + r * h,
        (1, 2): t * d - r * g,
        (1, 3): -t * f + r * q,
        (2, 2): t * a + r * 36.0,
        (2, 3): -t * b - r * g,
        (3, 3): t * e + r * h,
    }
    return _sym4(m, np.shape(t))


def _place(out: np.ndarray, dofs: np.ndarray, block: np.ndarray) -> None:
    out[..., dofs[:, None], dofs[None, :]] = block


def timoshenko_stiffness(*, L, E, G, A, Iy, Iz, J, Asy, Asz) -> np.ndarray:
    """Element stiffness matrix of the 12-DOF Timoshenko beam.

    Parameters
    ----------
    L : float or array_like
        Element length, m.
    E, G : float or array_like
        Young's and shear modulus, Pa.
    A : float or array_like
        Cross-section area, m² (axial stiffness E·A/L).
    Iy, Iz : float or array_like
        Second moments of area about the y and z axes, m⁴.
    J : float or array_like
        St-Venant torsion constant, m⁴ (torsional stiffness G·J/L).
    Asy, Asz : float or array_like
        Shear areas κ·A for shear along y (x–y plane) and along z (x–z
        plane), m²; ``np.inf`` gives the Euler–Bernoulli element.

    Returns
    -------
    ndarray, shape (..., 12, 12)
        Symmetric, positive semi-definite with the six rigid-body motions as
        its null space; N/m, N, N·m/rad by DOF pair.
    """
    L, E, G, A, Iy, Iz, J, Asy, Asz = _arrays(L, E, G, A, Iy, Iz, J, Asy, Asz)
    out = np.zeros(L.shape + (12, 12))
    _place(out, _AXIAL, (E * A / L)[..., None, None] * _BAR_K)
    _place(out, _TORSION, (G * J / L)[..., None, None] * _BAR_K)
    _place(out, _XY, _bending_stiffness(E * Iz, _phi(E, Iz, G, Asy, L), L))
    _place(out, _XZ, _bending_stiffness(E * Iy, _phi(E, Iy, G, Asz, L), L) * _XZ_FLIP)
    return out


def timoshenko_consistent_mass(*, L, E, G, rho, A, Iy, Iz, Ip, Asy, Asz, rotary_inertia=True) -> np.ndarray:
    """Consistent mass matrix of the 12-DOF Timoshenko beam.

    Built from the same interdependent shape functions as the stiffness, so it
    depends on the shear parameters Φ (hence on E, G and the shear areas).

    Parameters
    ----------
    L : float or array_like
        Element length, m.
    E, G : float or array_like
        Young's and shear modulus, Pa (for Φ only).
    rho : float or array_like
        Density, kg/m³.
    A : float or array_like
        Cross-section area, m² (mass ρ·A·L).
    Iy, Iz : float or array_like
        Second moments of area about y and z, m⁴ (rotary inertia ρ·I per
        length, and Φ).
    Ip : float or array_like
        Polar second moment of area, m⁴ (axial inertia ρ·Ip·L).
    Asy, Asz : float or array_like
        Shear areas along y and z, m².
    rotary_inertia : bool
        Include the rotary inertia of the sections in bending (ρ·Iy, ρ·Iz);
        ``False`` gives the Rayleigh-free (Euler–Bernoulli-type) mass. The
        polar inertia of torsion is always kept.

    Returns
    -------
    ndarray, shape (..., 12, 12)
        Symmetric positive definite; kg, kg·m, kg·m² by DOF pair. A rigid
        translation of unit speed carries the element mass ρ·A·L, a rigid
        spin about x the inertia ρ·Ip·L.
    """
    L, E, G, rho, A, Iy, Iz, Ip, Asy, Asz = _arrays(L, E, G, rho, A, Iy, Iz, Ip, Asy, Asz)
    out = np.zeros(L.shape + (12, 12))
    rot = 1.0 if rotary_inertia else 0.0
    _place(out, _AXIAL, (rho * A * L)[..., None, None] * _BAR_M)
    _place(out, _TORSION, (rho * Ip * L)[..., None, None] * _BAR_M)
    _place(out, _XY, _bending_mass(rho * A, rot * rho * Iz, _phi(E, Iz, G, Asy, L), L))
    _place(out, _XZ, _bending_mass(rho * A, rot * rho * Iy, _phi(E, Iy, G, Asz, L), L) * _XZ_FLIP)
    return out


def timoshenko_lumped_mass(*, L, rho, A, Iy, Iz, Ip) -> np.ndarray:
    """Lumped (diagonal) mass matrix: half the element's mass and inertias on each node.

    Parameters
    ----------
    L : float or array_like
        Element length, m.
    rho : float or array_like
        Density, kg/m³.
    A : float or array_like
        Cross-section area, m²: ρ·A·L/2 on ux, uy, uz of each node.
    Iy, Iz : float or array_like
        Second moments of area about y and z, m⁴: ρ·Iy·L/2 on θy and ρ·Iz·L/2
        on θz (the sections' rotary inertia; the slice's own ρ·A·L³/12 is not
        added, so the limit of many elements is the Timoshenko beam's).
    Ip : float or array_like
        Polar second moment of area, m⁴: ρ·Ip·L/2 on θx, as the torsion
        element's lumped inertia.

    Returns
    -------
    ndarray, shape (..., 12, 12)
        Diagonal; kg on translations, kg·m² on rotations.
    """
    L, rho, A, Iy, Iz, Ip = _arrays(L, rho, A, Iy, Iz, Ip)
    half = 0.5 * rho * L
    m, jx, jy, jz = half * A, half * Ip, half * Iy, half * Iz
    diag = np.stack([m, m, m, jx, jy, jz] * 2, axis=-1)
    out = np.zeros(L.shape + (12, 12))
    i = np.arange(12)
    out[..., i, i] = diag
    return out


def timoshenko_gyroscopic(*, L, E, G, rho, Iy, Iz, Ip, Asy, Asz) -> np.ndarray:
    """Gyroscopic matrix of the 12-DOF Timoshenko beam spinning about x, per rad/s of spin.

    A slice spinning at Ω with small tilts (θy, θz) carries the angular momentum ρ·Ip·Ω about x,
    which the tilt rates turn: the forces are −Ω·G·q̇ with G skew-symmetric, coupling the rotation
    fields of the two bending planes through the rotary inertia's shape functions,
    ``G = ρ·Ip·∫(ψzᵀψy − ψyᵀψz) dx`` (ψz = N·(uy, θz), ψy = −N·(uz, −θy) per the sign convention
    above). The interdependent shape functions are those of the mass matrix; with different shear
    parameters in the two planes (a section that is not axisymmetric) their mean is used.

    Parameters
    ----------
    L, E, G, rho, Iy, Iz, Asy, Asz
        As for :func:`timoshenko_consistent_mass` (E, G and the shear areas for Φ only).
    Ip : float or array_like
        Polar second moment of area, m⁴ (ρ·Ip per length is the spinning inertia).

    Returns
    -------
    ndarray, shape (..., 12, 12)
        Skew-symmetric, kg·m² by DOF pair (N·m·s/rad per rad/s of spin); only the (uy, θz) ×
        (uz, θy) blocks are non-zero.
    """
    L, E, G, rho, Iy, Iz, Ip, Asy, Asz = _arrays(L, E, G, rho, Iy, Iz, Ip, Asy, Asz)
    zero = np.zeros_like(L)
    # ∫ψᵀψ dx per unit ρI: the rotary part of the bending mass, on (v1, θ1, v2, θ2) of the x–y plane.
    R = 0.5 * (
        _bending_mass(zero, np.ones_like(L), _phi(E, Iz, G, Asy, L), L)
        + _bending_mass(zero, np.ones_like(L), _phi(E, Iy, G, Asz, L), L)
    )
    # The x–z plane's coordinates (uz, −θy) play the x–y plane's (uy, θz): ψy = −N·S·q_xz, S = _XZ_SIGN.
    block = (rho * Ip)[..., None, None] * (-R * _XZ_SIGN[None, :])  # rows x–y DOFs, columns x–z DOFs
    out = np.zeros(L.shape + (12, 12))
    out[..., _XY[:, None], _XZ[None, :]] = block
    out[..., _XZ[:, None], _XY[None, :]] = -np.swapaxes(block, -1, -2)
    return out
