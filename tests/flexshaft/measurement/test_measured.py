"""Measured test-bench files (TDMS, MDF 3/4, HDF5, MATLAB v5/v7.3): the same signals, written by each
format's own library, read back as the same floats in SI; channels by name and group; units from the
files; channels of different rates on one time base; and every damaged or hostile file one ModelError -
never a foreign exception, a crash, a hang, or an allocation a header merely claims."""

from __future__ import annotations

import json
import math
import os
import signal
import struct
import subprocess
import sys
import time

import numpy as np
import pytest

import flexshaft as fs
import flexshaft.measurement.files as measured
from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.measurement import signalfile
from flexshaft.measurement.files import read_measured
from flexshaft.measurement.signalfile import read_signals, write_signals
from tests.conftest import EXAMPLES
from tests.flexshaft.measurement.measured_files import (
    LIBRARY,
    RATE,
    WRITERS,
    T,
    expected,
    refused_without_allocating,
    signals,
    write_hdf5,
    write_mat5,
    write_mdf,
    write_tdms,
)


def _needs(key: str):
    if key in LIBRARY:
        pytest.importorskip(LIBRARY[key], reason="flexshaft[measured] is not installed")


def _written(tmp_path, key: str):
    _needs(key)
    write, units = WRITERS[key]
    return write(tmp_path / ("bench" + key)), units


def _one_line(err: ModelError, path) -> str:
    text = str(err)
    assert "\n" not in text and text.startswith(str(path)), text
    return text


# --- the same floats from every format ----------------------------------------------------------------


@pytest.mark.parametrize("key", list(WRITERS))
def test_every_format_reads_back_the_same_floats_in_si(tmp_path, key):
    path, units = _written(tmp_path, key)
    table = read_measured(path, ["torque", "speed"], units=units)
    torque, speed = expected()
    # each value is the file's float (written exactly by the library) times its unit's factor, one
    # rounded multiplication as in expected(): the same float, bit for bit
    assert np.array_equal(table.columns["torque"], torque)
    assert np.array_equal(table.columns["speed"], speed)
    assert table.units == {"torque": "N·m", "speed": "rad/s"} and table.notes == ()
    # TDMS times are wf_start_offset + k wf_increment: k fl(1/1000) differs from k/1000 by < k eps/1000
    np.testing.assert_allclose(table.time, T, rtol=0, atol=1e-15)
    assert table.rate_hz == pytest.approx(RATE, rel=1e-12) and table.source == str(path)
    # read_signals dispatches on the suffix: every consumer of signal files reads them
    again = read_signals(path, columns=["torque"], units=units and {"torque": "kNm"})
    assert np.array_equal(again.columns["torque"], torque)


def test_a_dat_file_of_csv_is_still_read_as_csv(tmp_path):
    tq, _ = signals()
    csv = write_signals(tmp_path / "run.csv", T, {"torque": (tq, "kNm")})
    dat = tmp_path / "run.dat"
    csv.rename(dat)
    assert np.array_equal(read_signals(dat).columns["torque"], expected()[0])
    for option in ({"group": "bench"}, {"rate": 100.0}):
        with pytest.raises(ModelError, match="applies to a measured file") as err:
            read_signals(dat, **option)
        assert err.value.field in option


def test_channels_by_name_and_group(tmp_path):
    _needs(".tdms")
    path = write_tdms(tmp_path / "two.tdms", other_group=True)
    with pytest.raises(ModelError) as err:
        read_measured(path, ["torque"])
    assert err.value.field == "channels" and "several groups ('bench', 'slow')" in str(err.value)
    assert "--group GROUP" in err.value.valid
    with pytest.raises(ModelError) as err:
        read_signals(path, ["torque"])  # the same, as read_signals names its argument
    assert err.value.field == "columns"
    tq, _ = signals()
    for table in (read_measured(path, ["torque"], group="slow"), read_measured(path, ["slow/torque"])):
        assert np.array_equal(table.columns["torque"], tq[::10] * 1e3)  # 'kN m': kN·m
        assert table.rate_hz == pytest.approx(100.0, rel=1e-12) and table.time.size == 200
    with pytest.raises(ModelError) as err:
        read_measured(path, ["torque"], group="fast")
    assert err.value.field == "group" and "'bench', 'slow'" in err.value.valid
    # every numeric channel of a group when none is named
    assert list(read_measured(path, group="bench").columns) == ["torque", "speed"]


