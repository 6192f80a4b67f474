"""Opening a user's input file: regular files only, each kind under a size ceiling.

Every reader in flexshaft (model files, targets, signal and section tables, STEP/BREP and mesh
parts, exported bodies) opens what a user names through this module, because a path can name
something that is not a file: ``/dev/zero`` never ends, ``/dev/urandom`` never ends either, a FIFO
(``mkfifo``) blocks the reader until someone writes, a socket cannot be read at all, and a 2 GB
sparse file costs nothing on disk but a parser's whole memory. So a file is

1. looked at with ``stat`` and refused by name (a FIFO, a character or block device, a socket, a
   directory, a file that does not exist) before it is opened - opening a device may act on it;
2. opened with ``O_NONBLOCK`` (a FIFO swapped in meanwhile cannot block the open) and looked at
   again with ``fstat`` on the open descriptor: a regular file, the one just checked;
3. refused when its size is above the ceiling for its kind;
4. read with ``O_NONBLOCK`` cleared, at most the ceiling plus one byte: the size ``stat`` gives is
   not trusted alone (files under ``/proc`` say 0 and hold more, a file may grow while it is read).

The ceilings (1 MB = 2**20 bytes), each far above what such a file holds in practice and low
enough that the reader behind it stays within seconds and a few GB:

==================  =======  ============================================================
kind                default  why
==================  =======  ============================================================
model file (TOML)   8 MB     real ones are a few kB; 8 MB is ~100 000 chain entries and
                             parses in ~3 s (Python's TOML reader takes ~3 MB/s)
targets file        1 MB     a targets file is a few lines
section table CSV   32 MB    a sliced part has hundreds to thousands of intervals (~200
                             bytes each); 32 MB is over 100 000 and reads in seconds
signal file (CSV)   2048 MB  measured records are long: ~50 million samples of a few
                             channels; read a piece at a time (streamed), never whole
STEP/BREP part      128 MB   one part (a shaft, a flange) is 0.1-10 MB; OCCT holds ~6x the
                             file while it translates it (a 9 MB part: 55 MB)
STL/OBJ/PLY mesh    128 MB   2.7 million triangles as binary STL; trimesh holds ~600 bytes
                             per triangle while it merges vertices (~1.7 GB at the ceiling)
flexible body       512 MB   npz/json/mat/op4/pch and their sidecars: 2 000 reduced
                             coordinates as JSON is ~240 MB; reading JSON holds ~3.5x
                             the text (~1.8 GB at the ceiling)
part module (.py)   8 MB     part code is a few kB (read only with --allow-code)
==================  =======  ============================================================

A study's output folder is read the same way (:mod:`flexshaft.study`): its stored results and the
files its stages wrote are flexshaft's own files (``own=True``), so a symbolic link is refused
there too (nothing is read from outside the folder through one) and they are not inputs of the
command (its stages write them again). Their ceilings:

==================  =======  ============================================================
stored result       256 MB   a study's record, a stage's stored results and figures, and
                             ``results.json``: each parsed whole (JSON holds ~3.5x the text)
study file digest   2048 MB  a file a study digests a piece at a time: an input its stages
                             read (the largest kind: a signal file) or a file they wrote
==================  =======  ============================================================

``FLEXSHAFT_MAX_FILE_MB`` (a number of MB > 0) sets every ceiling to its value, up or down; each
refusal names the file, its size, the ceiling and the variable.

A reader that must hand a *path* to a foreign library (OCCT's STEP reader) calls
:func:`check_path` first; the library then opens the path itself, so a file replaced between the
check and that open is not caught (the check stops every accident, not a race on purpose). A
library that takes an open file reads by offset through :func:`open_seekable` instead.

Every file opened here is noted (:func:`note_input`): :mod:`flexshaft.system.atomic` refuses to write over
any of them, ``--force`` or not, so an output never replaces an input. The CLI starts each command
with a fresh record (:func:`forget_inputs`).
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import stat
import threading
from dataclasses import dataclass
from pathlib import Path

from ..errors import ModelError

__all__ = [
    "ENV_VAR",
    "MB",
    "Kind",
    "KINDS",
    "MODEL",
    "TARGETS",
    "SECTIONS",
    "SIGNALS",
    "CAD",
    "MESH",
    "BODY",
    "CODE",
    "STUDY",
    "STORED",
    "DIGESTED",
    "ceiling_bytes",
    "file_kind",
    "read_bytes",
    "read_text",
    "open_input",
    "open_seekable",
    "check_path",
    "note_input",
    "tracking",
    "forget_inputs",
    "recorded_inputs",
    "same_input",
]

ENV_VAR = "FLEXSHAFT_MAX_FILE_MB"
MB = 1 << 20  # bytes: ceilings and sizes in messages are in these MB


@dataclass(frozen=True)
class Kind:
    """A kind of input file and its size ceiling.

    Attributes
    ----------
    label : str
        What the file is, for messages (``"model file"``).
    default_mb : float
        The ceiling when ``FLEXSHAFT_MAX_FILE_MB`` is not set, MB (2**20 bytes).
    """

    label: str
    default_mb: float


MODEL = Kind("model file", 8)
TARGETS = Kind("targets file", 1)
SECTIONS = Kind("section table", 32)
SIGNALS = Kind("signal file", 2048)
CAD = Kind("STEP/BREP file", 128)
MESH = Kind("mesh file", 128)
BODY = Kind("flexible-body file", 512)
CODE = Kind("part module", 8)
STUDY = Kind("study file", 1)
STORED = Kind("stored study result", 256)
DIGESTED = Kind("file a study digests", 2048)
KINDS = (MODEL, TARGETS, SECTIONS, SIGNALS, CAD, MESH, BODY, CODE, STUDY, STORED, DIGESTED)

# Bytes asked of the kernel per read once a file holds more than its size said (a /proc file says 0).
_CHUNK = 1 << 16


def ceiling_bytes(kind: Kind) -> int:
    """The largest file of ``kind`` read, bytes: ``FLEXSHAFT_MAX_FILE_MB`` when set, else the default.

    Raises
    ------
    ModelError
        ``FLEXSHAFT_MAX_FILE_MB`` is set to something that is not a number of MB > 0.
    """
    text = os.environ.get(ENV_VAR, "").strip()
    if not text:
        return int(kind.default_mb * MB)
    try:
        mb = float(text)
    except ValueError:
        mb = math.nan
    if not (math.isfinite(mb) and mb > 0):
        raise ModelError(
            "is not a size",
            file="environment",  # the setting, not the file being read (the CLI adds a file otherwise)
            field=ENV_VAR,
            value=text,
            valid="a number of MB > 0 (e.g. 4096), or unset for the defaults",
        )
    return max(1, int(mb * MB))


def _mb(n: float) -> str:
    """A size in MB as plain text: ``2048``, ``0.5``, ``0.001``."""
    v = n / MB
    text = f"{v:.3f}".rstrip("0").rstrip(".")
    return text if text != "0" else f"{v:.3g}"


def _error(path, message: str, field: str | None, valid: str) -> ModelError:
    """A refusal naming the file: as ``file`` or, for a reader that names paths by a field
    (``geometry = 'part.step'``), as that field's value."""
    if field is None:
        return ModelError(message, file=str(path), valid=valid)
    return ModelError(message, field=field, value=str(path), valid=valid)


