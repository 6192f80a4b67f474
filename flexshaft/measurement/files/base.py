"""What the measured-file readers share: a file's channel list, naming a channel, the checks made before
anything is read, and the guard that turns a foreign library's failure into one ModelError.

A format module (:mod:`.tdms`, :mod:`.mdf`, :mod:`.hdf5`, :mod:`.matlab`) opens its file as a source:
its :class:`Entry` list (every channel, metadata only), ``claim(entry)`` (the samples its header claims,
checked against what the file stores, nothing read) and ``read(entry, plan)`` giving one channel's
:class:`Raw` samples - or, where ``plan`` and the file stores them plainly, where they lie
(:class:`~.plan.Planned`) - with its file unit and timing. :mod:`.survey` finds the channels asked for
and their time; :mod:`.assemble` makes the table of them.
"""

from __future__ import annotations

import contextlib
import gc
import logging
import sys
import threading
import warnings
from dataclasses import dataclass

import numpy as np

from ...errors import ModelError
from ...system.inputs import MB, SIGNALS, ceiling_bytes
from ...validation import MAX_FREQUENCY_HZ

__all__ = [
    "EXTRA",
    "LISTED",
    "RATE_RANGE_HZ",
    "Entry",
    "Raw",
    "Stamps",
    "Uniform",
    "check_claim",
    "check_total",
    "error",
    "guarded",
    "label_list",
    "need",
    "resolve",
    "uniform_timing",
]

#: What to install for every measured format (pyproject's optional dependencies).
EXTRA = "pip install 'flexshaft[measured]'"
#: The most channel names an error lists (a logger's file can hold thousands).
LISTED = 20
#: The sampling rates a file's timing may state, Hz: from a sample every 11.6 days (a monitoring
#: logger's slowest) to 1 GHz (:data:`~flexshaft.validation.MAX_FREQUENCY_HZ`, above any acquisition
#: of a drivetrain's signals). Outside them a rate or a step is damage, not a record (a step of
#: 5e-324 s made the rate overflow to inf).
RATE_RANGE_HZ = (1e-6, MAX_FREQUENCY_HZ)


@dataclass(frozen=True)
class Entry:
    """One channel of a file, as its metadata names it (nothing read).

    Attributes
    ----------
    group : str
        Its group: a TDMS group's name, an MDF channel group's index (``"0"``, ``"1"``...), an HDF5
        dataset's parent path (``"bench/run1"``, ``""`` at the root); ``""`` in a MAT file.
    name : str
        Its name (the last part of an HDF5 path).
    handle : object
        The format's own key for it.
    aliases : tuple of str
        Other names of its group (an MDF channel group's acquisition name).
    numeric : bool
        Its samples are numbers (what the default selection takes).
    time : bool
        A time channel (an MDF master, a channel named ``time``): not a signal by default.
    """

    group: str
    name: str
    handle: object  # hashable: two channels of one name in one group stay two
    aliases: tuple = ()
    numeric: bool = True
    time: bool = False

    @property
    def label(self) -> str:
        """``GROUP/NAME``, or the name alone where the format has no groups."""
        return f"{self.group}/{self.name}" if self.group else self.name

    def in_group(self, group: str) -> bool:
        return group == self.group or group in self.aliases


@dataclass(frozen=True)
class Uniform:
    """Sample times given by a start and a step (TDMS ``wf_start_offset``/``wf_increment``), s."""

    start: float
    step: float


@dataclass(frozen=True)
class Stamps:
    """Sample times stored with the samples (an MDF group's master channel), in ``unit``."""

    values: np.ndarray
    unit: str | None
    entry: Entry | None = None  # the channel they come from, for a unit stated for it


@dataclass
class Raw:
    """One channel as its file holds it: the samples (or their plan, :class:`~.plan.Planned`), the unit
    its metadata states, its own timing."""

    values: object  # ndarray, or Planned
    unit: str | None
    timing: Uniform | Stamps | None = None