def test_mdf_groups_by_index_or_acquisition_name(tmp_path):
    _needs(".mf4")
    path = write_mdf(tmp_path / "two.mf4", slow_group=True)
    tq, _ = signals()
    for table in (read_measured(path, ["1/torque"]), read_measured(path, ["torque"], group="slow")):
        assert np.array_equal(table.columns["torque"], tq[::10] * 1e3) and table.rate_hz == pytest.approx(
            100.0
        )
    assert read_measured(path, ["fast/speed"]).time.size == T.size


def test_hdf5_by_path_or_last_name(tmp_path):
    _needs(".h5")
    path = write_hdf5(tmp_path / "b.h5")
    a = read_measured(path, ["bench/torque"])
    b = read_measured(path, ["torque"], group="bench")
    assert np.array_equal(a.columns["torque"], b.columns["torque"])
    assert list(read_measured(path).columns) == ["speed", "torque"]  # the time dataset is the time


# --- units ------------------------------------------------------------------------------------------


def test_a_unit_stated_against_the_file_s_is_an_error(tmp_path):
    path, _ = _written(tmp_path, ".tdms")
    with pytest.raises(ModelError) as err:
        read_measured(path, ["torque"], units={"torque": "Nm"})
    assert err.value.field == "bench/torque"
    assert "has the unit 'kNm' in the file and 'Nm' in units=" in _one_line(err.value, path)
    same = read_measured(path, ["torque"], units={"torque": "kNm"})  # the file's own: no conflict
    assert np.array_equal(same.columns["torque"], expected()[0])


def test_a_mat_file_states_no_units(tmp_path):
    path = write_mat5(tmp_path / "b.mat")
    with pytest.raises(ModelError) as err:
        read_measured(path, ["torque"])
    assert err.value.field == "torque" and "has no unit" in str(err.value)
    assert "--unit torque=UNIT" in err.value.valid
    with pytest.raises(ModelError) as err:
        read_measured(path, ["torque"], units={"speeed": "rpm"})
    assert err.value.field == "units" and "no such channel" in str(err.value)


def test_an_unknown_unit_names_channel_unit_and_the_valid_ones(tmp_path):
    h5py = pytest.importorskip("h5py", reason="flexshaft[measured] is not installed")
    path = tmp_path / "u.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("torque", data=np.ones(10)).attrs["units"] = "furlong"
        f["torque"].attrs["rate_hz"] = 10.0
        f.create_dataset("x", data=np.ones(10)).attrs["units"] = "Nm"
        f["x"].attrs["rate_hz"] = 10.0
        f.create_dataset("time", data=np.arange(10.0)).attrs["units"] = "rpm"
    with pytest.raises(ModelError) as err:
        read_measured(path, ["torque"])
    assert err.value.field == "torque" and err.value.value == "furlong"
    assert "unknown unit" in str(err.value) and "N·m" in err.value.valid and "1/min" in err.value.valid
    with pytest.raises(ModelError, match="is not a time") as err:
        read_measured(path, ["x"], time_column="time")
    assert err.value.field == "time"


def test_an_unknown_channel_lists_at_most_twenty(tmp_path):
    h5py = pytest.importorskip("h5py", reason="flexshaft[measured] is not installed")
    path = tmp_path / "many.h5"
    with h5py.File(path, "w") as f:
        for i in range(30):
            f.create_dataset(f"c{i:02d}", data=np.ones(4))
    with pytest.raises(ModelError) as err:
        read_measured(path, ["torque"])
    assert err.value.field == "channels" and "no such channel" in str(err.value)
    assert "'c19'" in err.value.valid and "'c20'" not in err.value.valid
    assert "(30 channels in all)" in err.value.valid


