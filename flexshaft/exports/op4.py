"""Nastran OUTPUT4 (OP4) text matrices: write and read, real double precision.

The layout is Nastran's formatted OUTPUT4: per matrix a header (columns, rows,
form, type = 2 for real double, name, Fortran format ``1P,3E23.16``), then per
column with non-zeros a record (column, first row, number of values) and the
values from that row to the last non-zero, three per line; a record for
column ``ncol + 1`` closes the matrix. Values are written with 17 significant
digits, so a read gives the same doubles. OP4 has no units: flexshaft writes a
JSON sidecar with them (see :mod:`flexshaft.exports.bodies`).
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from .bodyformat import MAX_ENTRIES

__all__ = ["op4_text", "parse_op4"]


def _form(A: np.ndarray) -> int:
    nrow, ncol = A.shape
    if nrow != ncol:
        return 2  # rectangular
    return 6 if np.array_equal(A, A.T) else 1  # symmetric, or square


def op4_text(matrices: dict[str, np.ndarray]) -> str:
    """OP4 text of named real matrices (names up to 8 characters, upper-cased)."""
    out = []
    for name, value in matrices.items():
        if len(name) > 8:
            raise ModelError(
                "OP4 names have at most 8 characters", field="name", value=name, valid="<= 8 chars"
            )
        A = np.atleast_2d(np.asarray(value, dtype=float))
        nrow, ncol = A.shape
        out.append(f"{ncol:8d}{nrow:8d}{_form(A):8d}{2:8d}{name.upper():<8s}1P,3E23.16")
        for j in range(ncol):
            nz = np.flatnonzero(A[:, j])
            if nz.size == 0:
                continue
            vals = A[nz[0] : nz[-1] + 1, j]
            out.append(f"{j + 1:8d}{nz[0] + 1:8d}{vals.size:8d}")
            out.extend("".join(f"{v:23.16E}" for v in vals[k : k + 3]) for k in range(0, vals.size, 3))
        out.append(f"{ncol + 1:8d}{1:8d}{1:8d}")
        out.append(f"{1.0:23.16E}")
    return "\n".join(out) + "\n"


def parse_op4(text: str, *, source: str = "<op4>") -> dict[str, np.ndarray]:
    """Read OP4 text written in the layout above (as flexshaft and Nastran write it)."""
    lines = text.splitlines()
    mats: dict[str, np.ndarray] = {}
    k = 0
    try:
        while k < len(lines):
            head = lines[k]
            if not head.strip():
                k += 1
                continue
            ncol, nrow, _form_, mtype = (int(head[i : i + 8]) for i in range(0, 32, 8))
            name = head[32:40].strip().lower()
            if mtype != 2:
                raise ModelError(
                    "only real double precision (type 2) is read",
                    file=source,
                    field=name,
                    value=mtype,
                    valid="2",
                )
            if not (0 < nrow and 0 < ncol and nrow * ncol <= MAX_ENTRIES):
                raise ModelError(
                    f"matrix claims {nrow} × {ncol}",
                    file=source,
                    field=name,
                    valid=f"a matrix of at most {MAX_ENTRIES:,} entries",
                )
            A = np.zeros((nrow, ncol))
            k += 1
            while True:
                col, row, nw = (int(lines[k][i : i + 8]) for i in range(0, 24, 8))
                k += 1
                nlines = -(-nw // 3)
                vals = [
                    float(line[i : i + 23])
                    for line in lines[k : k + nlines]
                    for i in range(0, len(line), 23)
                    if line[i : i + 23].strip()
                ]
                k += nlines
                if col > ncol:
                    break
                if not (1 <= col and 1 <= row and row - 1 + nw <= nrow and len(vals) >= nw):
                    raise ValueError(f"column {col}, rows {row}…{row + nw - 1} do not fit {nrow} × {ncol}")
                A[row - 1 : row - 1 + nw, col - 1] = vals[:nw]
            mats[name] = A
    except (ValueError, IndexError) as err:
        raise ModelError(f"is not readable OP4 text ({type(err).__name__}: {err})", file=source) from None
    return mats
