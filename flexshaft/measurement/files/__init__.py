"""Measured test-bench files: TDMS, MDF 3/4, HDF5, MATLAB and universal files read into a
:class:`~flexshaft.measurement.signaltable.SignalTable`, as a CSV signal file is.

================  ============================  ==========  =========================================
suffix            format                        library     channel names
================  ============================  ==========  =========================================
.tdms             NI TDMS (LabVIEW)             npTDMS      GROUP/CHANNEL, or CHANNEL
.mf4 .mdf .dat    ASAM MDF 4 and 3              asammdf     GROUP/NAME (group index or acquisition
                                                            name), or NAME
.h5 .hdf5         HDF5                          h5py        the dataset's path, or its last name
.mat              MATLAB v5-v7 / v7.3 (HDF5)    scipy/h5py  the variable's name
.uff .unv         universal file, dataset 58    pyuff       the record's first ID line (id1), or
                  time records (function 1)                 NODE:DIRECTION
================  ============================  ==========  =========================================

The suffix picks the format and the file's first bytes must agree (``TDSm``, ``MDF     ``, the HDF5
signature, the MAT header, a universal file's ``-1`` delimiter); a MAT file's version is read from
its header. A ``.dat`` file that is not MDF is read as a CSV signal file, as before. npTDMS, asammdf,
h5py and pyuff are optional (``pip install 'flexshaft[measured]'``), imported only when such a file is
read; without one the error says what to install.

Rules shared by every format (each format module's docstring has its own details: :mod:`.tdms`,
:mod:`.mdf`, :mod:`.hdf5`, :mod:`.matlab`, :mod:`.uff`):

- **Names.** A channel is named by its name; where two groups have one of that name, ``group=``
  (``--group``) names the group, or the name is written ``GROUP/NAME``. An unknown name is an error
  listing the channels there are (the first 20). The table's keys are the names (``GROUP/NAME``
  where two channels read share one). Without ``channels``, every numeric channel but time channels.
- **Units.** From the file's metadata (TDMS ``unit_string`` or ``NI_UnitDescription``, the MDF
  channel's unit, the HDF5 attribute ``units`` or ``unit``); a MAT file has none, so ``units=``
  (``--unit NAME=UNIT``) states them. A unit stated for a channel whose file states another is an
  error, as for a CSV header. Units are those of :data:`~flexshaft.measurement.signaltable.UNITS`, converted
  to SI; another is an error naming the channel, the unit and the valid ones.
- **Time.** A channel's own timing (TDMS waveform properties, the MDF master channel, HDF5 rate
  attributes), else a time channel beside it (``time_column``, or one named ``time``), else
  ``rate`` (Hz, from t = 0). ``time_column`` given wins over a channel's own timing. Channels of
  different sample times are brought to one uniform time base: the fastest channel's time stamps
  over the span all channels cover, the others interpolated linearly (:mod:`.assemble`); the
  table's ``notes`` say so. The fastest must be uniformly sampled (relative jitter <= 1e-6), the
  others increasing.
- **Untrusted files.** A damaged, truncated or hostile file is one ModelError naming the file and
  what is wrong, never the library's exception; a warning the library logs while reading refuses
  the file. What a header claims is checked before anything is allocated: a channel's length times
  its item size against the bytes the file stores for it - an HDF5 dataset against the storage
  allocated for it (every chunk stored; deflated chunks at most 1032:1), a TDMS channel against the
  file, an MDF group against its data blocks, a MAT variable against its element (or what its
  compressed data inflate to) - and its float64 size, and all the channels' together, against the
  signal file's ceiling (``FLEXSHAFT_MAX_FILE_MB``, 2048 MB by default). Timing attributes must be
  numbers (a boolean is none) whose rate lies within :data:`~.common.RATE_RANGE_HZ`, as must the
  rate of a time channel; a sample must stay finite in SI. The file must be a regular one within
  that ceiling, and is handed to the library open (no link swapped meanwhile, no sidecar index
  read). Nothing can run code: no pickles, no MATLAB objects, no HDF5 external links, external
  storage or virtual datasets.
- **Isolation.** The library reads in a forked child process (:func:`flexshaft.system.isolate.run_isolated`,
  which inherits the open file and the imported library): HDF5's C library can loop forever, and
  asammdf's C extension crash, on a corrupted file; either is then one ModelError naming the file
  after at most :func:`timeout_s`, not a hung or killed caller. The child's output goes to
  /dev/null, and its address space is capped (:data:`EXTRA_MEMORY` above what it inherits plus
  twice the signal file's ceiling), so a hostile structure that makes native code allocate without
  end gets a MemoryError, refused as damage, instead of the machine's memory. Where there is no
  ``fork`` (Windows), and in a multiprocessing pool's worker, the reading runs in the caller.
- **Speed.** The child surveys (:mod:`.survey`): names, units, time, claims. Samples stored plainly
  (HDF5 contiguous or unfiltered chunks, TDMS raw numbers, MDF 4 uncompressed records) are not read
  by the library: it says where they lie (:mod:`.plan`), and the caller reads them straight into its
  float64 arrays, testing each block finite while it is in the cache; the library's own first and
  last samples must agree with the plan's, else the library reads the file after all (a TDMS
  channel's ends only where their chunk is at most 1 MB: else npTDMS's own segment index). Other
  samples (compressed, scaled, MDF 3, MATLAB v5) the library reads and the child sends through the
  pipe. ``benchmarks/bench_measured.py`` times it against each library's own reading.
- **Memory.** Only the channels asked for are read, one at a time: planned ones once, into the
  caller's arrays (the peak is their float64 samples); those the library reads twice at most (the
  child's array, and the caller's copy as it arrives).
"""