# --- time ---------------------------------------------------------------------------------------------


def test_channels_of_different_rates_come_on_the_fastest_one_s_time_stamps(tmp_path):
    pytest.importorskip("asammdf", reason="flexshaft[measured] is not installed")
    from asammdf import MDF, Signal

    f, a = 3.0, 2.0  # Hz, N·m: a sine sampled at 1 kHz in one group, at 100 Hz in another
    t_fast, t_slow = np.arange(2000) / 1000.0, np.arange(150) / 100.0 + 0.105
    mdf = MDF(version="4.10")
    mdf.append([Signal(a * np.sin(2 * np.pi * f * t_fast), t_fast, name="fast", unit="Nm")])
    mdf.append([Signal(a * np.sin(2 * np.pi * f * t_slow), t_slow, name="slow", unit="Nm")])
    path = tmp_path / "rates.mf4"
    mdf.save(path)
    mdf.close()
    table = read_measured(path, ["slow", "fast"])
    # the 1 kHz stamps over the span both cover: 0.105 s .. 1.595 s
    inside = (t_fast >= t_slow[0]) & (t_fast <= t_slow[-1])
    assert np.array_equal(table.time, t_fast[inside]) and table.rate_hz == pytest.approx(1000.0, rel=1e-9)
    assert np.array_equal(table.columns["fast"], a * np.sin(2 * np.pi * f * t_fast[inside]))
    # linear interpolation of x = a sin(2 pi f t) at step h errs by at most h^2/8 max|x''| =
    # h^2/8 a (2 pi f)^2 (the remainder of the interpolating line), 2.2e-3 N·m here; the bound is
    # nearly reached mid-step at the sine's peaks (1 - cos(pi f h) of a: 0.99 of it), so > half of it
    err = np.abs(table.columns["slow"] - a * np.sin(2 * np.pi * f * table.time)).max()
    bound = 0.01**2 / 8 * a * (2 * np.pi * f) ** 2
    assert 0.5 * bound < err <= bound * (1 + 1e-9)
    assert any("'slow' (sampled at 100 Hz) is interpolated linearly" in n for n in table.notes)
    assert any("cut to 0.105 s .. 1.595 s" in n for n in table.notes)


def test_time_rules(tmp_path):
    pytest.importorskip("asammdf", reason="flexshaft[measured] is not installed")
    from asammdf import MDF, Signal

    def mdf_with(t, name):
        mdf = MDF(version="4.10")
        mdf.append([Signal(np.ones(t.size), t, name="x", unit="Nm")])
        mdf.save(tmp_path / name)
        mdf.close()
        return tmp_path / name

    t = np.arange(100) / 100.0
    jitter = t + np.where(np.arange(100) == 50, 1e-4, 0.0)
    with pytest.raises(ModelError, match="is not uniformly sampled") as err:
        read_measured(mdf_with(jitter, "j.mf4"), ["x"])
    assert err.value.field == "0/time"
    back = t.copy()
    back[[40, 41]] = back[[41, 40]]
    with pytest.raises(ModelError, match="does not increase at sample 41") as err:
        read_measured(mdf_with(back, "b.mf4"), ["x"])
    with pytest.raises(ModelError, match="file gives the time") as err:
        read_measured(mdf_with(t, "ok.mf4"), ["x"], rate=100.0)
    assert err.value.field == "rate"
    # a MAT file without a time variable: the rate given, or an error saying so
    from scipy.io import savemat

    savemat(tmp_path / "r.mat", {"torque": np.arange(5.0)})
    with pytest.raises(ModelError, match="has no time") as err:
        read_measured(tmp_path / "r.mat", ["torque"], units={"torque": "Nm"})
    assert "rate=HZ" in err.value.valid
    table = read_measured(tmp_path / "r.mat", ["torque"], units={"torque": "Nm"}, rate=200.0)
    assert np.array_equal(table.time, np.arange(5) * (1 / 200.0)) and table.rate_hz == pytest.approx(200.0)


