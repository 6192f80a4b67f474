"""Measured test-bench files written by each format's own library (npTDMS, asammdf, h5py, scipy), for
the reader's tests: the same known signals in every format."""

from __future__ import annotations

import math
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.measurement.files import read_measured

RATE = 1000.0  # Hz
N = 2000
T = np.arange(N) / RATE  # s


def signals():
    """A torque in kN·m and a speed in rpm (random, fixed seed: every float written and read back)."""
    rng = np.random.default_rng(7)
    torque_knm = 0.5 + rng.normal(0.0, 0.037, N)
    speed_rpm = 1500.0 + rng.normal(0.0, 3.0, N)
    return torque_knm, speed_rpm


def expected():
    """The same in SI, each one multiplication by the unit's factor (as the reader does it)."""
    torque_knm, speed_rpm = signals()
    return torque_knm * 1e3, speed_rpm * (math.pi / 30.0)


def write_tdms(path, *, other_group: bool = False):
    from nptdms import ChannelObject, TdmsWriter

    tq, sp = signals()
    wf = {"wf_increment": 1.0 / RATE, "wf_start_offset": 0.0}
    channels = [
        ChannelObject("bench", "torque", tq, properties={"unit_string": "kNm", **wf}),
        ChannelObject("bench", "speed", sp, properties={"NI_UnitDescription": "rpm", **wf}),
    ]
    if other_group:  # a second group with a channel of the same name, at another rate
        channels.append(
            ChannelObject(
                "slow", "torque", tq[::10], properties={"unit_string": "kN m", "wf_increment": 0.01}
            )
        )
    with TdmsWriter(str(path)) as w:
        w.write_segment(channels)
    return path


def write_mdf(path, version: str = "4.10", *, slow_group: bool = False):
    from asammdf import MDF, Signal

    tq, sp = signals()
    mdf = MDF(version=version)
    mdf.append(
        [Signal(tq, T, name="torque", unit="kNm"), Signal(sp, T, name="speed", unit="1/min")],
        acq_name="fast",
        comment="fast",
    )
    if slow_group:
        mdf.append([Signal(tq[::10], T[::10], name="torque", unit="kNm")], acq_name="slow", comment="slow")
    saved = mdf.save(str(path), overwrite=True)  # asammdf names a version 3 file .mdf
    mdf.close()
    if Path(saved) != Path(path):
        Path(saved).replace(path)
    return path


def write_hdf5(path):
    import h5py

    tq, sp = signals()
    with h5py.File(path, "w") as f:
        g = f.create_group("bench")
        g.create_dataset("time", data=T).attrs["units"] = "s"
        g.create_dataset("torque", data=tq).attrs["units"] = "kN·m"
        g.create_dataset("speed", data=sp).attrs["unit"] = np.bytes_(b"rpm")
    return path


def write_mat5(path, *, compress: bool = False):
    from scipy.io import savemat

    tq, sp = signals()
    # MATLAB's shapes: a row vector, a column vector (both read as one channel)
    savemat(path, {"time": T, "torque": tq[None, :], "speed": sp[:, None]}, do_compression=compress)
    return path


def mat73_header() -> bytes:
    """The 128 bytes before a MATLAB v7.3 file's HDF5 data: text, subsystem offset, version 0x0200, 'IM'."""
    text = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Thu Jan  1 00:00:00 2026 HDF5 schema 1.00 ."
    return text.ljust(116, b" ") + b" " * 8 + (0x0200).to_bytes(2, "little") + b"IM"


def write_mat73(path, variables: dict | None = None):
    """A v7.3 file as MATLAB writes one: HDF5 in a 512-byte user block, each variable a dataset with its
    MATLAB_class, a 1xN row vector stored transposed (N, 1)."""
    import h5py

    if variables is None:
        tq, sp = signals()
        variables = {"time": T, "torque": tq, "speed": sp}
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, values in variables.items():
            values = np.asarray(values)
            d = f.create_dataset(name, data=values[:, None])
            d.attrs["MATLAB_class"] = np.bytes_({"f": "double", "i": "int32"}[values.dtype.kind])
    with open(path, "r+b") as fh:
        fh.write(mat73_header())
    return path