def _size_error(path, size: int | None, limit: int, kind: Kind, field: str | None) -> ModelError:
    if size is None:  # more came than the size said
        what = f"holds more than {_mb(limit)} MB"
    else:
        shown = _mb(size)
        if shown == _mb(limit):  # rounding would hide that it is above
            shown = f"{shown} MB ({size:,} bytes)"
        else:
            shown += " MB"
        what = f"is {shown}"
    return _error(
        path,
        f"{what}, above the {_mb(limit)} MB ceiling for a {kind.label}",
        field,
        f"a {kind.label} of at most {_mb(limit)} MB, or a higher ceiling: "
        f"{ENV_VAR}=N sets every input file's ceiling to N MB",
    )


_NOT_REGULAR = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (a named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISLNK, "a symbolic link"),  # only where links are refused (own=True): lstat sees them
)


def file_kind(mode: int) -> str | None:
    """What a file of ``mode`` (``st_mode``, of ``lstat`` where links count) is when it is not a
    regular file: ``"a FIFO (a named pipe)"``, ``"a symbolic link"``, ...; None for a regular file."""
    return next((text for test, text in _NOT_REGULAR if test(mode)), None)


def _refuse_kind(path, mode: int, kind: Kind, field: str | None) -> ModelError:
    what = f"is {file_kind(mode) or 'not a regular file'}"
    return _error(
        path, f"{what}, not a {kind.label}", field, "a regular file (never a pipe, device, socket or folder)"
    )


