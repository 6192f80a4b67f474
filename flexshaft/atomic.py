"""Writing files safely: never overwrite silently, never leave half a file.

Every writer in flexshaft goes through :func:`atomic_write_text` (or its bytes
twin): the content goes to a temporary file beside the target and is moved
into place in one step, so an error leaves the target as it was.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import ModelError

__all__ = ["atomic_write_bytes", "atomic_write_text"]


def atomic_write_bytes(path, data: bytes, *, overwrite: bool = False) -> Path:
    """Write ``data`` to ``path`` atomically.

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
    if p.exists() and not overwrite:
        raise ModelError(
            "file exists",
            field="output",
            value=str(p),
            valid="a new path, or --force (overwrite=True) to replace it",
        )
    if not p.parent.is_dir():
        raise ModelError(
            "directory does not exist", field="output", value=str(p), valid="a path in an existing directory"
        )
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, p)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return p


def atomic_write_text(path, text: str, *, overwrite: bool = False) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; see :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, text.encode("utf-8"), overwrite=overwrite)
