"""Writing files safely: never overwrite silently, never leave half a file.

Every writer in flexshaft goes through :func:`atomic_write_text` (or its bytes
twin): the content goes to a temporary file beside the target and is moved
into place in one step, so an error leaves the target as it was.
"""

from __future__ import annotations

import glob
import os
import stat
import tempfile
from pathlib import Path

from .errors import ModelError

__all__ = ["atomic_write_bytes", "atomic_write_text"]


def _umask() -> int:
    """The process's umask (read by setting and restoring it: Python has no getter)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, not ours
        return True
    return True


def _remove_stale_temps(p: Path) -> None:
    """Temporary files of this target left by a killed writer (its process is gone)."""
    for tmp in p.parent.glob(f".{glob.escape(p.name)}.*.tmp"):
        pid = tmp.name[len(p.name) + 2 :].split(".", 1)[0]
        if pid.isdigit() and not _alive(int(pid)):
            tmp.unlink(missing_ok=True)


def atomic_write_bytes(path, data: bytes, *, overwrite: bool = False) -> Path:
    """Write ``data`` to ``path`` atomically.

    The content goes to ``.NAME.<pid>.<random>.tmp`` beside the target, is
    synced, given the permissions the umask allows (as any new file) and
    moved into place in one step. An error or interrupt removes the temporary
    file; one left by a killed run is removed by the next write of the target.
    ``overwrite`` replaces only a regular file, never a directory, a link, a
    pipe or a device.

    Parameters
    ----------
    path : str or Path
        Target file; its directory must exist.
    data : bytes
        The whole content.
    overwrite : bool
        Replace an existing file (the CLI's ``--force``).

    Returns
    -------
    Path
        The path written.
    """
    p = Path(path)
    if p.is_dir():
        raise ModelError("is a directory", field="output", value=str(p), valid="a file path")
    if p.exists() or p.is_symlink():
        if not overwrite:
            raise ModelError(
                "file exists",
                field="output",
                value=str(p),
                valid="a new path, or --force (overwrite=True) to replace it",
            )
        if p.is_symlink() or not stat.S_ISREG(p.lstat().st_mode):
            raise ModelError(
                "is not a regular file, so it is not replaced",
                field="output",
                value=str(p),
                valid="a new path, or a regular file to replace with --force",
            )
    if not p.parent.is_dir():
        raise ModelError(
            "directory does not exist", field="output", value=str(p), valid="a path in an existing directory"
        )
    _remove_stale_temps(p)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.{os.getpid()}.", suffix=".tmp", dir=p.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a written file honours the umask
        os.replace(tmp, p)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return p


def atomic_write_text(path, text: str, *, overwrite: bool = False) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; see :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, text.encode("utf-8"), overwrite=overwrite)