def test_a_tdms_time_channel(tmp_path):
    pytest.importorskip("nptdms", reason="flexshaft[measured] is not installed")
    from nptdms import ChannelObject, TdmsWriter

    stamps = np.datetime64("2026-01-01T00:00:00") + np.arange(50) * np.timedelta64(2, "ms")
    with TdmsWriter(str(tmp_path / "t.tdms")) as w:
        w.write_segment(
            [
                ChannelObject("g", "t", np.arange(50) * 2.0, properties={"unit_string": "ms"}),
                ChannelObject("g", "Time", stamps),
                ChannelObject("g", "x", np.arange(50.0), properties={"unit_string": "Nm"}),
            ]
        )
    # a channel named time (any case) beside it: TDMS timestamps, counted from the first
    by_name = read_measured(tmp_path / "t.tdms", ["x"])
    named = read_measured(tmp_path / "t.tdms", ["x"], time_column="t")  # in ms
    np.testing.assert_allclose(by_name.time, np.arange(50) * 0.002, rtol=0, atol=1e-15)
    np.testing.assert_allclose(named.time, by_name.time, rtol=0, atol=1e-15)
    assert by_name.rate_hz == pytest.approx(500.0, rel=1e-9)


# --- damaged and hostile files --------------------------------------------------------------------