from __future__ import annotations

import os
from pathlib import Path

from ...errors import ModelError
from ...system.inputs import MB, SIGNALS, ceiling_bytes, open_seekable
from ...system.isolate import Failure, run_isolated
from ...validation import check_real
from ..signaltable import SignalTable
from .base import RATE_RANGE_HZ, error, guarded, need

__all__ = [
    "read_frf_records",
    "EXTRA_MEMORY",
    "SECONDS_PER_MB",
    "SUFFIXES",
    "TIMEOUT_S",
    "is_measured",
    "read_measured",
    "timeout_s",
]

#: The suffixes read as measured files (lower case), and their formats.
SUFFIXES = {
    ".tdms": "tdms",
    ".mf4": "mdf",
    ".mdf": "mdf",
    ".dat": "mdf",
    ".h5": "hdf5",
    ".hdf5": "hdf5",
    ".mat": "mat",
    ".uff": "uff",
    ".unv": "uff",
}
_MDF_MAGICS = (b"MDF     ", b"UnFinMF ")
#: Seconds a reading may take at least before it counts as hung (a file of a few MB reads in well
#: under a second; a hung HDF5 read never ends).
TIMEOUT_S = 60.0
#: And per MB of the file: asammdf and h5py read 50-500 MB/s; 5 MB/s is a slow disk's worst.
SECONDS_PER_MB = 0.2
#: Bytes of address space the reading's child may add beyond what it inherits and twice the signal
#: file's ceiling (the libraries' own buffers and a record's pieces).
EXTRA_MEMORY = 1 << 30


def timeout_s(size: int) -> float:
    """Seconds the reading of a file of ``size`` bytes may take, s."""
    return TIMEOUT_S + SECONDS_PER_MB * size / MB


def _refused(path, failure: Failure) -> ModelError:
    """The reading's child crashed or hung: the file is damaged (its reader is trusted otherwise)."""
    if failure.kind == "timeout":
        return error(
            path,
            f"is damaged or too large: reading it took more than {failure.limit:.0f} s",
            valid="an undamaged file (a reader that loops on a corrupted structure is stopped)",
        )
    verb = "crashed" if failure.kind == "crashed" else "failed"  # failed: an exception guarded() let pass
    return error(
        path, f"is damaged: its reader {verb} on it ({failure.detail})", valid="an undamaged, complete file"
    )


