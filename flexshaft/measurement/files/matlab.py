"""MATLAB files, versions 5 to 7 (``save -v7``, the default before 7.3) through scipy; a v7.3 file is HDF5
and goes to :mod:`.hdf5` (the version is read from the file's header, not from its name).

- Channels: top-level numeric vectors (double, single, integer classes; 1xN or Nx1), by name. Cells,
  structs, objects, function handles, text, logical, sparse and complex arrays are refused: nothing
  is read that could make objects (scipy never unpickles; object arrays are refused as well).
- Units: a MAT file states none: ``units=`` (``--unit NAME=UNIT``) states every channel's.
- Time: a variable ``time_column`` (default: one named ``time``), or the ``rate`` given.
- Damage and claims: the file's elements are walked first (each must end within the file: a
  truncated file is named as such); a variable's size is its header's dimensions, checked against
  its stored bytes (uncompressed) or against what its compressed data inflate to, counted without
  being kept (compressed), before scipy reads it. Only the variables asked for are read.
"""

from __future__ import annotations

import contextlib
import struct
import zlib

from .base import Entry, Raw, check_claim, error

__all__ = ["LIBRARY", "WHAT", "check_variables", "header_version", "source"]

WHAT = "MATLAB file"
LIBRARY = ("scipy.io", "scipy")
_HEADER = 128  # bytes: text, subsystem offset, version, endian indicator
_MATRIX, _COMPRESSED = 14, 15  # miMATRIX, miCOMPRESSED: what a MAT file's top level holds
_ITEMSIZE = {
    "double": 8,
    "single": 4,
    "int8": 1,
    "uint8": 1,
    "int16": 2,
    "uint16": 2,
    "int32": 4,
    "uint32": 4,
    "int64": 8,
    "uint64": 8,
}
_MAX_VARIABLES = 100_000
_SLACK = 1 << 16  # bytes beside a variable's numbers in its element: flags, dimensions, name, tags
_PIECE = 1 << 20


def header_version(head: bytes) -> str | None:
    """``"5"`` (v5 to v7) or ``"7.3"`` from a MAT file's 128-byte header, or None: not a MAT file."""
    if len(head) < _HEADER or not head.startswith(b"MATLAB"):
        return None
    order = {b"IM": "little", b"MI": "big"}.get(head[126:128])
    if order is None:
        return None
    return {0x0100: "5", 0x0200: "7.3"}.get(int.from_bytes(head[124:126], order))


def _inflated(fh, offset: int, nbytes: int, limit: int) -> int:
    """Bytes the compressed element at ``offset`` inflates to, counted up to just above ``limit``."""
    fh.seek(offset + 8)
    z = zlib.decompressobj()
    total, left = 0, nbytes
    while left > 0 and not z.eof:
        buf = fh.read(min(_PIECE, left))
        if not buf:
            break
        left -= len(buf)
        while buf and not z.eof:
            total += len(z.decompress(buf, _PIECE))
            if total > limit:
                return total
            buf = z.unconsumed_tail
    return total


def _check_inflation(fh, path, label: str, element, nbytes_claimed: int, what: str) -> None:
    """Refuse a compressed variable (``element``: offset, type, bytes) whose data inflate to more than
    the ``nbytes_claimed`` its header's values take - counted, not kept (:func:`_inflated`), twice
    that and the element's other parts allowed (a complex variable holds two parts)."""
    offset, _, nbytes = element
    limit = nbytes_claimed * 2 + _SLACK
    if _inflated(fh, offset, nbytes, limit) > limit:
        raise error(
            path,
            f"is damaged: its compressed data inflate to more than its {what}",
            field=label,
            valid="an undamaged MATLAB file",
        )