def _not_found(path, kind: Kind, field: str | None) -> ModelError:
    link = os.path.islink(path)
    return _error(
        path,
        "file not found" + (" (a link to a missing file)" if link else ""),
        field,
        f"an existing {kind.label}",
    )


def _unreadable(path, err: OSError, kind: Kind, field: str | None) -> ModelError:
    return _error(
        path,
        f"cannot be read ({err.strerror or type(err).__name__})",
        field,
        f"a {kind.label} this user may read",
    )


def _open(
    path, kind: Kind, field: str | None, own: bool = False, noted: bool = True
) -> tuple[int, os.stat_result, int]:
    """An open, blocking descriptor of the regular file ``path``, its ``fstat``, and the ceiling.

    The checks of the module docstring, in that order; the descriptor is the caller's to close.
    ``own``: a file of flexshaft's own output folder - a symbolic link is refused (``lstat``,
    ``O_NOFOLLOW``). ``noted``: the file is noted as this command's input (:func:`note_input`;
    False for flexshaft's own files: an output folder's, the disk cache's entries).
    """
    try:
        name = os.fspath(path)
    except TypeError:
        raise ModelError("is not a path", field=field or "path", value=path, valid="a file path") from None
    limit = ceiling_bytes(kind)
    try:
        before = os.lstat(name) if own else os.stat(name)
    except FileNotFoundError:
        raise _not_found(name, kind, field) from None
    except OSError as err:
        raise _unreadable(name, err, kind, field) from None
    except ValueError:  # a NUL in the path
        raise _error(name, "is not a usable path (it holds a NUL byte)", field, "a file path") from None
    if not stat.S_ISREG(before.st_mode):
        raise _refuse_kind(name, before.st_mode, kind, field)
    if before.st_size > limit:
        raise _size_error(name, before.st_size, limit, kind, field)
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOCTTY", 0)
    if own:  # a link swapped in between the lstat and the open fails the open (ELOOP)
        flags |= getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(name, flags)
    except FileNotFoundError:
        raise _not_found(name, kind, field) from None
    except OSError as err:
        raise _unreadable(name, err, kind, field) from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):  # replaced between the stat and the open
            raise _refuse_kind(name, st.st_mode, kind, field)
        if st.st_size > limit:
            raise _size_error(name, st.st_size, limit, kind, field)
        _blocking(fd)
    except BaseException:
        os.close(fd)
        raise
    if noted:
        note_input(name, st)
    return fd, st, limit


