"""A study's hold on its output folder: whose it is (the marker) and who writes it now (the lock).

The folder is this study's from the first moment of its first run: before anything else is
written, :data:`~flexshaft.system.atomic.OUTPUT_MARKER` is created naming the study file (a line
``study: "<path>"``), so a first run killed at any point leaves a folder the next run of the
same study takes up, and any other study refuses. Folders of older versions, whose marker names
no study, are recognised by their record (``.flexshaft-study/manifest.json``).

One run writes a folder at a time: the run holds ``.flexshaft-study/lock`` with ``fcntl.flock``
from before it reads the record until its last write. The kernel releases the lock when the
process ends, however it ends (``kill -9`` included), so a lock is never stale. A second run
into the same folder is refused at once, in one line naming the folder and the pid of the run
that holds it - it is not made to wait: a study may run for an hour, a run waiting for it
behind a silent prompt looks hung, and the one holding the folder is often a forgotten
background job the user wants to hear of. Run the two one after the other, or into two folders.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
import time
from pathlib import Path

from ..errors import ModelError
from ..system.atomic import OUTPUT_MARKER, check_output_folder, prepare_output_folder
from ..system.inputs import STORED, read_text
from ..system.nesting import json_document

__all__ = ["FOLDER", "LOCK", "owner", "check_folder", "claimed", "real_folder", "folder_for"]

#: The study's own sub-folder of its output folder: the record, the stored stages, the lock.
FOLDER = ".flexshaft-study"
#: The lock file in :data:`FOLDER`; it holds the pid of the run holding it (for the refusal's message).
LOCK = "lock"
_OWNER = "study: "  # the marker's line naming the study file, a JSON string after it
_VALID = "a new or empty folder, or the folder of this study's earlier run (it is updated)"


def owner(folder: Path) -> str | None:
    """The study file whose folder ``folder`` is (the marker's, else an older record's), or None."""
    folder = Path(folder)
    try:
        text = read_text(folder / OUTPUT_MARKER, STORED, own=True)
    except (ModelError, OSError):
        text = ""
    for line in text.splitlines():
        if line.startswith(_OWNER):
            try:
                study = json_document(line[len(_OWNER) :], folder / OUTPUT_MARKER)
            except ValueError:
                return None
            return study if isinstance(study, str) else None
    # a folder written before the marker named its study: its record does
    try:
        doc = json_document(read_text(folder / FOLDER / "manifest.json", STORED, own=True), "manifest.json")
    except (ModelError, OSError, ValueError):
        return None
    study = doc.get("study") if isinstance(doc, dict) else None
    return study if isinstance(study, str) else None


def check_folder(folder: Path, study: Path, *, force: bool = True, files=()) -> None:
    """Refuse ``folder`` unless it is new, empty, or ``study``'s own (``study`` resolved).

    ``force`` and ``files`` as for :func:`~flexshaft.system.atomic.check_output_folder`: a study
    updates its own folder (``force``); ``flexshaft report`` replaces its ``files`` only with
    ``--force``, and takes a folder an older report marked without naming its model.

    Raises
    ------
    ModelError
        Naming ``-o``, the folder and what is valid (the checks of
        :func:`flexshaft.system.atomic.check_output_folder` first: a link, a home folder, one holding
        the study file, one flexshaft did not write).
    """
    check_output_folder(folder, force=force, inputs=(study,), files=files, option="-o")
    if not (folder / OUTPUT_MARKER).exists():
        return  # new, or empty (a marking killed midway aside): the check above says which
    held = owner(folder)
    if held is None and files:
        return  # a report's folder from before reports were studies: its files are replaced (force)
    if held != str(study):
        what = f"the run of the study {held!r}" if held else f"another flexshaft output ({OUTPUT_MARKER})"
        raise ModelError(f"holds {what}", field="-o", value=str(folder), valid=_VALID)


def real_folder(path: Path) -> None:
    """``path`` as a real folder: anything else of that name (a link, a file) is flexshaft's to replace."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        st = None
    if st is not None and not stat.S_ISDIR(st.st_mode):
        with contextlib.suppress(FileNotFoundError, IsADirectoryError):
            os.unlink(path)  # the link itself, never what it points to
    with contextlib.suppress(FileExistsError):
        os.mkdir(path)
    if not stat.S_ISDIR(os.lstat(path).st_mode):
        raise ModelError(
            "cannot be made a folder", field="-o", value=str(path), valid="a folder flexshaft may write in"
        )