class _Source:
    def __init__(self, fh, lib, path, size: int):
        self.fh, self.lib, self.path, self.size = fh, lib, path, size
        self.claimed: dict[Entry, int] = {}
        fh.seek(0)
        order = "<" if fh.read(_HEADER)[126:128] == b"IM" else ">"
        self.elements = self._walk(order)
        fh.seek(0)
        listed = lib.whosmat(fh)
        if len(listed) != len(self.elements):
            raise error(
                path,
                f"is damaged: {len(self.elements)} elements, of which scipy reads {len(listed)} variables",
                valid="an undamaged MATLAB file",
            )
        self.listed = [
            Entry(
                "",
                name,
                (i, tuple(shape), cls),
                numeric=cls in _ITEMSIZE and _vector(shape),
                time=name.lower() == "time",
            )
            for i, (name, shape, cls) in enumerate(listed)
        ]

    def _walk(self, order: str) -> list[tuple[int, int, int]]:
        """Every top-level element (offset, type, bytes), each ending within the file."""
        out, pos = [], _HEADER
        while pos < self.size:
            self.fh.seek(pos)
            tag = self.fh.read(8)
            if len(tag) < 8:
                raise error(self.path, f"is truncated: {len(tag)} bytes of an element's tag at byte {pos}")
            mdtype, nbytes = struct.unpack(order + "II", tag)
            if mdtype not in (_MATRIX, _COMPRESSED):
                raise error(
                    self.path,
                    f"is damaged: an element of type {mdtype} at byte {pos}",
                    valid="a MATLAB file of variables (matrix or compressed elements)",
                )
            if pos + 8 + nbytes > self.size:
                raise error(
                    self.path,
                    f"is truncated: the element at byte {pos} claims {nbytes:,} bytes, "
                    f"{self.size - pos - 8:,} follow",
                    valid="a complete MATLAB file",
                )
            out.append((pos, mdtype, nbytes))
            if len(out) > _MAX_VARIABLES:
                raise error(self.path, f"holds more than {_MAX_VARIABLES} variables")
            pos += 8 + (nbytes if mdtype == _COMPRESSED else -(-nbytes // 8) * 8)  # a matrix is padded to 8
        return out

    def entries(self) -> list[Entry]:
        return self.listed

    def claim(self, entry: Entry) -> int:
        """The values the variable's header claims, checked against its stored (or inflated) bytes."""
        i, shape, cls = entry.handle
        if not (cls in _ITEMSIZE and _vector(shape)):
            raise error(
                self.path,
                f"is a MATLAB {cls} of shape {shape}",
                field=entry.label,
                valid="a vector (1xN or Nx1) of double, single or an integer class",
            )
        if entry in self.claimed:
            return self.claimed[entry]
        n = shape[0] * shape[1]
        itemsize = _ITEMSIZE[cls]
        _, mdtype, nbytes = self.elements[i]
        if mdtype == _MATRIX:
            check_claim(self.path, entry.label, n, itemsize, nbytes)
        else:
            check_claim(self.path, entry.label, n, itemsize, None)
            what = f"{shape} {cls} values"
            _check_inflation(self.fh, self.path, entry.label, self.elements[i], n * itemsize, what)
        self.claimed[entry] = n  # the inflation counted once (it reads the element through)
        return n

    def read(self, entry: Entry, plan: bool = False) -> Raw:
        n = self.claim(entry)  # scipy reads the variable: no plan for MATLAB v5
        self.fh.seek(0)
        got = self.lib.loadmat(
            self.fh,
            variable_names=[entry.name],
            mat_dtype=False,
            squeeze_me=False,
            struct_as_record=True,
            simplify_cells=False,
            verify_compressed_data_integrity=True,
        ).get(entry.name)
        if got is None or got.size != n:
            raise error(self.path, "is damaged: the variable cannot be read whole", field=entry.label)
        return Raw(got.reshape(-1), None, None)


def check_variables(fh, path, size: int, lib, *, names, max_entries: int) -> None:
    """Refuse a MATLAB v5-v7 file whose variables ``names`` claim more than it can hold - before
    scipy reads any (a 3 MB file whose compressed element claims a 20000 x 20000 matrix made
    ``loadmat`` allocate 3.2 GB).

    The file's elements are walked (each must end within it); each variable named must be a real
    numeric or text matrix of at most ``max_entries`` entries, and its data must be there: an
    uncompressed element's bytes hold its entries, a compressed one inflates (counted, not kept) to
    no more than they take. scipy reads nothing beyond a variable's element, so the rest of the
    file costs nothing.

    Parameters
    ----------
    fh : binary file
        The open file (seekable).
    path : Path
        Its name, for the errors.
    size : int
        Its size, bytes.
    lib : module
        ``scipy.io``.
    names : iterable of str
        The variables to be read.
    max_entries : int
        The most entries a variable may have.
    """
    src = _Source(fh, lib, path, size)
    found = {e.name: e.handle for e in src.listed}
    for name in names:
        if name not in found:
            continue  # the reader says what is missing
        i, shape, cls = found[name]
        n = 1
        for d in shape:
            n *= int(d)
        itemsize = 4 if cls == "char" else _ITEMSIZE.get(cls)  # text: at most UTF-32 in numpy
        if itemsize is None:
            raise error(
                path,
                f"holds a MATLAB {cls} where a matrix of numbers or text belongs",
                field=name,
                valid="a numeric or char matrix",
            )
        if n > max_entries:
            raise error(
                path,
                f"claims {n:,} entries (shape {shape})",
                field=name,
                valid=f"at most {max_entries:,} entries",
            )
        _, mdtype, nbytes = src.elements[i]
        stored = n * (1 if cls == "char" else itemsize)  # text as UTF-8 takes a byte a character at least
        if mdtype == _MATRIX:
            if stored > nbytes:
                raise error(
                    path,
                    f"is damaged: its header claims {n:,} entries, {stored:,} bytes at least, where its "
                    f"element holds {nbytes:,}",
                    field=name,
                    valid="an undamaged MATLAB file",
                )
        else:
            _check_inflation(fh, path, name, src.elements[i], n * itemsize, f"{shape} {cls} entries")
    fh.seek(0)


def _vector(shape) -> bool:
    return len(shape) == 2 and min(shape) == 1


@contextlib.contextmanager
def source(fh, path, size: int, lib):
    """The open MATLAB v5-v7 file ``fh`` as a source of variables."""
    yield _Source(fh, lib, path, size)
