"""Flexible bodies to and from files, with their units: ``.npz``, JSON, MATLAB ``.mat``, Nastran OP4 and DMIG.

Every file carries the format name and version, the unit system (SI, spelled
out per quantity), the part's name, material, DOF order, interface node
positions, frequencies and damping. The reader refuses a file whose units
are not flexshaft's, naming both - the study lost days to a part that came
into a multibody tool in the wrong length unit. No pickles: ``.npz`` holds
plain arrays and one JSON string of metadata. The two Nastran formats (OP4
matrices, a DMIG ``.pch`` punch) hold only what Nastran reads; a JSON
sidecar beside them (``.op4.json``, ``.pch.json``) carries the units and the
rest, and the reader requires it.

Integrity: every file carries SHA-256 checksums (``body_sha256`` in the
metadata of npz/json/mat; ``data_sha256`` and ``sidecar_sha256`` in a
sidecar; see :mod:`flexshaft.exports.bodyformat`), and the reader requires them:
a missing, malformed or different checksum is refused with the advice to
export the part again. Then the physics: K, M, C symmetric, M positive
definite, K positive semidefinite with the body's rigid-body modes, C
positive semidefinite, the stored free-free frequencies those of K and M.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..reduction.craig_bampton import FlexibleBody
from ..system.atomic import atomic_write_bytes, atomic_write_text
from ..system.inputs import BODY, check_path, read_bytes, read_text
from ..system.nesting import json_document  # every JSON here: its nesting checked before it is parsed
from ..system.threads import follows_policy
from .bodyformat import (
    BODY_SHA256,
    DATA_SHA256,
    FORMAT,
    MAX_ENTRIES,
    SIDECAR_SHA256,
    UNITS,
    VERSION,
    body_sha256,
    check_body,
    check_metadata,
    check_sha256,
    dof_order,
    metadata,
    sidecar_sha256,
    text_sha256,
)

__all__ = [
    "FORMAT",
    "VERSION",
    "UNITS",
    "MAT_NAMES",
    "BodyFile",
    "write_flexible_body",
    "read_flexible_body",
    "dof_order",
]

_ARRAYS = (
    "boundary_nodes",
    "boundary_x",
    "K",
    "M",
    "C",
    "T",
    "fixed_interface_hz",
    "free_hz",
    "free_modes",
    "damping_ratios",
)
#: Variable names in a ``.mat`` file (MATLAB/Simulink). ``boundary_nodes`` there is 1-based.
MAT_NAMES = {
    "boundary_nodes": "boundary_nodes",
    "boundary_x": "boundary_x_m",
    "K": "K",
    "M": "M",
    "C": "C",
    "T": "T_recovery",
    "fixed_interface_hz": "fixed_interface_hz",
    "free_hz": "free_hz",
    "free_modes": "free_modes",
    "damping_ratios": "damping_ratios",
}


@follows_policy
def write_flexible_body(body: FlexibleBody, path, *, material=None, overwrite: bool = False) -> Path:
    """Write a flexible body; the suffix picks the format.

    ``.npz`` (arrays + JSON metadata), ``.json`` (everything as JSON),
    ``.mat`` (MATLAB), ``.op4`` (Nastran OUTPUT4) or ``.pch`` (Nastran DMIG
    punch, see :mod:`flexshaft.exports.dmig`: GRID 1001… for the boundary nodes,
    SPOINT 9001… for the modes, KAAX/MAAX/BAAX; other ids or names through
    :func:`flexshaft.exports.dmig.dmig_text`). The Nastran formats get a ``.json``
    sidecar with the units and what the file cannot hold.

    Parameters
    ----------
    body : FlexibleBody
        From :func:`flexshaft.reduction.craig_bampton`.
    path : str or Path
        Target; its suffix picks the format.
    material : Material, optional
        Recorded with the part.
    overwrite : bool
        Replace an existing file (the CLI's ``--force``). The write is atomic.
    """
    p = Path(path)
    meta = metadata(body, material)
    # One dtype per array whatever the body holds, so that every format hashes the same numbers.
    arrays = {k: np.asarray(getattr(body, k), dtype=int if k == "boundary_nodes" else float) for k in _ARRAYS}
    if p.suffix.lower() in (".npz", ".json", ".mat"):
        # Self-contained: the checksum of metadata and arrays travels in the metadata.
        meta = json.loads(json.dumps(meta))  # as a reader will see it
        meta[BODY_SHA256] = body_sha256(meta, arrays)
    if p.suffix.lower() == ".npz":
        buf = io.BytesIO()
        np.savez_compressed(buf, metadata=np.array(json.dumps(meta, ensure_ascii=False)), **arrays)
        return atomic_write_bytes(p, buf.getvalue(), overwrite=overwrite)
    if p.suffix.lower() == ".json":
        doc = meta | {k: v.tolist() for k, v in arrays.items()}
        return atomic_write_text(p, json.dumps(doc, ensure_ascii=False), overwrite=overwrite)
    if p.suffix.lower() == ".mat":
        # MATLAB/Simulink: plain double matrices under documented names, metadata as a JSON char array.
        from scipy.io import savemat

        buf = io.BytesIO()
        savemat(
            buf,
            {
                MAT_NAMES[k]: (v.astype(float) if k != "boundary_nodes" else v.astype(float) + 1.0)
                for k, v in arrays.items()
            }
            | {"flexshaft_metadata": json.dumps(meta, ensure_ascii=False)},
            do_compression=True,
            oned_as="column",
        )
        return atomic_write_bytes(p, buf.getvalue(), overwrite=overwrite)
    if p.suffix.lower() == ".op4":
        # Nastran: K, M, B (damping) and the recovery matrix as OP4 text, in SI (N, m, kg, s - a
        # consistent set, as Nastran expects); OP4 has no units, so a JSON sidecar carries them and
        # everything else. Both are checked before either is written.
        from .op4 import op4_text

        side = _sidecar(p, overwrite)
        rest = {k: v.tolist() for k, v in arrays.items() if k not in ("K", "M", "C", "T")}
        text = op4_text({"KAA": arrays["K"], "MAA": arrays["M"], "BAA": arrays["C"], "TREC": arrays["T"]})
        extra = {"op4": {"KAA": "K", "MAA": "M", "BAA": "C", "TREC": "T"}, DATA_SHA256: text_sha256(text)}
        return _write_pair(p, text, side, meta | rest | extra, overwrite)
    if p.suffix.lower() == ".pch":
        # Nastran DMIG punch (flexshaft.exports.dmig): K, M, B on GRIDs and SPOINTs, units in its comments;
        # the sidecar, as for OP4, carries what a deck cannot (T, the free-free basis) exactly.
        from .dmig import dmig_text

        side = _sidecar(p, overwrite)
        text = dmig_text(body, material=material)  # checked before anything is written
        rest = {k: v.tolist() for k, v in arrays.items() if k not in ("K", "M", "C")}
        names = {"KAAX": "K", "MAAX": "M"} | ({"BAAX": "C"} if np.any(body.C) else {})
        extra = {"dmig": names, DATA_SHA256: text_sha256(text)}
        return _write_pair(p, text, side, meta | rest | extra, overwrite)
    raise ModelError(
        "unknown export format",
        field="output",
        value=str(p),
        valid=".npz, .json, .mat, .op4 (+ .op4.json) or .pch (+ .pch.json)",
    )


def _write_pair(path: Path, text: str, side: Path, doc: dict, overwrite: bool) -> Path:
    """A Nastran file and its sidecar, each written atomically; the sidecar carries both checksums."""
    doc = json.loads(json.dumps(doc))  # as a reader will see it
    doc[SIDECAR_SHA256] = sidecar_sha256(doc)
    atomic_write_text(side, json.dumps(doc, ensure_ascii=False), overwrite=True)
    return atomic_write_text(path, text, overwrite=overwrite)


def _check_sidecar(path: Path, doc: dict) -> None:
    """Refuse a sidecar changed after it was written (its own checksum is required)."""
    side = path.with_name(path.name + ".json")
    check_sha256(
        doc,
        SIDECAR_SHA256,
        sidecar_sha256(doc),
        str(side),
        mismatch="does not match the sidecar's content: it was edited or damaged after flexshaft wrote it",
    )


def _check_pair(path: Path, text: str, doc: dict) -> None:
    """Refuse a Nastran file that is not the one its sidecar was written with (the checksum is required)."""
    check_sha256(
        doc,
        DATA_SHA256,
        text_sha256(text),
        str(path),
        mismatch=f"does not match its sidecar: the {path.suffix.lower()} was edited or damaged, or is "
        f"not the one {path.name}.json was written with (a write was interrupted, or one was replaced)",
    )


def _check_self_contained(meta: dict, arrays: dict, source: str) -> None:
    """Refuse an npz, JSON or mat body changed after it was written (its checksum is required)."""
    check_sha256(
        meta,
        BODY_SHA256,
        body_sha256(meta, arrays),
        source,
        mismatch="does not match the file's metadata and arrays: it was edited or damaged after "
        "flexshaft wrote it",
    )


def _sidecar(path: Path, overwrite: bool) -> Path:
    """The JSON sidecar of a Nastran file; neither is replaced without ``overwrite``."""
    side = path.with_name(path.name + ".json")
    for q in (path, side):
        if q.exists() and not overwrite:
            raise ModelError(
                "file exists",
                field="output",
                value=str(q),
                valid="a new path, or --force (overwrite=True) to replace it",
            )
    return side


def _read_sidecar(path: Path) -> tuple[dict, dict]:
    """The sidecar document of a Nastran file and its checked metadata; required."""
    side = path.with_name(path.name + ".json")
    if not side.exists():  # there but no regular file (a FIFO): refused by name when it is read
        raise ModelError(
            "its units sidecar is missing",
            file=str(path),
            field="sidecar",
            value=str(side),
            valid=f"the {path.suffix.lower()}.json written with it",
        )
    return _json_document(side)


_META_KEYS = ("format", "version", "units", "name", "dofs", "dof_order", "residual_vectors", "material")
_VECTORS = ("boundary_nodes", "boundary_x", "fixed_interface_hz", "free_hz", "damping_ratios")


def _json_document(path: Path) -> tuple[dict, dict]:
    """A JSON export (or OP4 sidecar): the whole document and its checked metadata."""
    text = read_text(path, BODY)  # a regular file within the body file's ceiling (flexshaft.system.inputs)
    try:
        doc = json_document(text, path)  # ModelError (a ValueError) past the nesting limit
    except ModelError:
        raise
    except (OSError, ValueError) as err:
        raise ModelError(f"cannot be read ({type(err).__name__}: {err})", file=str(path)) from None
    meta = {k: doc.get(k) for k in _META_KEYS}
    check_metadata(meta, str(path))
    return doc, meta


def _arrays_from(doc: dict, keys) -> dict:
    return {k: np.asarray(doc[k], dtype=int if k == "boundary_nodes" else float) for k in keys}


@dataclass(frozen=True)
class BodyFile:
    """A flexible body read from a file, with what the file says about it.

    Attributes
    ----------
    body : FlexibleBody
        The reduced matrices, recovery matrix, frequencies and damping (SI).
    metadata : dict
        The file's metadata: ``format``, ``version``, ``units`` (checked to
        be flexshaft's SI), ``name``, ``dofs``, ``dof_order``,
        ``residual_vectors`` and ``material`` (name, E Pa, nu, rho kg/m³, or
        None).
    path : Path
        Where it was read from.
    """

    body: FlexibleBody
    metadata: dict
    path: Path

    @property
    def dof_order(self) -> list[str]:
        """Names of the reduced coordinates, as the file lists them."""
        return list(self.metadata["dof_order"])

    @property
    def material(self) -> dict | None:
        """The part's material as written (name, E Pa, nu, rho kg/m³), or None."""
        return self.metadata.get("material")


@follows_policy
def read_flexible_body(path) -> BodyFile:
    """Read a flexible body written by :func:`write_flexible_body`, checking format and units.

    Returns a :class:`BodyFile`: the body and the file's metadata (name,
    material, DOF order, units).
    Bit-identical to what was written, except ``K``, ``M``, ``C`` from a
    ``.pch``: a DMIG field holds 9-12 significant digits (see
    :mod:`flexshaft.exports.dmig`).
    """
    p = check_path(path, BODY)  # a regular file within the body file's ceiling (flexshaft.system.inputs)
    source = str(p)
    try:
        arrays, meta, rounding = _read_arrays(p, source)
        check_body(arrays, meta, source, rounding=rounding)
        body = FlexibleBody(
            name=meta["name"], dofs=meta["dofs"], n_residual=int(meta.get("residual_vectors", 0)), **arrays
        )
    except ModelError:
        raise
    except Exception as err:  # noqa: BLE001 - a damaged file: any decoder error is the file's, not ours
        detail = str(err).splitlines()[0] if str(err) else ""
        raise ModelError(
            f"cannot be read ({type(err).__name__}{': ' + detail if detail else ''})",
            file=source,
            valid="a flexible-body file written by flexshaft",
        ) from None
    return BodyFile(body=body, metadata=meta, path=p)


def _npz_arrays(p: Path, names) -> tuple[dict, dict]:
    """The metadata and arrays of an ``.npz``, each array's header checked before it is read."""
    import zipfile

    buf = io.BytesIO(read_bytes(p, BODY))
    with zipfile.ZipFile(buf) as zf:
        for name in ("metadata", *names):
            with zf.open(f"{name}.npy") as fh:
                version = np.lib.format.read_magic(fh)
                fmt = np.lib.format
                readers = {(1, 0): fmt.read_array_header_1_0, (2, 0): fmt.read_array_header_2_0}
                if version not in readers:
                    raise ModelError(f"array format {version} is not read", file=str(p), field=name)
                shape, _, dtype = readers[version](fh)
                if int(np.prod(shape, dtype=float)) > MAX_ENTRIES or dtype.hasobject:
                    raise ModelError(
                        f"array claims shape {shape} of {dtype}",
                        file=str(p),
                        field=name,
                        valid=f"numbers, at most {MAX_ENTRIES:,} entries",
                    )
    buf.seek(0)  # the zip scan above left the buffer mid-file; np.load reads from where it stands
    with np.load(buf, allow_pickle=False) as data:
        meta = json_document(str(data["metadata"]), p)
        check_metadata(meta, str(p))
        return {k: np.array(data[k]) for k in names}, meta


def _read_arrays(p: Path, source: str) -> tuple[dict, dict, float]:
    """Every array of a body file, its checked metadata and checksums, by format.

    Returns the arrays, the metadata and the relative rounding of K, M, C in
    the file (0: doubles; a DMIG punch's digits).
    """
    rounding = 0.0
    if p.suffix.lower() == ".npz":
        arrays, meta = _npz_arrays(p, _ARRAYS)
        _check_self_contained(meta, arrays, source)
    elif p.suffix.lower() == ".json":
        doc, meta = _json_document(p)
        arrays = _arrays_from(doc, _ARRAYS)
        _check_self_contained({k: v for k, v in doc.items() if k not in _ARRAYS}, arrays, source)
    elif p.suffix.lower() == ".mat":
        import scipy.io as scipy_io

        from ..measurement.files.matlab import check_variables

        raw = io.BytesIO(read_bytes(p, BODY))
        wanted = ["flexshaft_metadata", *MAT_NAMES.values()]
        try:
            # every header's claim checked first: loadmat allocates what a header says
            size = len(raw.getbuffer())
            check_variables(raw, source, size, scipy_io, names=wanted, max_entries=MAX_ENTRIES)
            data = scipy_io.loadmat(raw, variable_names=wanted)
            meta = json_document(str(np.atleast_1d(data["flexshaft_metadata"])[0]), source)
            check_metadata(meta, source)
            arrays = {}
            for k, name in MAT_NAMES.items():
                a = np.asarray(data[name], dtype=float)
                if k == "boundary_nodes" and np.all(np.abs(a) < 2.0**53):  # else refused as non-finite/large
                    a = a.astype(int) - 1
                arrays[k] = a.ravel() if k in _VECTORS else a  # .mat stores vectors as columns
        except ModelError:
            raise
        except (OSError, ValueError, KeyError) as err:
            raise ModelError(f"cannot be read ({type(err).__name__}: {err})", file=source) from None
        _check_self_contained(meta, arrays, source)
    elif p.suffix.lower() == ".op4":
        from .op4 import parse_op4

        doc, meta = _read_sidecar(p)
        _check_sidecar(p, doc)
        text = read_text(p, BODY)
        mats = parse_op4(text, source=source)
        _check_pair(p, text, doc)
        arrays = _arrays_from(doc, [k for k in _ARRAYS if k not in ("K", "M", "C", "T")])
        arrays.update(K=mats["kaa"], M=mats["maa"], C=mats["baa"], T=mats["trec"])
    elif p.suffix.lower() == ".pch":
        from .dmig import ROUNDING, parse_dmig

        doc, meta = _read_sidecar(p)
        _check_sidecar(p, doc)
        text = read_text(p, BODY)
        deck = parse_dmig(text, source=source)  # checks the deck's own units
        for key in ("name", "dofs", "dof_order"):
            if deck["metadata"].get(key) != meta[key]:
                raise ModelError(
                    "the punch and its sidecar describe different bodies",
                    file=source,
                    field=key,
                    value=deck["metadata"].get(key),
                    has_value=True,
                    valid=f"{meta[key]!r}, as in {p.name}.json",
                )
        _check_pair(p, text, doc)  # after the named checks: they say more than a checksum
        arrays = _arrays_from(doc, [k for k in _ARRAYS if k not in ("K", "M", "C")])
        arrays.update(K=deck["K"], M=deck["M"], C=deck["C"])
        rounding = ROUNDING
    else:
        raise ModelError(
            "unknown format", field="input", value=source, valid=".npz, .json, .mat, .op4 or .pch"
        )
    return arrays, meta, rounding