def is_measured(path) -> bool:
    """Whether ``path`` is read as a measured file: its suffix is one of :data:`SUFFIXES`, and a
    ``.dat`` file starts as an MDF file does (another ``.dat`` file is a CSV signal file).

    Raises
    ------
    ModelError
        A ``.dat`` path that is no readable regular file (the CSV reader's refusal, word for word).
    """
    try:
        suffix = Path(path).suffix.lower()
    except TypeError:
        return False
    if suffix != ".dat":
        return suffix in SUFFIXES
    with open_seekable(path, SIGNALS) as fh:
        return fh.read(8) in _MDF_MAGICS


def _check_options(channels, group, rate, time_column):
    if isinstance(channels, str):
        channels = [channels]
    elif channels is not None:
        try:
            channels = list(channels)
        except TypeError:
            raise ModelError(
                "is not a list of channel names", field="channels", value=channels, valid="e.g. ['torque']"
            ) from None
    if group is not None and (not isinstance(group, str) or not group.strip()):
        raise ModelError("is not a group name", field="group", value=group, valid="a group's name")
    if time_column is not None and (not isinstance(time_column, str) or not time_column.strip()):
        raise ModelError("is not a channel name", field="time_column", value=time_column, valid="a name")
    if rate is not None:
        rate = check_real(rate, "rate", "Hz", lo=RATE_RANGE_HZ[0], hi=RATE_RANGE_HZ[1])
    return channels, (group.strip() if group is not None else None), rate


def _format_module(fh, path, size: int, fmt: str):
    """The format module for ``fmt`` (a MAT file's by its header), once the file's first bytes agree."""
    head = fh.read(128)
    fh.seek(0)
    if not head:
        raise error(path, "is empty", valid="a measured file (TDMS, MDF, HDF5 or MAT)")
    if fmt == "mat":
        from .matlab import header_version

        version = header_version(head)
        if version is None:
            raise error(
                path,
                "is not a MATLAB file (no MATLAB 5.0 or 7.3 header)",
                valid="a MATLAB file saved with -v7 or -v7.3",
            )
        fmt = "mat73" if version == "7.3" else "mat5"
    if fmt == "tdms":
        from . import tdms as module

        if not head.startswith(module.MAGIC):
            raise error(path, f"is not a TDMS file (it starts {head[:4]!r})", valid="a TDMS file ('TDSm')")
    elif fmt == "mdf":
        from . import mdf as module

        if head[:8] not in module.MAGICS:
            raise error(path, f"is not an MDF file (it starts {head[:8]!r})", valid="an MDF 3 or 4 file")
    elif fmt == "uff":
        from . import uff as module

        if not module.is_uff(head):
            raise error(
                path, f"is not a universal file (it starts {head[:8]!r})", valid="a UFF/UNV file ('    -1')"
            )
    elif fmt in ("hdf5", "mat73"):
        from . import hdf5 as module

        found = module.superblock_offset(fh, size)
        fh.seek(0)
        if found is None:
            what = "a MATLAB v7.3 file (no HDF5 data after its header)" if fmt == "mat73" else "an HDF5 file"
            raise error(path, f"is not {what}", valid="an HDF5 file (its signature at byte 0, 512, 1024...)")
    else:
        from . import matlab as module
    return module, fmt == "mat73"