_HELD: set[int] = set()  # lock descriptors this process holds: a forked child must not keep them


def _close_held_in_child() -> None:
    # flock belongs to the open file, which fork shares: a worker outliving a killed run would
    # otherwise hold the folder
    for fd in list(_HELD):
        with contextlib.suppress(OSError):
            os.close(fd)
    _HELD.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_close_held_in_child)


def _holder(fd: int) -> str:
    """The pid the holder wrote into the lock file (it writes it right after locking)."""
    for _ in range(20):  # 1 s at most, for a holder between its lock and its write
        with contextlib.suppress(OSError):
            text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
            if text.isdigit():
                return f"pid {text}"
        time.sleep(0.05)
    return "pid unknown"


def _lock(folder: Path) -> int:
    """Take the folder's lock (flock on :data:`LOCK`); its descriptor, or a ModelError naming the holder."""
    import fcntl

    home = folder / FOLDER
    real_folder(home)
    path = home / LOCK
    flags = os.O_RDWR | os.O_CREAT | os.O_NONBLOCK | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NOCTTY
    valid = "a regular file flexshaft creates: remove it, then run again"
    try:
        fd = os.open(path, flags, 0o666)
    except OSError as err:
        what = f"cannot be opened as the folder's lock ({err.strerror})"
        raise ModelError(what, field="-o", value=str(path), valid=valid) from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            # never unlinked and made anew: a run that did so could take a second lock beside a live one
            raise ModelError("is not a regular file", field="-o", value=str(path), valid=valid)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ModelError(
                f"another flexshaft study run ({_holder(fd)}) is writing this folder",
                field="-o",
                value=str(folder),
                valid="one run at a time in a folder: run again when that one has ended, or use another",
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)
    except BaseException:
        os.close(fd)
        raise
    _HELD.add(fd)
    return fd


@contextlib.contextmanager
def claimed(folder: Path, study: Path, *, writer: str = "flexshaft study", force: bool = True, files=()):
    """The output folder checked, marked as ``study``'s and locked for the block.

    In this order, so that a kill at any point leaves a folder the next run takes up: the checks
    (nothing is made before them), the folder and its marker naming the study (created, never
    replaced), the lock, and the ownership checked again under it (another study's run may have
    marked the new folder first). ``writer`` is what the marker says wrote the folder; ``force``
    and ``files`` as for :func:`check_folder`.
    """
    check_folder(folder, study, force=force, files=files)
    note = _OWNER + json.dumps(str(study), ensure_ascii=False)
    rules = {"force": force, "inputs": (study,), "files": files, "option": "-o"}
    prepare_output_folder(folder, writer=writer, note=note, **rules)
    fd = _lock(folder)
    try:
        check_folder(folder, study, force=force, files=files)
        yield
    finally:
        _HELD.discard(fd)
        os.close(fd)  # the kernel releases the lock


def folder_for(folder: Path, rel: str) -> None:
    """Make the folders a stage's file ``rel`` goes into, inside the output ``folder``: each one a
    real folder (a link put in place of ``exports/`` would send the writes outside the output
    folder; it is replaced, as the study's own files are). The system's refusal (a full disk, a
    read-only folder) is the stage's one-line error naming it, not a defect."""
    here = folder
    for part in Path(rel).parent.parts:
        here = here / part
        try:
            real_folder(here)
        except OSError as err:
            from ..system.atomic import output_error

            raise output_error(err, here) from None