def _real(value) -> float | None:
    """``value`` as a float where it is a real number (an int or float, numpy's too), else None: a
    boolean (``True`` is no 1 Hz), text or anything else is no number of a timing."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer | np.floating):
        return None
    return float(value)


def uniform_timing(path, label: str, key: str, value, *, rate: bool, start=0.0, what: str = "attribute"):
    """A channel's :class:`Uniform` timing from its metadata, every number checked.

    Parameters
    ----------
    label : str
        The channel (``GROUP/NAME``).
    key : str
        The attribute (property) stating it: a rate (``rate_hz``, Hz) where ``rate``, else a step
        (``wf_increment``, s).
    value : object
        Its value as the file holds it.
    start : object
        The first sample's time, s (``wf_start_offset``; 0 when the file states none).
    what : str
        What the format calls a channel's metadata item (``attribute``, ``property``).

    Raises
    ------
    ModelError
        One naming the attribute, its value and unit and what is valid: a value that is no real number
        (a boolean, text), not finite, or whose rate lies outside :data:`RATE_RANGE_HZ`.
    """
    lo, hi = RATE_RANGE_HZ
    x = _real(value)
    if rate:
        unit, valid = "Hz", f"a number from {lo:g} to {hi:g} Hz (the sampling rate)"
        ok = x is not None and lo <= x <= hi  # False for NaN
    else:
        unit, valid = (
            "s",
            f"a number from {1 / hi:g} to {1 / lo:g} s (the sampling step; a rate of {lo:g} to {hi:g} Hz)",
        )
        ok = x is not None and 1 / hi <= x <= 1 / lo
    if not ok:
        why = "is not a number" if x is None else "is not finite" if not np.isfinite(x) else "is out of range"
        shown = unit if x is not None else None  # "true Hz" would read as a quantity
        raise error(path, why, field=f"{label} {what} {key}", value=value, unit=shown, valid=valid)
    t0 = _real(start)
    if t0 is None or not np.isfinite(t0):
        raise error(
            path,
            "is not a finite number",
            field=f"{label} {what} wf_start_offset",
            value=start,
            unit="s",
            valid="the first sample's time, s",
        )
    return Uniform(t0, 1.0 / x if rate else x)


def error(path, message: str, **fields) -> ModelError:
    return ModelError(message, file=str(path), **fields)


def label_list(entries) -> str:
    """At most :data:`LISTED` channels by label, and how many there are in all."""
    entries = list(entries)
    shown = ", ".join(repr(e.label) for e in entries[:LISTED])
    if len(entries) > LISTED:
        shown += f", ... ({len(entries)} channels in all)"
    return shown or "none: the file holds no channels"


def resolve(path, entries, wanted, group: str | None, field: str) -> Entry:
    """The one channel ``wanted`` names, within ``group`` when given.

    A channel is named by its name; where that is not unique (the same name in two groups) or the
    group is wanted anyway, ``group`` names the group, or the name is written ``GROUP/NAME``.
    """
    if not isinstance(wanted, str) or not wanted.strip():
        raise error(path, "is not a channel name", field=field, value=wanted, valid="a channel's name")
    name = wanted.strip()
    pool = [e for e in entries if group is None or e.in_group(group)]
    found = [e for e in pool if e.name == name]
    if not found and group is None and "/" in name:
        # GROUP/NAME, split at each '/' in turn (a group's own name may hold one: an HDF5 path)
        found = [e for e in pool if e.label == name.lstrip("/")] or [
            e
            for i, c in enumerate(name)
            if c == "/"
            for e in pool
            if e.in_group(name[:i]) and e.name == name[i + 1 :]
        ]
    if len(found) == 1:
        return found[0]
    if found:
        groups = ", ".join(repr(e.group) for e in found[:LISTED])
        raise error(
            path,
            f"is a channel of several groups ({groups})",
            field=field,
            value=wanted,
            valid="the group named: group='GROUP' (command line: --group GROUP), or 'GROUP/NAME'",
        )
    where = f" in group {group!r}" if group is not None else ""
    valid = "one of " + label_list(pool)
    if group is not None and not pool:
        valid = "a group of the file; its channels: " + label_list(entries)
    raise error(path, f"no such channel{where}", field=field, value=wanted, valid=valid)


def check_claim(path, label: str, n: int, itemsize: int, stored_limit: int | None) -> None:
    """Refuse a channel whose header claims more samples than can be: before anything is allocated.

    Parameters
    ----------
    n : int
        The samples its metadata claims.
    itemsize : int
        Bytes each takes in the file.
    stored_limit : int or None
        The bytes the file (or the data blocks) can hold of it, when stored uncompressed; None where
        compression makes the file's size no bound.

    The samples are returned as float64, so ``8 n`` bytes must fit under the signal file's ceiling
    (``FLEXSHAFT_MAX_FILE_MB``), compressed or not.
    """
    limit = ceiling_bytes(SIGNALS)
    if n < 0 or n * 8 > limit:
        raise error(
            path,
            f"claims {n:,} samples ({n * 8 / MB:,.0f} MB as numbers), above the {limit / MB:g} MB ceiling "
            "for a signal file",
            field=label,
            valid="a channel of at most that size, or a higher ceiling: FLEXSHAFT_MAX_FILE_MB=N",
        )
    if stored_limit is not None and n * itemsize > stored_limit:
        raise error(
            path,
            f"is damaged: its header claims {n:,} samples of {itemsize} bytes, where the file holds "
            f"{stored_limit:,} bytes for them",
            field=label,
            valid="an undamaged, complete file",
        )


def check_total(path, claims) -> None:
    """Refuse channels whose claims together exceed the signal file's ceiling as float64 (each alone may
    pass): ``claims`` is each channel's samples, checked before anything is read."""
    limit = ceiling_bytes(SIGNALS)
    total = sum(claims)
    if total * 8 > limit:
        raise error(
            path,
            f"claims {total:,} samples in the {len(claims)} channels asked for ({total * 8 / MB:,.0f} MB as "
            f"numbers), above the {limit / MB:g} MB ceiling for a signal file",
            field="channels",
            valid="fewer channels at once, or a higher ceiling: FLEXSHAFT_MAX_FILE_MB=N",
        )