# suffix -> (writer, the units a test must state: MAT files have none)
WRITERS = {
    ".tdms": (write_tdms, None),
    ".mf4": (write_mdf, None),
    ".mdf": (lambda p: write_mdf(p, "3.30"), None),
    ".dat": (lambda p: write_mdf(p, "3.30"), None),
    ".h5": (write_hdf5, None),
    ".mat": (write_mat5, {"torque": "kNm", "speed": "rpm"}),
    "compressed.mat": (lambda p: write_mat5(p, compress=True), {"torque": "kNm", "speed": "rpm"}),
    "v73.mat": (write_mat73, {"torque": "kNm", "speed": "rpm"}),
}
# the library each format needs
LIBRARY = {".tdms": "nptdms", ".mf4": "asammdf", ".mdf": "asammdf", ".dat": "asammdf", ".h5": "h5py"}
LIBRARY["v73.mat"] = "h5py"


# TDMS data types (NI's TDMS file format reference): code and numpy type
TDMS_TYPES = {"<i2": 0x02, "<i4": 0x03, "<f4": 0x09, "<f8": 0x0A}
_TOC_META, _TOC_RAW, _TOC_NEW_LIST, _TOC_INTERLEAVED, _TOC_BIG_ENDIAN = 1 << 1, 1 << 3, 1 << 2, 1 << 5, 1 << 6


def write_tdms_by_hand(path, channels, *, rate=RATE, group="bench", segments=1, interleaved=False, big=False):
    """A TDMS file written byte by byte as NI's format reference describes it (npTDMS's writer writes
    only contiguous little-endian data): ``channels`` [(name, values, unit)] of one length, in
    ``segments`` segments, their raw data interleaved (one value of each channel per row) or not, in
    big- or little-endian byte order; each channel a waveform (wf_increment 1/rate, unit_string)."""
    import struct

    order = ">" if big else "<"

    def text(s: str) -> bytes:
        b = s.encode()
        return struct.pack(order + "I", len(b)) + b

    pieces = np.array_split(np.arange(len(channels[0][1])), segments)
    out = b""
    for rows in pieces:
        meta = struct.pack(order + "I", 2 + len(channels))
        meta += text("/") + struct.pack(order + "II", 0xFFFFFFFF, 0)
        meta += text(f"/'{group}'") + struct.pack(order + "II", 0xFFFFFFFF, 0)
        for name, values, unit in channels:
            code = TDMS_TYPES["<" + np.dtype(values.dtype).str[1:]]
            meta += text(f"/'{group}'/'{name}'") + struct.pack(order + "IIIQ", 20, code, 1, rows.size)
            meta += struct.pack(order + "I", 2)
            meta += text("unit_string") + struct.pack(order + "I", 0x20) + text(unit)
            meta += text("wf_increment") + struct.pack(order + "Id", 0x0A, 1.0 / rate)
        cols = [np.asarray(v[rows]).astype(np.dtype(v.dtype).newbyteorder(order)) for _, v, _ in channels]
        if interleaved:
            rec = np.empty(rows.size, dtype=[(f"c{i}", c.dtype) for i, c in enumerate(cols)])
            for i, c in enumerate(cols):
                rec[f"c{i}"] = c
            raw = rec.tobytes()
        else:
            raw = b"".join(c.tobytes() for c in cols)
        toc = _TOC_META | _TOC_RAW | _TOC_NEW_LIST | (_TOC_INTERLEAVED if interleaved else 0)
        toc |= _TOC_BIG_ENDIAN if big else 0
        # the lead-in's table of contents is little-endian, what follows it in the segment's order
        lead = (
            b"TDSm"
            + struct.pack("<I", toc)
            + struct.pack(order + "IQQ", 4713, len(meta) + len(raw), len(meta))
        )
        out += lead + meta + raw
    with open(path, "wb") as fh:
        fh.write(out)
    return path


def refused_without_allocating(path, channels, units=None) -> ModelError:
    """The reading's ModelError, with what it allocated meanwhile (the ``in_process`` fixture of this
    folder's conftest) under 4 MB: the
    metadata's few kB and the libraries' buffers, far below the smallest claim the tests refuse (8 MB)."""
    tracemalloc.reset_peak()
    with pytest.raises(ModelError) as err:
        read_measured(path, channels, units=units)
    assert tracemalloc.get_traced_memory()[1] < 4 << 20
    return err.value