def _blocking(fd: int) -> None:
    """Clear ``O_NONBLOCK``: a regular file's reads then wait for the disk, as any reader expects."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not a POSIX system: O_NONBLOCK is 0 there
        return
    fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)


def read_bytes(path, kind: Kind, *, field: str | None = None, own: bool = False) -> bytes:
    """The bytes of the regular file ``path``, refused as the module docstring says.

    Parameters
    ----------
    path : str or Path
        The file as the user named it.
    kind : Kind
        Its kind (:data:`MODEL`, :data:`TARGETS`, ...): the ceiling and the word in messages.
    field : str, optional
        Name the file as this field's value (``geometry = 'part.step'``) instead of as the file.
    own : bool
        A file of flexshaft's own output folder (a study's stored result): a symbolic link is
        refused too, and the file is not recorded as an input (the command may write it again).

    Returns
    -------
    bytes
        At most :func:`ceiling_bytes` of them.

    Raises
    ------
    ModelError
        Not found, not a regular file (by name), unreadable, or above the ceiling.
    """
    fd, st, limit = _open(path, kind, field, own=own, noted=not own)
    try:
        chunks, total = [], 0
        want = min(st.st_size, limit) + 1  # one more than the size says: whether more comes
        while total <= limit:
            ask = min(limit + 1 - total, max(want - total, _CHUNK))
            try:
                chunk = os.read(fd, ask)
            except OSError as err:
                raise _unreadable(path, err, kind, field) from None
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > limit:
            raise _size_error(path, None, limit, kind, field)
        return chunks[0] if len(chunks) == 1 else b"".join(chunks)
    finally:
        os.close(fd)


def read_text(path, kind: Kind, *, field: str | None = None, own: bool = False) -> str:
    """The UTF-8 text of ``path`` (see :func:`read_bytes`); bytes that are not UTF-8 are refused."""
    data = read_bytes(path, kind, field=field, own=own)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise _error(
            path, f"not a UTF-8 text file (byte {err.start})", field, f"a {kind.label} in UTF-8"
        ) from None


class _Capped(io.RawIOBase):
    """A regular file's descriptor whose reads refuse the file once more than ``limit`` bytes came."""

    def __init__(self, fd: int, limit: int, over):
        super().__init__()
        self._file = io.FileIO(fd, "rb", closefd=True)
        self._limit = limit
        self._over = over  # () -> the ModelError to raise
        self._count = 0

    def readable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self._file.fileno()

    def readinto(self, buffer) -> int:
        n = self._file.readinto(buffer)
        if n:
            self._count += n
            if self._count > self._limit:
                raise self._over()
        return n

    def close(self) -> None:
        self._file.close()
        super().close()


@contextlib.contextmanager
def open_input(path, kind: Kind, *, field: str | None = None, own: bool = False):
    """The regular file ``path`` as a binary file object, to stream (a signal file, a hash).

    Checked as :func:`read_bytes` checks before reading (``own`` as there); a read that brings the
    total above the ceiling (a file that grows, or holds more than its size said) raises the size
    ModelError.
    Sequential reading only (``read``, ``readline``, ``readinto``; no ``seek``).

    Yields
    ------
    io.BufferedReader
    """
    fd, _, limit = _open(path, kind, field, own=own, noted=not own)
    try:
        raw = _Capped(fd, limit, lambda: _size_error(path, None, limit, kind, field))
    except BaseException:
        os.close(fd)
        raise
    with io.BufferedReader(raw, buffer_size=_CHUNK) as fh:
        yield fh


@contextlib.contextmanager
def open_seekable(path, kind: Kind, *, field: str | None = None, noted: bool = True):
    """The regular file ``path`` as a seekable binary file object, for a foreign reader that seeks.

    For formats read by offset (TDMS, MDF, HDF5, MAT): checked as :func:`read_bytes` checks, then
    handed over open, so the library reads the very file checked (no second open by path that a
    link swapped meanwhile could redirect, no sidecar found beside the path). The ceiling is the
    size at opening; the reader is trusted to stay within the file's size (these libraries read
    at offsets the file's own structure gives, and a read past its end returns nothing).
    ``noted=False`` for flexshaft's own files (its disk cache's entries): checked alike, but not
    noted as an input - not the user's, and no study stage depends on them.

    Yields
    ------
    io.BufferedReader
        Seekable; its ``name`` is the path as given.
    """
    fd, _, _ = _open(path, kind, field, noted=noted)
    try:
        raw = io.FileIO(fd, "rb", closefd=True)
        raw.name = os.fspath(path)  # what a library's own messages call it (else the descriptor's number)
    except BaseException:
        os.close(fd)
        raise
    with io.BufferedReader(raw, buffer_size=_CHUNK) as fh:
        yield fh


