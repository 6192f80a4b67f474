"""What a measured file's header claims, checked before anything is allocated: an HDF5 dataset's shape
against the storage the file has allocated for it (chunks never written, chunks that cannot inflate to
their claim), a TDMS channel's value count, the channels together against the ceiling; and a file's
timing attributes, which must be numbers whose rate is one (a boolean, 5e-324 s, 1e12 Hz are refused in
one line, nothing warned). The readers' own claims of MDF and MATLAB files: ``test_measured.py``."""

from __future__ import annotations

import os
import subprocess
import sys
import time
import warnings
import zlib

import numpy as np
import pytest

from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.measurement.files import read_measured
from tests.flexshaft.measurement.measured_files import (
    refused_without_allocating,
    write_tdms,
)

h5py = pytest.importorskip("h5py", reason="flexshaft[measured] is not installed")

CLAIM = 60_000_000  # samples: the 109 kB file claimed these (480 MB as float64)
CHUNK = 1 << 16


def _hostile(path, *, compression="gzip"):
    """The issue's file: a chunked dataset claiming 60 M samples of which one chunk is written, the rest
    left to the fill value; a few hundred kB at most."""
    with h5py.File(path, "w") as f:
        d = f.create_dataset(
            "torque", shape=(CLAIM,), dtype="f8", chunks=(CHUNK,), compression=compression, fillvalue=1.0
        )
        d[:1000] = np.sin(np.arange(1000.0))
        d.attrs["units"] = "Nm"
        d.attrs["rate_hz"] = 1000.0
    assert path.stat().st_size < 1 << 20
    return path


def _refused_without_allocating(path, channels, units=None) -> ModelError:
    """Refused allocating little (the claims are 480 MB and more), in one line, within the 30 s the
    issue allows."""
    start = time.monotonic()
    err = refused_without_allocating(path, channels, units)
    assert time.monotonic() - start < 30.0
    text = str(err)
    assert "\n" not in text and text.startswith(str(path))
    return err


