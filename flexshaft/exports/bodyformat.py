"""What every flexible-body file carries: format, version, units, DOF order, material, checksums.

Shared by the writers and readers of every format (:mod:`flexshaft.exports.bodies`,
:mod:`flexshaft.exports.dmig`), so that each checks the same things.

Integrity (format version 2). Every file carries SHA-256 checksums the reader
requires - a missing, malformed or different one is refused, never skipped:

- ``.npz``, ``.json``, ``.mat`` (self-contained): ``body_sha256`` in the
  metadata, over the canonical metadata without that key followed by every
  array (:func:`body_sha256`).
- ``.op4``, ``.pch`` and their ``.json`` sidecar: ``data_sha256`` in the
  sidecar over the Nastran file's text (UTF-8), and ``sidecar_sha256`` over the
  canonical sidecar without that key (:func:`sidecar_sha256`).

"Canonical" is :func:`canonical_json`: keys sorted, ASCII, no blanks - the
same bytes for the same document whatever wrote it. A checksum finds a
damaged, hand-edited or half-replaced file; it is not a signature (anyone can
compute one), so every file is also checked for physics (:func:`check_physics`):
what a checksum cannot vouch for, a body that cannot be, is refused too.
"""

from __future__ import annotations

import hashlib
import json
import re

import numpy as np

from ..errors import ModelError
from ..parts.model import DOF_NAMES
from ..reduction.craig_bampton import FlexibleBody

__all__ = [
    "FORMAT",
    "VERSION",
    "UNITS",
    "MAX_ENTRIES",
    "BODY_SHA256",
    "DATA_SHA256",
    "SIDECAR_SHA256",
    "RIGID_MODES",
    "dof_order",
    "metadata",
    "check_metadata",
    "check_body",
    "check_physics",
    "canonical_json",
    "body_sha256",
    "sidecar_sha256",
    "text_sha256",
    "check_sha256",
]

FORMAT = "flexshaft-flexible-body"
#: 2: checksums required (``body_sha256``; ``data_sha256`` and ``sidecar_sha256`` in a sidecar).
#: Version 1 files carry none (or only ``data_sha256``) and are refused: re-export them.
VERSION = 2
#: The unit of every quantity in an exported flexible body.
UNITS = {
    "length": "m",
    "angle": "rad",
    "mass": "kg",
    "time": "s",
    "frequency": "Hz",
    "K": "N/m, N/rad, N·m/m, N·m/rad (by DOF pair)",
    "M": "kg, kg·m, kg·m² (by DOF pair)",
    "C": "N·s/m, N·m·s/rad (by DOF pair)",
    "damping_ratios": "fraction",
}


def dof_order(body: FlexibleBody) -> list[str]:
    """Names of the reduced coordinates: boundary DOFs (node-major), then the modal coordinates."""
    names = [f"node {n} {d}" for n in body.boundary_nodes for d in DOF_NAMES[body.dofs]]
    n_fixed = body.n_modes - body.n_residual
    return (
        names
        + [f"mode {k + 1}" for k in range(n_fixed)]
        + [f"residual {k + 1}" for k in range(body.n_residual)]
    )