@pytest.mark.parametrize("key", list(WRITERS))
def test_empty_garbage_and_truncated_files_are_one_error(tmp_path, key, capfd):
    path, units = _written(tmp_path, key)
    data = path.read_bytes()
    rng = np.random.default_rng(11)
    bad = tmp_path / ("bad" + key)
    for variant in (
        b"",
        rng.bytes(len(data)),
        *(data[: int(f * len(data))] for f in (0.02, 0.25, 0.5, 0.75)),
    ):
        bad.write_bytes(variant)
        with pytest.raises(ModelError) as err:
            read_measured(bad, ["torque", "speed"], units=units)
        _one_line(err.value, bad)
    assert capfd.readouterr().err == ""  # nothing of the libraries' own on the terminal
    bad.write_bytes(data[: len(data) // 2])
    args = ["spectrum", str(bad), "--column", "torque"] + (["--unit", "torque=kNm"] if units else [])
    assert main(args) == 2
    out = capfd.readouterr()
    assert out.out == "" and out.err.count("\n") == 1 and out.err.startswith(f"flexshaft: error: {bad}: ")


@pytest.mark.slow
@pytest.mark.parametrize("key", [".tdms", ".mf4", ".h5", ".mat", "compressed.mat", "v73.mat"])
def test_corrupted_bytes_are_read_or_refused_never_a_crash(tmp_path, key, capfd, monkeypatch):
    """Random byte changes (fixed seed): the file read (a changed sample is a number like another) or
    one ModelError. Among such files HDF5 looped forever and asammdf crashed (SIGSEGV): the reading's
    child process makes both one error."""
    monkeypatch.setattr(measured, "TIMEOUT_S", 10.0)  # a small file reads in well under a second
    path, units = _written(tmp_path, key)
    data = path.read_bytes()
    rng = np.random.default_rng(20261124)
    bad = tmp_path / ("bad" + key)
    refused = 0
    for _ in range(60):
        b = bytearray(data)
        for pos in rng.integers(0, len(b), size=int(rng.integers(1, 8))):
            b[pos] = int(rng.integers(0, 256))
        bad.write_bytes(bytes(b))
        try:
            table = read_measured(bad, ["torque", "speed"], units=units)
        except ModelError as err:
            _one_line(err, bad)
            refused += 1
        else:
            assert set(table.columns) == {"torque", "speed"}
    assert refused > 0 and capfd.readouterr().err == ""


def test_a_crash_or_a_hang_of_the_reader_is_one_error(tmp_path, monkeypatch):
    _needs(".h5")
    path = write_hdf5(tmp_path / "b.h5")
    from flexshaft.measurement.files import hdf5

    monkeypatch.setattr(hdf5._Source, "read", lambda self, *_: os.kill(os.getpid(), signal.SIGSEGV))
    with pytest.raises(ModelError, match=r"its reader crashed on it \(signal SIGSEGV\)") as err:
        read_measured(path, ["torque"])
    _one_line(err.value, path)
    monkeypatch.setattr(hdf5._Source, "read", lambda self, *_: time.sleep(60))
    monkeypatch.setattr(measured, "TIMEOUT_S", 0.5)
    start = time.monotonic()
    with pytest.raises(ModelError, match="reading it took more than 1 s"):
        read_measured(path, ["torque"])
    assert time.monotonic() - start < 5.0  # stopped at the timeout (0.5 s and one poll), not at 60 s


def test_a_header_claiming_a_huge_length_is_refused_before_anything_is_allocated(tmp_path, in_process):
    pytest.importorskip("asammdf", reason="flexshaft[measured] is not installed")
    h5py = pytest.importorskip("h5py", reason="flexshaft[measured] is not installed")
    from asammdf import MDF

    # MDF 4: the channel group's cycle count (8 bytes after its 6 links) made 2**40 and 1e6
    path = write_mdf(tmp_path / "b.mf4")
    with MDF(path) as mdf:
        at = mdf.groups[0].channel_group.address + 24 + 6 * 8 + 8
    data = bytearray(path.read_bytes())
    assert struct.unpack_from("<Q", data, at)[0] == T.size
    for cycles, says in (
        (1 << 40, "above the 2048 MB ceiling"),
        (10**6, "its header claims 1,000,000 samples"),
    ):
        struct.pack_into("<Q", data, at, cycles)
        path.write_bytes(data)
        err = refused_without_allocating(path, ["torque"])
        assert says in str(err) and err.field == "0/torque"
    # HDF5: datasets' shapes never written (no storage allocated), beside 9 MB of other data
    path = tmp_path / "claim.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("huge", shape=(1 << 40,), dtype="f8").attrs["rate_hz"] = 1.0
        f.create_dataset("empty", shape=(10**6,), dtype="f8").attrs["rate_hz"] = 1.0
        f.create_dataset("other", data=np.zeros(9 << 17))
    assert "above the 2048 MB ceiling" in str(refused_without_allocating(path, ["huge"], {"huge": "Nm"}))
    err = refused_without_allocating(path, ["empty"], {"empty": "Nm"})
    assert "its shape claims 1,000,000 samples (8,000,000 bytes), the file stores 0 bytes of them;" in str(
        err
    )
    # MATLAB v5: the dimensions of 'torque' (1x2000) made 1x1e6, in an uncompressed file
    path = write_mat5(tmp_path / "claim.mat")
    data = bytearray(path.read_bytes())
    dims = struct.pack("<iiii", 5, 8, 1, T.size)  # miINT32, 8 bytes: 1, 2000 (time's are the same)
    at = data.find(dims, data.find(dims) + 1)
    struct.pack_into("<i", data, at + 12, 10**6)
    path.write_bytes(data)
    err = refused_without_allocating(path, ["torque"], {"torque": "Nm"})
    assert "its header claims 1,000,000 samples of 8 bytes" in str(err)


def test_a_missing_library_names_the_extra(tmp_path, monkeypatch):
    for key, module, package in (
        (".tdms", "nptdms", "npTDMS"),
        (".mf4", "asammdf", "asammdf"),
        (".h5", "h5py", "h5py"),
    ):
        path, _ = _written(tmp_path, key)
        with monkeypatch.context() as m:
            m.setitem(sys.modules, module, None)  # as if not installed: its import fails
            with pytest.raises(ModelError) as err:
                read_measured(path, ["torque"])
        assert str(err.value) == f"{path}: reading {key} needs {package}: pip install 'flexshaft[measured]'"


def test_hdf5_links_and_outside_storage_are_never_followed(tmp_path):
    h5py = pytest.importorskip("h5py", reason="flexshaft[measured] is not installed")
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.create_dataset("secret", data=np.arange(10.0)).attrs["rate_hz"] = 1.0
    raw = tmp_path / "raw.bin"
    raw.write_bytes(np.arange(10.0).tobytes())
    path = tmp_path / "links.h5"
    with h5py.File(path, "w") as f:
        f["linked"] = h5py.ExternalLink(str(other), "/secret")
        f["soft"] = h5py.SoftLink("/elsewhere")
        f.create_dataset("outside", shape=(10,), dtype="f8", external=[(str(raw), 0, 80)]).attrs[
            "rate_hz"
        ] = 1.0
        layout = h5py.VirtualLayout(shape=(10,), dtype="f8")
        layout[:] = h5py.VirtualSource(str(other), "secret", shape=(10,))
        f.create_virtual_dataset("virtual", layout).attrs["rate_hz"] = 1.0
        f.create_dataset("refs", data=[f["outside"].ref], dtype=h5py.ref_dtype)
    for name in ("linked", "soft"):
        with pytest.raises(ModelError, match="no such channel"):
            read_measured(path, [name], units={"outside": "Nm"})
    for name in ("outside", "virtual"):
        with pytest.raises(ModelError, match="keeps its data in other files") as err:
            read_measured(path, [name])
        assert err.value.field == name
    with pytest.raises(ModelError, match="holds object values"):
        read_measured(path, ["refs"])


def test_matlab_objects_cells_text_and_complex_are_refused(tmp_path):
    from scipy.io import savemat

    path = tmp_path / "o.mat"
    savemat(
        path,
        {
            "time": T[:3],
            "cell": np.array([np.arange(3.0), "x"], dtype=object),
            "s": {"a": np.arange(3.0)},
            "text": "abc",
            "z": np.arange(3.0) + 1j,
            "ok": np.arange(3.0),
        },
    )
    for name, cls in (("cell", "cell"), ("s", "struct"), ("text", "char")):
        with pytest.raises(ModelError, match=f"is a MATLAB {cls}") as err:
            read_measured(path, [name], units={name: "Nm"})
        assert err.value.field == name
    with pytest.raises(ModelError, match="holds complex128 values, not numbers"):
        read_measured(path, ["z"], units={"z": "Nm"})
    assert read_measured(path, units={"ok": "Nm", "z": "Nm"}, channels=["ok"]).columns["ok"].size == 3


# --- the command line ----------------------------------------------------------------------------


def test_spectrum_of_a_tdms_file_is_that_of_the_same_csv(tmp_path, capsys):
    pytest.importorskip("nptdms", reason="flexshaft[measured] is not installed")
    from nptdms import ChannelObject, TdmsWriter

    t = np.arange(4000) / 1000.0
    x = np.exp(-2 * np.pi * 0.01 * 12.0 * t) * np.sin(2 * np.pi * 12.0 * t)  # a 12 Hz free decay, kN·m
    tdms = tmp_path / "decay.tdms"
    with TdmsWriter(str(tdms)) as w:
        props = {"unit_string": "kNm", "wf_increment": 0.001, "wf_start_offset": 0.0}
        w.write_segment([ChannelObject("bench", "torque", x, properties=props)])
    table = read_measured(tdms, ["torque"])
    csv = write_signals(tmp_path / "decay.csv", table.time, {"torque": (table.columns["torque"], "N·m")})
    docs = []
    for path, extra in ((tdms, ["--group", "bench"]), (csv, [])):
        assert main(["spectrum", str(path), "--column", "torque", *extra, "--json"]) == 0
        docs.append(json.loads(capsys.readouterr().out))
    # the same floats (the CSV holds the TDMS file's values, as read, exactly): the same analysis
    assert docs[0].pop("source") == str(tdms) and docs[1].pop("source") == str(csv)
    assert docs[0] == docs[1] and docs[0]["peaks"][0]["frequency_hz"] == pytest.approx(12.0, abs=0.5)
    assert main(["spectrum", str(tdms), "--column", "torque", "--group", "nope"]) == 2
    assert "group = 'nope': no such group; valid: one of 'bench'" in capsys.readouterr().err


def test_simulate_takes_a_torque_history_from_an_mdf_file(tmp_path, capsys):
    pytest.importorskip("asammdf", reason="flexshaft[measured] is not installed")
    from asammdf import MDF, Signal

    t = np.arange(0, 2.0, 0.001)
    history = 0.05 * (t > 0.1)  # 50 N·m from 0.1 s, in kN·m
    mdf = MDF(version="4.10")
    mdf.append([Signal(history, t, name="drive", unit="kNm")], acq_name="bench")
    mf4 = tmp_path / "torque.mf4"
    mdf.save(mf4)
    mdf.close()
    csv = write_signals(tmp_path / "torque.csv", t, {"drive": (history, "kNm")})
    runs = []
    for series in (mf4, csv):
        out = tmp_path / f"run-{series.suffix[1:]}.csv"
        args = ["simulate", str(EXAMPLES / "customer1.toml"), "--scenario", "csv", "--series", str(series)]
        assert (
            main(
                [*args, "--column", "drive", "--measure", "torque:part 3", "--duration", "1.5"]
                + ["-o", str(out)]
            )
            == 0
        )
        capsys.readouterr()
        runs.append(fs.read_signals(out).columns["torque:part 3"])
    # the same history (the same floats, converted alike), the same run in one process
    np.testing.assert_allclose(runs[0], runs[1], rtol=0, atol=1e-12 * np.ptp(runs[1]))
    args = ["simulate", str(EXAMPLES / "customer1.toml"), "--scenario", "csv", "--series", str(mf4)]
    args += ["--column", "drive", "--measure", "torque:part 3", "--group", "nope"]
    assert main([*args, "-o", str(tmp_path / "x.csv")]) == 2
    assert "no such group" in capsys.readouterr().err


def test_reading_imports_no_format_library_until_a_file_needs_it():
    code = (
        "import sys, flexshaft.measurement.signalfile, flexshaft.measurement.files, flexshaft.cli;"
        "print(sorted(m for m in ('nptdms', 'asammdf', 'h5py') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_the_units_table_is_shared():
    # the CSV reader and the measured reader read one table; rpm's spellings are revolutions per minute
    from flexshaft.measurement.files import survey

    assert signalfile.UNITS is survey.UNITS
    for unit in ("rpm", "1/min", "U/min", "rev/min"):
        assert signalfile.UNITS[unit] == ("rad/s", math.pi / 30.0)


@pytest.mark.parametrize("suffix", [".tdms", ".mf4"])
def test_write_measured_reads_back_the_same_floats(tmp_path, suffix):
    _needs(suffix)
    tq, sp = signals()
    path = fs.write_measured(
        tmp_path / f"w{suffix}", T, {"torque": (tq, "kNm"), "speed": (sp, "rpm")}, group="bench"
    )
    table = read_measured(path, ["bench/torque", "speed"])
    torque, speed = expected()
    assert np.array_equal(table.columns["torque"], torque) and np.array_equal(table.columns["speed"], speed)
    np.testing.assert_allclose(table.time, T, rtol=0, atol=1e-15)  # TDMS: start + k step, within rounding
    with pytest.raises(ModelError, match="file exists"):
        fs.write_measured(path, T, {"torque": (tq, "kNm")})
    with pytest.raises(ModelError) as err:
        fs.write_measured(tmp_path / f"u{suffix}", T, {"torque": (tq, "furlong")})
    assert err.value.field == "torque" and "unknown unit" in str(err.value)