def check_path(path, kind: Kind, *, field: str | None = None) -> Path:
    """Check ``path`` as :func:`read_bytes` does, read nothing, and return it for a foreign reader.

    For libraries that open a path themselves (OCCT's STEP and BREP readers): the file is a
    regular one within its kind's ceiling when checked. It is noted as an input.
    """
    fd, _, _ = _open(path, kind, field)
    os.close(fd)
    return Path(path)


# --- the inputs of this command: an output never replaces one of them ------------------------------

_LOCK = threading.Lock()
_READ: dict[tuple[int, int], str] = {}  # (st_dev, st_ino) -> the absolute path it was read by
_DEPTH = [0]  # open recording() blocks: outside one, nothing is recorded


@contextlib.contextmanager
def recording():
    """A block whose inputs no output may replace: the CLI runs each command in one.

    Inside it, every file read through this module is recorded and
    :func:`flexshaft.system.atomic.atomic_write_bytes` refuses to write over any of them, ``--force`` or
    not. Outside (a Python session that reads a body and then deliberately writes it again, with
    ``overwrite=True``) nothing is recorded: the caller names both paths itself. The record starts
    empty and is dropped when the outermost block ends; nested blocks share it.
    """
    with _LOCK:
        if _DEPTH[0] == 0:
            _READ.clear()
        _DEPTH[0] += 1
    try:
        yield
    finally:
        with _LOCK:
            _DEPTH[0] -= 1
            if _DEPTH[0] == 0:
                _READ.clear()


_TRACKERS: list[list[str]] = []  # open tracking() blocks, each collecting the files read inside it


@contextlib.contextmanager
def tracking():
    """A block that lists the files read inside it (absolute paths, in order, repeats kept).

    What a study stage read decides whether its stored result still holds: the stage is redone
    when one of these files changes. Independent of :func:`recording` (nothing is protected by
    it); blocks nest, each sees every file read while it is open.
    """
    seen: list[str] = []
    with _LOCK:
        _TRACKERS.append(seen)
    try:
        yield seen
    finally:
        with _LOCK:
            _TRACKERS.remove(seen)


def note_input(path, st: os.stat_result | None = None) -> None:
    """Record ``path`` (with its device and inode: ``st``, else ``os.stat``) as read by this command.

    Only inside :func:`recording` (the CLI's commands); elsewhere a no-op - except for the lists
    of open :func:`tracking` blocks, which every read joins.
    """
    if _TRACKERS:
        with _LOCK:
            for seen in _TRACKERS:
                seen.append(os.path.abspath(os.fspath(path)))
    if not _DEPTH[0]:
        return
    if st is None:
        try:
            st = os.stat(path)
        except (OSError, ValueError):
            return  # nothing there: nothing to protect
    with _LOCK:
        _READ[(st.st_dev, st.st_ino)] = os.path.abspath(os.fspath(path))


def forget_inputs() -> None:
    """Start a fresh record (each CLI command does)."""
    with _LOCK:
        _READ.clear()


def recorded_inputs() -> tuple[Path, ...]:
    """The files read since :func:`forget_inputs`, as the paths they were read by (absolute)."""
    with _LOCK:
        return tuple(Path(p) for p in _READ.values())


def same_input(path) -> Path | None:
    """The recorded input that ``path`` is (links followed, hard links included), or None.

    A match is the same device and inode *and* the recorded path still leads to that inode: an
    input deleted since it was read may have left its inode number to a new, unrelated file.
    """
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None  # nothing there yet: no input is replaced
    key = (st.st_dev, st.st_ino)
    with _LOCK:
        recorded = _READ.get(key)
    if recorded is None:
        return None
    try:
        again = os.stat(recorded)
    except OSError:
        return None
    return Path(recorded) if (again.st_dev, again.st_ino) == key else None