@pytest.mark.parametrize("compression", ["gzip", None])
def test_chunks_never_written_are_refused_naming_claim_and_storage(tmp_path, in_process, compression):
    path = _hostile(tmp_path / "claim.h5", compression=compression)
    with h5py.File(path) as f:  # what the file stores, as HDF5 itself counts it
        stored, chunks = f["torque"].id.get_storage_size(), f["torque"].id.get_num_chunks()
    err = _refused_without_allocating(path, ["torque"])
    needed = -(-CLAIM // CHUNK)
    assert err.field == "torque"
    assert f"claims {CLAIM:,} samples ({8 * CLAIM:,} bytes), the file stores {stored:,} bytes" in str(err)
    assert f"{chunks} of its {needed:,} chunks" in str(err) and "fill value" in str(err)


def test_chunks_that_cannot_inflate_to_their_claim_are_refused(tmp_path, in_process):
    # every chunk stored, each a valid deflate stream of 8 bytes: 16 chunks of 1 MB claimed in 176 bytes,
    # beyond deflate's 1032:1 (a 258-byte match in 2 bits)
    path = tmp_path / "forged.h5"
    n = 16 * (1 << 17)
    with h5py.File(path, "w") as f:
        d = f.create_dataset("torque", shape=(n,), dtype="f8", chunks=(1 << 17,), compression="gzip")
        for k in range(16):
            d.id.write_direct_chunk((k << 17,), zlib.compress(b"\0" * 8))
        d.attrs["units"] = "Nm"
        d.attrs["rate_hz"] = 1000.0
        stored = d.id.get_storage_size()
    err = _refused_without_allocating(path, ["torque"])
    assert f"the file stores {stored:,} bytes of them (deflated, which inflates at most 1032:1)" in str(err)


def test_a_compressible_record_within_deflates_bound_is_read(tmp_path):
    # the control: zeros deflate (with shuffle, level 9) to ~1009:1 - close to the bound, and read
    path = tmp_path / "zeros.h5"
    with h5py.File(path, "w") as f:
        d = f.create_dataset("torque", data=np.zeros(1 << 21), chunks=(1 << 17,), compression="gzip")
        d.attrs["units"] = "Nm"
        d.attrs["rate_hz"] = 1000.0
    table = read_measured(path, ["torque"])
    assert table.columns["torque"].size == 1 << 21 and not table.columns["torque"].any()


def test_the_hostile_file_on_the_command_line_is_one_line_exit_2(tmp_path, capfd):
    path = _hostile(tmp_path / "claim.h5")
    for argv in (
        ["spectrum", str(path), "--column", "torque"],
        ["identify", str(path), "--channel", "torque"],
    ):
        assert main(argv) == 2
        out = capfd.readouterr()
        assert out.out == "" and out.err.count("\n") == 1
        assert out.err.startswith(f"flexshaft: error: {path}: torque: is damaged: its shape claims")


# Runs the command and prints its exit code and peak resident memory (kB), from the kernel's account of
# that child (wait4). Started from this small process, not the test's: Linux carries the memory of the
# process that forks into the child's peak (exec keeps the old image's high-water mark).
LAUNCHER = """
import os, subprocess, sys
proc = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
err = proc.stderr.read()
_, status, usage = os.wait4(proc.pid, 0)
print(os.waitstatus_to_exitcode(status), usage.ru_maxrss, err.count(b"\\n"))
"""


def test_the_hostile_file_costs_no_memory_in_a_process_of_its_own(tmp_path):
    """The whole command as a process, its peak resident memory (and its reading child's): before, it
    read the 480 MB claim (4.1 GB at its peak) and exited 0."""
    path = _hostile(tmp_path / "claim.h5")
    flexshaft = os.path.join(os.path.dirname(sys.executable), "flexshaft")
    argv = [sys.executable, "-c", LAUNCHER, flexshaft, "spectrum", str(path), "--column", "torque"]
    out = subprocess.run(argv, capture_output=True, text=True, timeout=120, check=True)
    code, peak_kb, lines = map(int, out.stdout.split())
    assert code == 2 and lines == 1
    # ru_maxrss (kB on Linux): the largest of the command and its reading child; the interpreter with
    # numpy and h5py takes ~120 MB, the claim alone is 480 MB
    assert peak_kb < 300 * 1024


def test_channels_together_above_the_ceiling_are_refused_before_any_is_read(
    tmp_path, in_process, monkeypatch
):
    monkeypatch.setenv("FLEXSHAFT_MAX_FILE_MB", "1")
    path = tmp_path / "two.h5"
    with h5py.File(path, "w") as f:
        for name in ("a", "b"):
            # 0.8 MB each as numbers: each alone within 1 MB, and the file (deflated) too
            d = f.create_dataset(name, data=np.ones(100_000), compression="gzip")
            d.attrs["units"] = "Nm"
            d.attrs["rate_hz"] = 1000.0
    assert read_measured(path, ["a"]).columns["a"].size == 100_000
    err = _refused_without_allocating(path, ["a", "b"])
    assert err.field == "channels" and "claims 200,000 samples in the 2 channels asked for" in str(err)


def test_a_tdms_channel_claiming_more_values_than_the_file_holds(tmp_path, in_process):
    path = write_tdms(tmp_path / "b.tdms")
    data = bytearray(path.read_bytes())
    # the raw data index of '/bench/torque': type 0x0A (double), dimension 1, then the value count
    name = b"/'bench'/'torque'"
    at = data.index(name) + len(name) + 4 + 4 + 4
    assert int.from_bytes(data[at : at + 8], "little") == 2000
    data[at : at + 8] = (10**6).to_bytes(8, "little")
    path.write_bytes(data)
    err = _refused_without_allocating(path, ["torque"])
    # npTDMS finds the segment's data too short for the claim first (and logs it: that refuses the
    # file), so the claim's own check is shown apart below
    assert "is damaged" in str(err) and "npTDMS" in str(err)


def test_a_tdms_channels_claim_is_checked_against_the_files_size():
    # What npTDMS's index says a channel holds (its len), against the bytes the file has: 10^6 doubles
    # cannot be in 1000 bytes, whatever the segments claim.
    from types import SimpleNamespace

    from flexshaft.measurement.files import tdms
    from flexshaft.measurement.files.base import Entry

    class Channel:
        data_type = SimpleNamespace(size=8)

        def __len__(self):
            return 10**6

    source = SimpleNamespace(path="b.tdms", size=1000)
    entry = Entry("bench", "torque", Channel())
    claim = "its header claims 1,000,000 samples of 8 bytes, where the file holds 1,000 bytes"
    with pytest.raises(ModelError, match=claim):
        tdms._Source.claim(source, entry)


# --- timing attributes ------------------------------------------------------------------------------


def _h5_with(path, **attrs):
    with h5py.File(path, "w") as f:
        d = f.create_dataset("torque", data=np.sin(np.arange(2000.0)))
        d.attrs["units"] = "Nm"
        for key, value in attrs.items():
            d.attrs[key] = value
    return path


@pytest.mark.parametrize(
    "key,value,says",
    [
        ("rate_hz", True, "torque attribute rate_hz = true: is not a number"),
        ("sampling_rate", "1000", "torque attribute sampling_rate = '1000': is not a number"),
        ("rate_hz", 1e12, "torque attribute rate_hz = 1000000000000.0 Hz: is out of range"),
        ("rate_hz", np.nan, "torque attribute rate_hz = nan Hz: is not finite"),
        ("wf_increment", 5e-324, "torque attribute wf_increment = 5e-324 s: is out of range"),
        ("wf_increment", -1e-3, "torque attribute wf_increment = -0.001 s: is out of range"),
    ],
)
def test_a_timing_attribute_that_is_no_rate_is_one_error_and_no_warning(tmp_path, capfd, key, value, says):
    path = _h5_with(tmp_path / "t.h5", **{key: value})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning would fail the test
        with pytest.raises(ModelError) as err:
            read_measured(path, ["torque"])
    assert str(err.value).startswith(f"{path}: {says}; valid: a number from ")
    assert ("Hz (the sampling rate)" if "rate" in key else "s (the sampling step") in err.value.valid
    assert main(["identify", str(path), "--channel", "torque"]) == 2
    out = capfd.readouterr()
    assert out.err.count("\n") == 1 and says in out.err and "Warning" not in out.err


def test_a_tdms_increment_of_5e_324_s_is_one_error(tmp_path, capfd):
    pytest.importorskip("nptdms", reason="flexshaft[measured] is not installed")
    from nptdms import ChannelObject, TdmsWriter

    path = tmp_path / "tiny.tdms"
    with TdmsWriter(str(path)) as w:
        props = {"unit_string": "Nm", "wf_increment": 5e-324}
        w.write_segment([ChannelObject("g", "torque", np.ones(100), properties=props)])
    assert main(["spectrum", str(path), "--column", "torque"]) == 2
    out = capfd.readouterr()
    assert out.err.count("\n") == 1 and "Warning" not in out.err
    assert "g/torque property wf_increment = 5e-324 s: is out of range" in out.err


def test_time_stamps_a_rate_beyond_floating_point_are_one_error(tmp_path, capfd):
    # an MDF master channel stepping 5e-324 s: uniform (every step the same denormal), its rate 1/5e-324
    # overflows to inf - refused, not warned
    pytest.importorskip("asammdf", reason="flexshaft[measured] is not installed")
    from asammdf import MDF, Signal

    mdf = MDF(version="4.10")
    mdf.append([Signal(np.ones(100), np.arange(100) * 5e-324, name="x", unit="Nm")])
    path = tmp_path / "tiny.mf4"
    mdf.save(path)
    mdf.close()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ModelError, match="is sampled at inf Hz; valid: a sampling rate from 1e-06 to 1e"):
            read_measured(path, ["x"])
    assert capfd.readouterr().err == ""