def read_measured(
    path,
    channels=None,
    units=None,
    *,
    time_column: str | None = None,
    group: str | None = None,
    rate: float | None = None,
) -> SignalTable:
    """Read channels of a measured test-bench file (TDMS, MDF, HDF5, MATLAB) in SI on one time base.

    Parameters
    ----------
    path : str or Path
        The file; its suffix picks the format (module docstring).
    channels : str or sequence of str, optional
        The channels, each by name or ``GROUP/NAME``. Default: every numeric channel but time
        channels (within ``group`` when given).
    units : dict of str to str, optional
        Units of channels whose file states none (every channel of a MAT file), by name:
        ``{"torque": "kNm"}``; one the file states otherwise is an error.
    time_column : str, optional
        A channel holding the sample times (s or ms, or TDMS timestamps); default: each channel's own
        timing, else a channel named ``time`` beside it.
    group : str, optional
        The group the channels are in (TDMS group, MDF channel group index or acquisition name, HDF5
        group path).
    rate : float, optional
        The sampling rate, Hz, of channels the file gives no time for (a MAT file without a time
        variable); an error where the file has their time.

    Returns
    -------
    SignalTable
        Time in s from the file's own zero, every channel in SI; ``notes`` say what reading changed
        (channels interpolated to one time base, the record cut to their common span).

    Raises
    ------
    ModelError
        A damaged or hostile file, an unknown channel or group, a unit missing, unknown or stated
        twice, no time, a library not installed.
    """
    from .assemble import assemble
    from .layout import Disagrees
    from .survey import survey

    try:
        p = Path(path)
    except TypeError:
        raise ModelError("is not a path", field="path", value=path, valid="a file path") from None
    fmt = SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        raise ModelError(
            "unknown file type",
            field="path",
            value=str(p),
            valid="a file ending in " + ", ".join(SUFFIXES) + " (or .csv: flexshaft.read_signals)",
        )
    channels, group, rate = _check_options(channels, group, rate, time_column)
    if units is not None and not isinstance(units, dict):
        raise ModelError("must map channel names to unit strings", field="units", value=units, valid="a dict")

    time_column = time_column.strip() if time_column is not None else None
    with open_seekable(p, SIGNALS) as fh:
        size = os.fstat(fh.fileno()).st_size
        module, matlab = _format_module(fh, p, size, fmt)
        lib = need(module.LIBRARY[0], module.LIBRARY[1], p.suffix.lower(), p)
        what = "MATLAB v7.3 file" if matlab else module.WHAT

        def work(plan: bool):
            own = _own(fh)
            opened = (
                module.source(own, p, size, lib, matlab=True) if matlab else module.source(own, p, size, lib)
            )
            with own, opened as src:
                return survey(
                    p,
                    src,
                    channels=channels,
                    units=units,
                    time_column=time_column,
                    group=group,
                    rate=rate,
                    plan=plan,
                )

        def surveyed(plan: bool):
            return _in_child(p, what, module.LIBRARY[1], size, lambda: work(plan))

        try:
            return assemble(p, fh, size, surveyed(plan=True))
        except Disagrees:
            # a plan read other numbers than the library's at a channel's ends: the library reads all
            return assemble(p, fh, size, surveyed(plan=False))


def _own(fh):
    """A file object of its own over the open file ``fh``, at its start: a reading before this one (in
    another process: the one whose plan the library's samples disagreed with) moved the file's
    offset, which ``fh``'s buffer would not know of."""
    own = open(os.dup(fh.fileno()), "rb")  # noqa: SIM115 - the caller closes it, after the library
    own.seek(0)  # its first seek moves the offset: the libraries start at the file's start
    return own


def _in_child(p: Path, what: str, library: str, size: int, work):
    """``work()`` in a forked child: a crash or a hang of the library's native code is one ModelError
    naming the file, its failures are :func:`~.base.guarded`'s, its memory and time are capped."""
    return run_isolated(
        lambda send: guarded(p, what, library, work),
        timeout=timeout_s(size),
        error=lambda failure: _refused(p, failure),
        memory=2 * ceiling_bytes(SIGNALS) + EXTRA_MEMORY,
    )


def read_frf_records(path) -> list[dict]:
    """The frequency responses (dataset 58, function type 4) of a universal file, as
    :func:`~flexshaft.measurement.files.uff.frf_records` gives them: read in the isolated child,
    under the same ceilings, claims and refusals as :func:`read_measured`'s channels."""
    try:
        p = Path(path)
    except TypeError:
        raise ModelError("is not a path", field="path", value=path, valid="a file path") from None
    if SUFFIXES.get(p.suffix.lower()) != "uff":
        raise ModelError(
            "unknown file type", field="path", value=str(p), valid="a universal file, .uff or .unv"
        )
    with open_seekable(p, SIGNALS) as fh:
        size = os.fstat(fh.fileno()).st_size
        module, _ = _format_module(fh, p, size, "uff")
        lib = need(module.LIBRARY[0], module.LIBRARY[1], p.suffix.lower(), p)

        def work():
            with _own(fh) as own:
                return module.frf_records(own, p, size, lib)

        return _in_child(p, module.WHAT, module.LIBRARY[1], size, work)