def metadata(body: FlexibleBody, material) -> dict:
    """The metadata every export carries: format, version, units, name, DOFs, material."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "units": UNITS,
        "name": body.name,
        "dofs": body.dofs,
        "dof_order": dof_order(body),
        "residual_vectors": body.n_residual,
        "material": None
        if material is None
        else {"name": material.name, "E": material.E, "nu": material.nu, "rho": material.rho},
    }


def check_metadata(meta: dict, source: str) -> None:
    """Refuse metadata that is not a flexshaft flexible body of this version in SI units, naming both."""

    def refuse(what: str, field: str, value, valid: str) -> ModelError:
        return ModelError(what, file=source, field=field, value=value, has_value=True, valid=valid)

    if meta.get("format") != FORMAT:
        raise refuse("is not a flexshaft flexible body", "format", meta.get("format"), repr(FORMAT))
    if meta.get("version") == 1:
        raise ModelError(
            "was written by an earlier flexshaft (format version 1), whose files carry no checksums "
            "and are not read",
            file=source,
            field="version",
            value=1,
            valid=f"a version {VERSION} file: export the part again with `flexshaft reduce`",
        )
    if meta.get("version") != VERSION:
        raise refuse("unsupported version", "version", meta.get("version"), str(VERSION))
    units = meta.get("units", {})
    for key, unit in UNITS.items():
        if units.get(key) != unit:
            raise refuse(
                f"the file's {key} unit is {units.get(key)!r}, flexshaft's is {unit!r}",
                f"units.{key}",
                units.get(key),
                repr(unit),
            )


#: Most entries one matrix of a body file may claim (T of a 20 000-element 6-DOF part reduced to 34
#: coordinates has 4e6; 5e7 doubles are 400 MB). A header claiming more is refused before anything
#: is allocated.
MAX_ENTRIES = 50_000_000


def _bad(source: str, field: str, what: str, valid: str, value=None) -> ModelError:
    return ModelError(what, file=source, field=field, value=value, has_value=value is not None, valid=valid)


def check_body(arrays: dict, meta: dict, source: str, *, rounding: float = 0.0) -> None:
    """Refuse a body whose metadata or arrays do not fit together, before it is used.

    Types and sizes of the metadata; every array finite and of the shape the
    DOF order implies; frequencies >= 0; damping ratios in [0, 1); then the
    physics (:func:`check_physics`; ``rounding`` is the relative rounding of
    the file's K, M, C entries, 0 for doubles).
    """
    if not isinstance(meta.get("name"), str):
        raise _bad(source, "name", "must be a string", "the part's name", meta.get("name"))
    if meta.get("dofs") not in DOF_NAMES:
        raise _bad(source, "dofs", "unknown DOF set", "'torsion' or 'full'", meta.get("dofs"))
    order = meta.get("dof_order")
    if not isinstance(order, list) or not all(isinstance(x, str) for x in order):
        raise _bad(source, "dof_order", "must be a list of names", "one name per reduced coordinate")
    n_res = meta.get("residual_vectors", 0)
    if isinstance(n_res, bool) or not isinstance(n_res, int) or n_res < 0:
        raise _bad(source, "residual_vectors", "must be a whole number >= 0", "an integer >= 0", n_res)
    mat = meta.get("material")
    if mat is not None and not (
        isinstance(mat, dict)
        and isinstance(mat.get("name"), str)
        and all(isinstance(mat.get(k), int | float) and np.isfinite(mat.get(k)) for k in ("E", "nu", "rho"))
    ):
        raise _bad(source, "material", "must be {name, E, nu, rho}", "null or a material with finite numbers")
    d = len(DOF_NAMES[meta["dofs"]])
    n = len(order)
    for key, a in arrays.items():
        if not isinstance(a, np.ndarray) or a.dtype.kind not in "fiu":
            raise _bad(source, key, "is not a numeric array", "numbers")
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            raise _bad(source, key, "has non-finite values", "finite numbers")
    nodes = arrays["boundary_nodes"]
    nb = nodes.size * d
    shapes = {
        "boundary_nodes": (nodes.size,),
        "boundary_x": (nodes.size,),
        "K": (n, n),
        "M": (n, n),
        "C": (n, n),
        "fixed_interface_hz": (n - nb,),
        "free_hz": (n,),
        "free_modes": (n, n),
        "damping_ratios": (n,),
    }
    for key, shape in shapes.items():
        if arrays[key].shape != shape:
            raise _bad(source, key, f"has shape {arrays[key].shape}", f"{shape} for {n} coordinates", None)
    T = arrays["T"]
    if T.ndim != 2 or T.shape[1] != n or T.shape[0] % d or T.shape[0] < nb:
        raise _bad(source, "T", f"has shape {T.shape}", f"(a multiple of {d} rows, {n} columns)")
    if n_res > n - nb:
        raise _bad(source, "residual_vectors", f"is more than the {n - nb} modal coordinates", "fewer", n_res)
    if np.any(nodes < 0) or np.any(nodes >= T.shape[0] // d) or np.unique(nodes).size != nodes.size:
        valid = f"distinct nodes 0 … {T.shape[0] // d - 1}"
        raise _bad(source, "boundary_nodes", "are not distinct nodes of the mesh", valid)
    for key in ("fixed_interface_hz", "free_hz"):
        if np.any(arrays[key] < 0):
            raise _bad(source, key, "has negative frequencies", "frequencies >= 0 (Hz)")
    z = arrays["damping_ratios"]
    if np.any((z < 0) | (z >= 1)):
        raise _bad(source, "damping_ratios", "has ratios outside [0, 1)", "fractions in [0, 1)")
    check_physics(arrays, meta, source, rounding=rounding)


# --- checksums --------------------------------------------------------------------------------

#: Metadata key of a self-contained file's checksum (npz, json, mat).
BODY_SHA256 = "body_sha256"
#: Sidecar key: the SHA-256 of its Nastran file's text. A pair left half-replaced by a killed write
#: (new sidecar, old matrices), or an edited matrix, is refused instead of read.
DATA_SHA256 = "data_sha256"
#: Sidecar key: the SHA-256 of the sidecar itself (canonical, without this key).
SIDECAR_SHA256 = "sidecar_sha256"
_HEX64 = re.compile(r"[0-9a-f]{64}")
_AGAIN = "the checksum flexshaft wrote: export the part again (`flexshaft reduce MODEL --part NAME -o FILE`)"


def canonical_json(doc) -> bytes:
    """The bytes a checksum covers: JSON with sorted keys, ASCII only, no blanks.

    Floats print as Python's shortest round-trip form, so a document read back
    from a JSON file gives the same bytes as the one that was written.
    """
    return json.dumps(doc, sort_keys=True, ensure_ascii=True, separators=(",", ":")).encode("ascii")


def body_sha256(meta: dict, arrays: dict) -> str:
    """SHA-256 of a self-contained body: canonical metadata (without ``body_sha256``), then each array.

    Arrays in name order, each as ``["name", [shape]]`` (canonical JSON) and
    its values as little-endian int64 (integer arrays) or float64 (the rest),
    C order - the same digest whichever format holds the numbers.
    """
    h = hashlib.sha256(canonical_json({k: v for k, v in meta.items() if k != BODY_SHA256}))
    for name in sorted(arrays):
        a = np.asarray(arrays[name])
        a = np.ascontiguousarray(a, dtype="<i8" if a.dtype.kind in "iu" else "<f8")
        h.update(canonical_json([name, list(a.shape)]))
        h.update(a.tobytes())
    return h.hexdigest()


def sidecar_sha256(doc: dict) -> str:
    """SHA-256 of a sidecar document: canonical, without its ``sidecar_sha256``."""
    return hashlib.sha256(canonical_json({k: v for k, v in doc.items() if k != SIDECAR_SHA256})).hexdigest()


def text_sha256(text: str) -> str:
    """SHA-256 of a Nastran file's text, as UTF-8."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def check_sha256(doc: dict, key: str, actual: str, source: str, *, mismatch: str) -> None:
    """Refuse a checksum ``doc[key]`` that is missing, malformed, or not ``actual`` (the content's).

    Parameters
    ----------
    doc : dict
        The metadata or sidecar holding the checksum.
    key : str
        Its key (:data:`BODY_SHA256`, :data:`DATA_SHA256`, :data:`SIDECAR_SHA256`).
    actual : str
        The SHA-256 of the content, as computed on reading.
    source : str
        The file named in the error.
    mismatch : str
        What a different checksum means, for the message.
    """
    if key not in doc:
        raise ModelError(
            "is missing: the file carries no checksum (written by flexshaft before checksums were "
            "required, or edited)",
            file=source,
            field=key,
            valid=_AGAIN,
        )
    given = doc[key]
    if not isinstance(given, str) or not _HEX64.fullmatch(given):
        shown = given if isinstance(given, str) else json.dumps(given, ensure_ascii=False, default=str)
        shown = shown[:20] + "…" if len(shown) > 20 else shown
        raise ModelError(
            "is not a SHA-256 (64 lower-case hex digits)",
            file=source,
            field=key,
            value=shown,
            has_value=True,
            valid=_AGAIN,
        )
    if given != actual:
        shown = given[:12] + "…"
        raise ModelError(mismatch, file=source, field=key, value=shown, has_value=True, valid=_AGAIN)


# --- physics ----------------------------------------------------------------------------------

#: Rigid-body modes of a free flexible body by DOF set, and what they are.
RIGID_MODES = {"torsion": 1, "full": 6}
_RIGID_WHAT = {
    "torsion": "its free rotation about the axis",
    "full": "three translations and three rotations",
}
#: An eigenvalue of (K, M) within this fraction of the largest (or of 1 (rad/s)²) is a rigid-body mode:
#: craig_bampton's own rule for writing a mode as 0 Hz, so a body reads back with the modes it was
#: written with. On the examples' parts (torsion and 6-DOF, 0 to 60 modes, through a DMIG punch too)
#: the reduction leaves its rigid modes at 2e-12 of the largest or less and its lowest elastic mode
#: above 8e-7: the threshold sits between, over two decades from each.
RIGID_FRACTION = 1e-9
_EPS = float(np.finfo(float).eps)
# Each of the two eigen-solves whose results are compared (the writer's, the reader's) is backward
# stable to about n·eps of ‖K‖, ‖M‖; twice that again for a first-order estimate.
_SOLVES = 4.0
_UNIT = {
    "torsion": {"K": "N·m/rad", "M": "kg·m²", "C": "N·m·s/rad"},
    "full": {
        "K": "(N/m … N·m/rad by DOF pair)",
        "M": "(kg … kg·m² by DOF pair)",
        "C": "(N·s/m … N·m·s/rad by DOF pair)",
    },
}


def check_physics(arrays: dict, meta: dict, source: str, *, rounding: float = 0.0) -> None:
    """Refuse a body that cannot be a free flexible body: what a checksum cannot vouch for.

    - K, M, C symmetric to round-off: ``16·N·eps`` of their largest entry (N
      the longer of the mesh's and the body's DOF counts: a reduced matrix is
      sums of N products), plus the file's own rounding.
    - M positive definite: every eigenvalue above ``16·n·eps`` of the largest.
    - K positive semidefinite with exactly :data:`RIGID_MODES` rigid-body
      modes (1 torsion, 6 full): the eigenvalues λ of K φ = λ M φ, none below
      ``-max(RIGID_FRACTION·scale, tolᵢ)``, exactly that many within it
      (scale: the largest ``|λ|``, at least 1 (rad/s)²).
    - C positive semidefinite: the eigenvalues of (C, M), none below
      ``-max(RIGID_FRACTION, 4·(rounding + n·eps))`` of the largest in size.
    - ``free_hz`` the frequencies of (K, M), mode by mode: a 0 Hz entry where λ
      is rigid, else ``|λᵢ - (2π fᵢ)²| <= tolᵢ`` with the first-order
      perturbation bound of λᵢ (conditioning of that eigenvalue)::

          tolᵢ = 4·[rounding·(|φᵢ|ᵀ|K||φᵢ| + λᵢ|φᵢ|ᵀ|M||φᵢ|) + n·eps·(‖K‖₂ + λᵢ‖M‖₂)·‖φᵢ‖₂²]

      φᵢ mass-normalised. On the examples' bodies the stored frequencies lie
      within 0.05 of that (npz/json/mat/op4) or 0.001 (pch); it is 7e-7 of λ
      or less on their elastic modes (3e-5 through a punch).

    Parameters
    ----------
    arrays, meta : dict
        The body, its shapes already checked (:func:`check_body`).
    source : str
        The file, for messages.
    rounding : float
        Relative rounding of the file's K, M, C entries: 0 for doubles, 5e-9
        for a DMIG punch (at least 9 significant digits).
    """
    dofs = meta["dofs"]
    K, M, C = (np.asarray(arrays[k], dtype=float) for k in ("K", "M", "C"))
    n = K.shape[0]
    if n == 0:
        raise _bad(source, "dof_order", "is empty", "a body's interface DOFs and modes")
    rows = max(n, int(np.shape(arrays["T"])[0]))
    import scipy.linalg as la

    # Numbers near the ends of double precision overflow in these products: an error of the file's,
    # said as one, never a RuntimeWarning beside a result.
    try:
        with np.errstate(over="raise", invalid="raise", divide="raise", under="ignore"):
            for key, A in (("K", K), ("M", M), ("C", C)):
                _check_symmetric(A, key, (16 * rows * _EPS + rounding), source)
            mu = _positive_mass(M, n, dofs, source)
            lam, phi = la.eigh(K, M, check_finite=False)
            tol = _eigenvalue_tolerances(K, M, lam, phi, rounding, float(mu[-1]))
            scale = max(float(np.max(np.abs(lam))), 1.0)
            zero = np.maximum(RIGID_FRACTION * scale, tol)
            _check_stiffness(K, lam, zero, dofs, source)
            _check_damping(C, M, n, rounding, dofs, source)
            _check_frequencies(arrays["free_hz"], lam, tol, zero, rounding, source)
    except (FloatingPointError, np.linalg.LinAlgError, la.LinAlgError) as err:
        raise _bad(
            source,
            "K, M, C",
            f"cannot be checked in double precision ({type(err).__name__}: {err})",
            "the matrices of a body: entries well inside 1e-150 ... 1e150 in size, M positive definite",
        ) from None


def _check_symmetric(A: np.ndarray, key: str, rel: float, source: str) -> None:
    size = float(np.max(np.abs(A), initial=0.0))
    asym = float(np.max(np.abs(A - A.T), initial=0.0))
    if asym > rel * size:
        raise _bad(
            source,
            key,
            f"is not symmetric: its largest |{key} - {key}ᵀ| is {asym:.3g}, "
            f"{asym / size:.2g} of its largest entry",
            f"a symmetric {key} (to round-off, {rel:.1g} of its largest entry)",
        )


def _positive_mass(M: np.ndarray, n: int, dofs: str, source: str) -> np.ndarray:
    """The eigenvalues of M, ascending; refused unless all are clearly > 0."""
    mu = np.linalg.eigvalsh(M)
    floor = 16 * n * _EPS * float(np.max(np.abs(mu)))
    if not mu[0] > floor:
        raise _bad(
            source,
            "M",
            f"is not positive definite: its smallest eigenvalue is {float(mu[0]):.3g} {_UNIT[dofs]['M']}"
            + (f", {float(mu[0] / mu[-1]):.2g} of its largest" if mu[-1] > 0 else ""),
            f"a mass matrix with every eigenvalue > 0, above round-off ({16 * n}·eps of the largest)",
        )
    return mu


def _eigenvalue_tolerances(K, M, lam, phi, rounding: float, m_norm: float) -> np.ndarray:
    """First-order bound on how far each eigenvalue of (K, M) can be from the writer's (see check_physics)."""
    n = K.shape[0]
    a = np.abs(phi)
    quad_k = np.einsum("ij,ij->j", a, np.abs(K) @ a)
    quad_m = np.einsum("ij,ij->j", a, np.abs(M) @ a)
    data = rounding * (quad_k + np.abs(lam) * quad_m)
    k_norm = float(np.max(np.abs(np.linalg.eigvalsh(K))))
    solves = n * _EPS * (k_norm + np.abs(lam) * m_norm) * np.einsum("ij,ij->j", phi, phi)
    return _SOLVES * (data + solves)


def _check_stiffness(K, lam, zero, dofs: str, source: str) -> None:
    """K positive semidefinite with exactly the rigid-body modes a free body of its DOF set has."""
    want = RIGID_MODES[dofs]
    valid = (
        f"K positive semidefinite with exactly {want} rigid-body mode{'s' if want > 1 else ''} "
        f"({_RIGID_WHAT[dofs]}): eigenvalues of K φ = λ M φ >= 0, {want} of them 0 "
        f"(to {RIGID_FRACTION:g} of the largest)"
    )
    if np.any(lam < -zero):
        kappa = float(np.linalg.eigvalsh(K)[0])
        i = int(np.argmin(lam + zero))
        hz = float(np.sqrt(-lam[i]) / (2 * np.pi))
        raise _bad(
            source,
            "K",
            f"has a negative eigenvalue {kappa:.3g} {_UNIT[dofs]['K']}: a mode of (K, M) at an imaginary "
            f"{hz:.4g} Hz (λ = {float(lam[i]):.3g} (rad/s)²)",
            valid,
        )
    rigid = int(np.count_nonzero(lam <= zero))
    if rigid != want:
        raise _bad(source, "K", f"has {rigid} rigid-body modes (eigenvalues of (K, M) at 0)", valid)


def _check_damping(C, M, n: int, rounding: float, dofs: str, source: str) -> None:
    """C positive semidefinite: no mode of (C, M) with a negative damping rate."""
    import scipy.linalg as la

    rates = la.eigh(C, M, eigvals_only=True, check_finite=False)
    size = float(np.max(np.abs(rates), initial=0.0))
    rel = max(RIGID_FRACTION, _SOLVES * (rounding + n * _EPS))
    if rates.size and rates[0] < -rel * size:
        least = float(np.linalg.eigvalsh(C)[0])
        raise _bad(
            source,
            "C",
            f"has a negative eigenvalue {least:.3g} {_UNIT[dofs]['C']}: the body would feed energy into "
            f"the drivetrain (a damping rate of {float(rates[0]):.3g} 1/s)",
            f"C positive semidefinite: eigenvalues of C φ = γ M φ >= 0 (to {rel:.1g} of the largest)",
        )


def _check_frequencies(free_hz, lam, tol, zero, rounding: float, source: str) -> None:
    """The stored free-free frequencies are those of (K, M), mode by mode."""
    stored = (2 * np.pi * np.asarray(free_hz, dtype=float)) ** 2
    computed = np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi)
    rigid = free_hz == 0
    bad = np.where(rigid, lam > zero, np.abs(lam - stored) > tol)
    if not np.any(bad):
        return
    i = int(np.flatnonzero(bad)[0])
    f, fc = float(free_hz[i]), float(computed[i])
    what = "the punch's digits and its conditioning allow" if rounding else "its conditioning allows"
    raise _bad(
        source,
        "free_hz",
        f"mode {i + 1} is stored at {f:.9g} Hz but K and M give {fc:.9g} Hz"
        + ("" if rigid[i] else f" (λ differs by {float(abs(lam[i] - stored[i]) / stored[i]):.2g})"),
        f"the free-free frequencies of K and M, each to the tolerance {what} "
        f"({float(tol[i] / max(stored[i], zero[i])):.1g} of λ here)",
    )
