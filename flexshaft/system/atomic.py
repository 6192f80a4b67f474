"""Writing files safely: never overwrite silently, never leave half a file.

Every writer in flexshaft goes through :func:`atomic_write_text` (or its bytes
twin): the content goes to a temporary file beside the target and is moved
into place in one step, so an error leaves the target as it was.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import stat
import tempfile
from pathlib import Path

from ..errors import ModelError

__all__ = [
    "OUTPUT_MARKER",
    "refused_write",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_output_folder",
    "prepare_output_folder",
    "in_flight",
    "OutputError",
    "output_error",
    "report_temporaries",
]


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


def _dead_writers_temp(name: str, target: str) -> bool:
    """Whether ``name`` is a temporary file of the file ``target`` (``.TARGET.<pid>.<random>.tmp``,
    as :func:`atomic_write_bytes` names them) whose writer is gone: a killed writer's leftover."""
    head = f".{target}."
    if not (name.startswith(head) and name.endswith(".tmp")):
        return False
    pid = name[len(head) :].split(".", 1)[0]
    return pid.isdigit() and not _alive(int(pid))


def _remove_stale_temps(p: Path) -> None:
    """Temporary files of this target left by a killed writer (its process is gone)."""
    for tmp in p.parent.glob(f".{glob.escape(p.name)}.*.tmp"):
        if _dead_writers_temp(tmp.name, p.name):
            tmp.unlink(missing_ok=True)


def _stale_marker_temp(name: str) -> bool:
    """Whether ``name`` is a temporary file of :data:`OUTPUT_MARKER` whose writer was killed: the
    folder was being marked, so it holds nothing of anyone's (the next marking removes it)."""
    return _dead_writers_temp(name, OUTPUT_MARKER)


def _refuse_an_input(p: Path) -> None:
    """An output is never one of the files this command read (:mod:`flexshaft.system.inputs`), ``--force``
    or not: through a symbolic link or a hard link it is still the input."""
    from .inputs import same_input

    hit = same_input(p)
    if hit is None:
        return
    shown = os.path.relpath(hit)
    if shown.startswith(".."):
        shown = str(hit)
    raise ModelError(
        f"is the input file {shown!r}: an output never replaces an input, --force or not",
        field="output",
        value=str(p),
        valid="a path that is none of the command's input files",
    )


#: The temporary files being written now (absolute paths), and whom to tell of each one: the CLI's
#: watchdog (:mod:`flexshaft.system.watchdog`) removes those still there if it has to kill this process.
_IN_FLIGHT: set[str] = set()
_REPORT: list = []


def in_flight() -> frozenset[str]:
    """The temporary files this process is writing at this moment (absolute paths)."""
    return frozenset(_IN_FLIGHT)


def report_temporaries(report) -> None:
    """Call ``report(live, path)`` when a temporary file appears (True) and when it is gone (False)."""
    _REPORT.append(report)


def _track(tmp: str, live: bool) -> None:
    path = os.path.abspath(tmp)
    (_IN_FLIGHT.add if live else _IN_FLIGHT.discard)(path)
    for report in _REPORT:
        report(live, path)


#: What a user can do about the operating system's refusals a writer meets (the others: "a path
#: flexshaft can write").
_REMEDIES = {
    errno.ENOSPC: "free space on that disk, or a path on another",
    errno.EDQUOT: "room in your disk quota, or a path on another disk",
    errno.EFBIG: "a file system that takes files this large, or a smaller output",
    errno.EROFS: "a path on a file system mounted for writing",
    errno.EACCES: "a folder you may write to",
    errno.EPERM: "a folder you may write to",
}


def refused_write(err: OSError) -> bool:
    """Whether ``err`` is the system refusing to write a file it names (:data:`_REMEDIES`' reasons)."""
    return err.filename is not None and err.errno in _REMEDIES


class OutputError(ModelError):
    """An output the operating system refused to take (:func:`output_error`). It names the output
    itself, so it keeps no other file as its place (:meth:`located` gives it back unchanged: the
    model file a command read is not where a full disk is)."""

    def located(self, *, file: str | None = None, component: str | None = None) -> ModelError:
        return self


def output_error(err: OSError, path=None) -> OutputError:
    """The operating system's refusal to write an output (a full disk, a read-only folder, a quota,
    a file too large) as the one-line error users get: it names the output (``path``, else the
    file the error names), the system's reason with its code (``ENOSPC``) and what would do.

    Parameters
    ----------
    err : OSError
        What the write, the folder's creation or the flush of a stream raised.
    path : str or Path, optional
        The output as the user named it (not the temporary file beside it).
    """
    where = path if path is not None else (err.filename if err.filename is not None else "?")
    code = errno.errorcode.get(err.errno) if err.errno is not None else None
    reason = err.strerror or str(err) or type(err).__name__
    return OutputError(
        f"cannot be written: {reason}{f' ({code})' if code else ''}",
        field="output",
        value=str(where),
        valid=_REMEDIES.get(err.errno, "a path flexshaft can write"),
    )