def test_a_sample_beyond_floating_point_in_si_is_one_error(tmp_path):
    # 1e307 kN·m is a float; in N·m (x 1000) it is not: refused, not an inf in the table nor a warning
    path = tmp_path / "big.h5"
    with h5py.File(path, "w") as f:
        d = f.create_dataset("torque", data=np.array([1.0, 2.0, 1e307, 3.0]))
        d.attrs["units"] = "kNm"
        d.attrs["rate_hz"] = 10.0
        d = f.create_dataset("start", data=np.ones(4))
        d.attrs["units"] = "Nm"
        d.attrs["wf_increment"] = 1.0
        d.attrs["wf_start_offset"] = 1.7e308  # the record's end, 1.7e308 + 3 s, is a float...
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ModelError, match="sample 2 times 1000 .its unit to SI. is beyond floating point"):
            read_measured(path, ["torque"])
        # ... but 1.7e308 + 3 is 1.7e308: the steps are not 1 s (the full check finds it)
        with pytest.raises(ModelError, match="does not increase at sample 1"):
            read_measured(path, ["start"])


def test_a_rate_given_outside_the_range_is_refused(tmp_path):
    from scipy.io import savemat

    savemat(tmp_path / "r.mat", {"torque": np.arange(5.0)})
    for rate in (0.0, 1e12, float("inf")):
        with pytest.raises(ModelError) as err:
            read_measured(tmp_path / "r.mat", ["torque"], units={"torque": "Nm"}, rate=rate)
        assert err.value.field == "rate" and err.value.unit == "Hz"


# --- what a reading imports ------------------------------------------------------------------------


def test_reading_imports_the_reader_alone(tmp_path):
    """Neither scipy's signal processing and statistics nor the identification: reading a record was
    0.85 s of imports before (flexshaft.measurement pulled them in), and the thread policy scipy.linalg."""
    path = _h5_with(tmp_path / "t.h5", rate_hz=1000.0)
    code = (
        "import sys, json; from flexshaft.measurement.signalfile import read_signals; "
        "read_signals(sys.argv[1]);"
        "print(json.dumps(sorted(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True)
    loaded = set(__import__("json").loads(out.stdout))
    assert "h5py" in loaded
    unwanted = {"scipy.signal", "scipy.stats", "scipy.linalg", "flexshaft.measurement.identify"}
    assert not unwanted & loaded, unwanted & loaded
    assert not any(m.startswith("flexshaft.analysis.identification") for m in loaded)
