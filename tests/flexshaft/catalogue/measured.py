"""Measured test-bench files (TDMS, MDF, HDF5, MAT) that are not what they claim: a FIFO, a sparse file
over the ceiling, bytes of another kind, a truncated file, a header claiming a terabyte, a link out of
the file, a MATLAB cell. Each is one error line naming the file (or the option)."""

from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

from tests.flexshaft.catalogue import Case
from tests.flexshaft.measurement.measured_files import write_mdf

SPECTRUM = ["spectrum", "s.{}", "--column", "torque"]


def _spectrum(suffix: str, extra=()) -> list[str]:
    return [a.format(suffix) for a in SPECTRUM] + list(extra)


def _fifo(d: Path) -> list[str]:
    os.mkfifo(d / "s.tdms")
    return _spectrum("tdms")


def _sparse(d: Path) -> list[str]:
    with open(d / "s.mf4", "wb") as fh:
        fh.truncate((2 << 30) + 1)  # one byte above the signal file's ceiling, nothing of it on disk
    return _spectrum("mf4")


def _png_as_tdms(d: Path) -> list[str]:
    (d / "s.tdms").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    return _spectrum("tdms")


def _truncated_mdf(d: Path) -> list[str]:
    path = write_mdf(d / "s.mf4")
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    return _spectrum("mf4")


def _terabyte_mdf(d: Path) -> list[str]:
    from asammdf import MDF

    path = write_mdf(d / "s.mf4")
    with MDF(path) as mdf:
        at = mdf.groups[0].channel_group.address + 24 + 6 * 8 + 8  # the group's cycle count
    data = bytearray(path.read_bytes())
    struct.pack_into("<Q", data, at, 1 << 40)
    path.write_bytes(data)
    return _spectrum("mf4")


def _link_out(d: Path) -> list[str]:
    import h5py

    with h5py.File(d / "s.h5", "w") as f:
        f["torque"] = h5py.ExternalLink("/dev/zero", "/x")
        f.create_dataset("speed", data=np.ones(10)).attrs["rate_hz"] = 10.0
    return _spectrum("h5")


def _unwritten_chunks(d: Path) -> list[str]:
    import h5py

    with h5py.File(d / "s.h5", "w") as f:  # 60 M samples claimed in a file of a few kB: one chunk written
        t = f.create_dataset("torque", shape=(60_000_000,), dtype="f8", chunks=(1 << 16,), compression="gzip")
        t[:1000] = 1.0
        t.attrs["units"] = "Nm"
        t.attrs["rate_hz"] = 1000.0
    return ["identify", "s.h5", "--channel", "torque"]


def _cell(d: Path) -> list[str]:
    from scipy.io import savemat

    savemat(d / "s.mat", {"torque": np.array([np.arange(3.0), "x"], dtype=object), "time": np.arange(3.0)})
    return _spectrum("mat", ["--unit", "torque=Nm"])


CASES = {
    "FIFO as a TDMS file for spectrum": Case(_fifo, says=("s.tdms", "FIFO"), budget_s=15),
    "sparse MDF file one byte above the 2048 MB ceiling": Case(
        _sparse, says=("s.mf4", "2048 MB ceiling", "FLEXSHAFT_MAX_FILE_MB"), budget_s=15
    ),
    "a PNG named .tdms": Case(_png_as_tdms, says=("s.tdms", "is not a TDMS file", "valid"), budget_s=15),
    "MDF 4 file cut in half": Case(_truncated_mdf, says=("s.mf4", "not a readable MDF file"), budget_s=30),
    "MDF 4 group claiming 2**40 records": Case(
        _terabyte_mdf, says=("s.mf4", "0/torque", "above the 2048 MB ceiling"), budget_s=30
    ),
    "HDF5 channel that is an external link to /dev/zero": Case(
        _link_out, says=("s.h5", "columns", "no such channel"), budget_s=30
    ),
    "MATLAB cell as the signal": Case(_cell, says=("s.mat", "is a MATLAB cell"), budget_s=30),
    "HDF5 dataset claiming 60 M samples in chunks never written": Case(
        _unwritten_chunks, says=("s.h5", "torque", "60,000,000 samples", "1 of its 916 chunks"), budget_s=15
    ),
}