@contextlib.contextmanager
def _filled_temporary(p: Path, data: bytes):
    """A temporary file beside ``p`` (``.NAME.<pid>.<random>.tmp``, a killed writer's left over ones
    removed first) holding ``data``, synced, with the permissions the umask gives a new file (mkstemp
    makes 0600): its path, for the caller to move into place. The watchdog knows of it while it
    exists (:func:`_track`); it is removed on the way out, whatever happened (after a move, there is
    nothing left to remove). An OSError is the system refusing the output ``p``, named."""
    try:
        _remove_stale_temps(p)
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.{os.getpid()}.", suffix=".tmp", dir=p.parent)
    except OSError as err:  # a read-only or full file system, a folder not ours: not even a start
        raise output_error(err, p) from None
    _track(tmp, True)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        yield tmp
    except OSError as err:  # a full disk, a quota, a file too large: named, not a defect
        raise output_error(err, p) from None
    finally:
        # the target stays as it was (absent, or the old file); the half-written temporary goes
        with contextlib.suppress(OSError):
            Path(tmp).unlink(missing_ok=True)
        _track(tmp, False)


def atomic_write_bytes(path, data: bytes, *, overwrite: bool = False) -> Path:
    """Write ``data`` to ``path`` atomically.

    The content goes to ``.NAME.<pid>.<random>.tmp`` beside the target, is
    synced, given the permissions the umask allows (as any new file) and
    moved into place in one step. An error or interrupt removes the temporary
    file; one left by a killed run is removed by the next write of the target.
    ``overwrite`` replaces only a regular file, never a directory, a link, a
    pipe or a device; and never a file this command read, ``overwrite`` or
    not (:func:`flexshaft.system.inputs.same_input`: links and hard links followed).

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
    _refuse_an_input(p)
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
    with _filled_temporary(p, data) as tmp:
        os.replace(tmp, p)
    return p


def atomic_write_text(path, text: str, *, overwrite: bool = False) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; see :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, text.encode("utf-8"), overwrite=overwrite)


# --- output folders (a report): new, empty, or flexshaft's own ----------------------------------------

OUTPUT_MARKER = ".flexshaft-output"
"""The file flexshaft puts in every output folder it creates; ``--force`` works only where it is."""

_FOLDER_VALID = "a new folder, an empty one, or one flexshaft wrote (it holds .flexshaft-output)"


def _home_folders() -> set[Path]:
    """Every home folder: this user's and each in the password database (resolved)."""
    homes = []
    try:
        homes.append(Path.home())
    except (RuntimeError, KeyError, OSError):  # no HOME and no password entry
        pass
    try:
        import pwd

        homes += [Path(entry.pw_dir) for entry in pwd.getpwall() if entry.pw_dir]
    except (ImportError, OSError):  # not a POSIX system, or no database
        pass
    found = set()
    for h in homes:
        try:
            found.add(h.resolve())
        except (OSError, RuntimeError):  # a link loop: that home cannot be the output's resolved path
            continue
    return found