def need(module: str, package: str, suffix: str, path):
    """Import the reader library ``module``, or say what to install (one ModelError naming the file)."""
    try:
        return __import__(module, fromlist=["_"])
    except ImportError:
        raise ModelError(f"reading {suffix} needs {package}: {EXTRA}", file=str(path)) from None


# The libraries' own loggers: what they log while reading is a sign of damage (npTDMS reads a truncated
# file partly and warns), and must not reach the user's terminal as extra lines.
_LOGGERS = ("nptdms", "asammdf", "h5py", "canmatrix")
# One read at a time changes the loggers and the unraisable hook: both are the process's.
_QUIET = threading.RLock()


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record):
        try:
            self.messages.append(record.getMessage())
        except Exception:  # noqa: BLE001 - a message that cannot be formatted is still a warning
            self.messages.append(str(record.msg))


@contextlib.contextmanager
def _quiet():
    """The libraries' log records collected (not printed), their Python warnings and unraisable
    exceptions (asammdf's ``__del__`` of a half-built object) swallowed: the one line is ours."""
    with _QUIET:
        handler = _Collect()
        saved = []
        # each library logger and its modules' own (npTDMS gives each module a console handler)
        names = [
            n
            for n in list(logging.Logger.manager.loggerDict)
            if any(n == p or n.startswith(p + ".") for p in _LOGGERS)
        ]
        for name in {*_LOGGERS, *names}:
            log = logging.getLogger(name)
            saved.append((log, log.propagate, log.handlers[:]))
            log.handlers = [handler]
            log.propagate = False
        hook = sys.unraisablehook
        sys.unraisablehook = lambda unraisable: None
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # a value that overflows is caught as non-finite after
                yield handler.messages
        finally:
            sys.unraisablehook = hook
            for log, propagate, handlers in saved:
                log.handlers = handlers
                log.propagate = propagate


def _first_line(text: str, limit: int = 200) -> str:
    line = next((s.strip() for s in str(text).splitlines() if s.strip()), "")
    return line if len(line) <= limit else line[: limit - 3] + "..."


def guarded(path, what: str, library: str, work):
    """``work()``, whose failures are one ModelError naming the file: never the library's exception.

    A ModelError of ``work`` is raised as it is; any other exception (the library's, a ``struct.error``
    of a truncated block, a MemoryError) becomes "is not a readable {what}", naming the library's
    complaint. A warning the library logged while reading also refuses the file (a truncated TDMS
    file is read partly, with a warning): it outranks an unknown channel, which the damage explains.
    KeyboardInterrupt and SystemExit pass untouched.
    """
    failure = None
    with _quiet() as logged:
        try:
            result = work()
        except ModelError as err:
            failure = err.with_traceback(None)  # its frames (and the file objects they hold) go now
        except Exception as exc:  # noqa: BLE001 - the library boundary: no foreign exception passes
            detail = _first_line(str(exc))
            kind, module = type(exc).__name__, type(exc).__module__
            if module != "builtins":  # struct.error, zlib.error, asammdf's MdfException
                kind = f"{module.split('.')[0].lstrip('_')}.{kind}"
            failure = error(
                path,
                f"is not a readable {what} ({library}: {kind}" + (f": {detail})" if detail else ")"),
                valid=f"an undamaged, complete {what}",
            )
            del exc
        if logged:
            more = f"; {len(logged) - 1} more warnings" if len(logged) > 1 else ""
            failure = error(
                path,
                f"is damaged ({library}: {_first_line(logged[0])}{more})",
                valid=f"an undamaged, complete {what}",
            )
        if failure is not None:
            # the half-read objects of the failure (its traceback's frames) go now, under the hook
            gc.collect()
    if failure is not None:
        raise failure
    return result