def check_output_folder(path, *, force: bool = False, inputs=(), files=(), option: str = "output") -> Path:
    """Refuse an output folder flexshaft must not write into; nothing is created or changed.

    A folder is accepted when it is new, empty, or holds :data:`OUTPUT_MARKER` (flexshaft
    created it); a temporary file of the marker whose writer was killed does not count (a folder
    killed while it was being marked is still empty). It is refused, ``force`` or not, when it
    is a symbolic link (the linked folder stays untouched), the root folder, a home folder
    (``Path.home()`` or any home in the password database), a folder holding one of ``inputs``
    (at any depth), a folder that is not empty and has no marker, or a path that starts with a
    ``~`` the shell did not expand.
    Without ``force`` a marked folder is refused when one of ``files`` is already in it; with
    ``force`` those files may be replaced, and only when each is a regular file.

    Parameters
    ----------
    path : str or Path
        The output folder as the user gave it.
    force : bool
        Replace flexshaft's own files in a marked folder (the CLI's ``--force``).
    inputs : iterable of str or Path
        The command's input files; the folder must not hold any of them, nor any file read so far
        (:func:`flexshaft.system.inputs.recorded_inputs`: a model's parts and tables too).
    files : iterable of str
        The names the writer puts in the folder (e.g. ``index.html``).
    option : str
        What the errors call the path (the CLI's ``-o``).

    Returns
    -------
    Path
        ``path`` as a Path (not resolved: the writer uses what the user named).

    Raises
    ------
    ModelError
        Naming ``option``, the path and what is valid.
    """

    def refused(message: str, path, valid: str = _FOLDER_VALID) -> ModelError:
        return ModelError(message, field=option, value=str(path), valid=valid)

    if not str(path).strip():
        raise refused("names no folder", path, "a folder path")
    p = Path(path)
    if p.parts and p.parts[0].startswith("~"):
        raise refused(
            "starts with '~', which only the shell expands (it would make a folder named '~' here)",
            path,
            "the folder's full path (an unquoted ~ lets the shell write it out)",
        )
    if p.is_symlink():
        raise refused(
            "is a symbolic link: flexshaft never writes a folder through a link",
            path,
            "the real folder's path, or a new folder",
        )
    try:
        real = p.resolve()
    except (OSError, RuntimeError) as err:  # a link loop among its parents
        raise refused(f"cannot be resolved ({err})", path) from None
    if real == Path(real.anchor):
        raise refused("is the root folder", path)
    if real in _home_folders():
        raise refused("is a home folder", path, "a new folder inside it, e.g. ~/reports/NAME")
    from .inputs import recorded_inputs

    # The inputs named, and every file this command has read so far (a model's STEP parts, tables)
    for source in (*inputs, *recorded_inputs()):
        try:
            held = Path(source).resolve()
        except (OSError, RuntimeError):
            continue  # an input that cannot be resolved is refused by its reader
        if real == held or real in held.parents:
            raise refused(
                f"holds the input file {str(source)!r}", path, "a folder that holds none of the inputs"
            )
    if not (p.exists() or p.is_symlink()):
        return p
    if not p.is_dir():
        raise refused("is not a folder", path, "a folder path for the output")
    entries = [e for e in os.listdir(p) if not _stale_marker_temp(e)]
    if not entries:
        return p
    marker = p / OUTPUT_MARKER
    if not (marker.is_file() and not marker.is_symlink()):
        raise refused("is not empty and flexshaft did not write it (no .flexshaft-output in it)", path)
    for name in files:
        target = p / name
        if not (target.exists() or target.is_symlink()):
            continue
        if not force:
            raise refused(
                "file exists", target, "a new folder, or --force to replace flexshaft's files in it"
            )
        if target.is_symlink() or not stat.S_ISREG(target.lstat().st_mode):
            raise refused(
                "is not a regular file, so it is not replaced",
                target,
                "a folder whose report files are regular files",
            )
    return p


def prepare_output_folder(
    path,
    *,
    force: bool = False,
    inputs=(),
    files=(),
    option: str = "output",
    writer: str = "flexshaft",
    note: str = "",
) -> Path:
    """Check an output folder (:func:`check_output_folder`), then create it and mark it as flexshaft's.

    A new folder is made (with its missing parents) and given :data:`OUTPUT_MARKER`, whose text
    says which command wrote it; so is an empty one. A marked folder keeps its marker, and so does
    one that another writer marked meanwhile: the marker is created, never replaced. The files
    written into the folder afterwards go through :func:`atomic_write_bytes`, each atomically.

    Parameters
    ----------
    path, force, inputs, files, option
        As for :func:`check_output_folder`.
    writer : str
        What writes the folder, recorded in the marker (e.g. ``"flexshaft report"``).
    note : str
        More lines for the marker (a study names its study file there: the folder is that
        study's from its first moment on, whatever happens to the run).

    Returns
    -------
    Path
        The folder, ready for the writer's files.
    """
    rules = {"force": force, "inputs": inputs, "files": files, "option": option}
    p = check_output_folder(path, **rules)
    made = False
    if not p.exists():
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
            p.mkdir()
        except FileExistsError:  # made by someone else meanwhile: judge it afresh
            return prepare_output_folder(path, writer=writer, note=note, **rules)
        except OSError as err:  # a full disk, a read-only parent: the folder named, one line
            raise output_error(err, p) from None
        made = True
    marker = p / OUTPUT_MARKER
    if not (marker.exists() or marker.is_symlink()):
        text = f"written by {writer}; --force replaces flexshaft's own files in this folder, nothing else\n"
        try:
            _create(marker, (text + (note.rstrip("\n") + "\n" if note else "")).encode("utf-8"))
        except (OSError, OutputError) as err:
            if made:  # no empty folder left behind by a run that wrote nothing
                with contextlib.suppress(OSError):
                    p.rmdir()
            if isinstance(err, OutputError):  # the marker's writing, named already
                raise
            raise output_error(err, marker) from None
    return p


def _create(p: Path, data: bytes) -> None:
    """Write a new file whole, unless ``p`` appeared meanwhile (then it stands as it is).

    The bytes go to a temporary file first, which is then hard-linked to ``p``: a link never
    replaces an existing name, so of two writers racing only the first one's file is there, and a
    kill leaves either no file or the whole one. A file system without hard links gets a rename,
    after a last look that ``p`` is still absent.
    """
    with _filled_temporary(p, data) as tmp:
        try:
            os.link(tmp, p)
        except FileExistsError:
            pass  # another writer's file came first: it stands
        except OSError:  # no hard links here (FAT, some network file systems)
            if not (p.exists() or p.is_symlink()):
                os.replace(tmp, p)
