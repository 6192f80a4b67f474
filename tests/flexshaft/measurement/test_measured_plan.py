"""Samples stored plainly are read by the caller from where the library says they lie (:mod:`.plan`):
every layout gives the library's own numbers, bit for bit - TDMS contiguous and interleaved, little- and
big-endian, over several segments (written byte by byte as NI's format reference describes it, and
read back by npTDMS as the peer); HDF5 contiguous and in chunks, of several types (h5py the peer); MDF 4
records with a linear conversion, across many data blocks whose ends cut records (asammdf the peer).
What no plan can read (compressed, invalidation bits) the library reads, and a plan that disagrees with
the library at a channel's ends gives way to it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexshaft.measurement.files as measured
import flexshaft.measurement.files.survey as survey_module
from flexshaft.errors import ModelError
from flexshaft.measurement.files import read_measured
from flexshaft.measurement.files.layout import Planned, Run, read_planned
from tests.flexshaft.measurement.measured_files import write_tdms_by_hand

N = 3001  # samples: no chunk or block size divides it


def _planned(monkeypatch) -> dict:
    """The reading in this process (run_isolated's child is a fork: it could not tell the test), and
    for each channel read whether it was planned: {label: True/False}."""
    monkeypatch.setattr(measured, "run_isolated", lambda work, **_: work(lambda *message: None))
    seen = {}
    real = survey_module.survey

    def spy(*args, **kwargs):
        found = real(*args, **kwargs)
        for s in [c.samples for c in found.columns] + list(found.times.values()):
            seen[s.label] = isinstance(s.data, Planned)
        return found

    monkeypatch.setattr(survey_module, "survey", spy)
    return seen


@pytest.fixture
def planned(monkeypatch):
    return _planned(monkeypatch)


def _signals():
    rng = np.random.default_rng(3)
    return {
        "f8": rng.normal(0.0, 1.0, N),
        "i2": rng.integers(-30000, 30000, N).astype(np.int16),
        "f4": rng.normal(0.0, 1.0, N).astype(np.float32),
        "i4": rng.integers(-(2**31), 2**31 - 1, N).astype(np.int32),
    }


@pytest.mark.parametrize("interleaved", [False, True], ids=["contiguous", "interleaved"])
@pytest.mark.parametrize("big", [False, True], ids=["little", "big"])
def test_tdms_layouts_read_as_nptdms_reads_them(tmp_path, planned, interleaved, big):
    nptdms = pytest.importorskip("nptdms", reason="flexshaft[measured] is not installed")
    sig = _signals()
    units = {"f8": "Nm", "i2": "Nm", "f4": "rpm", "i4": "kNm"}
    channels = [(k, v, units[k]) for k, v in sig.items()]
    path = write_tdms_by_hand(tmp_path / "h.tdms", channels, segments=3, interleaved=interleaved, big=big)
    table = read_measured(path, list(sig))
    assert all(planned[f"bench/{k}"] for k in sig)
    peer = nptdms.TdmsFile.read(path)["bench"]
    factors = {"Nm": 1.0, "rpm": math.pi / 30.0, "kNm": 1e3}
    for k in sig:
        # npTDMS's values as float64 times the unit's factor, one rounded multiplication: the same floats
        want = peer[k][:].astype(np.float64) * factors[units[k]]
        assert np.array_equal(table.columns[k], want), k
    assert np.array_equal(table.time, np.arange(N) * (1 / 1000.0))  # wf_start_offset 0 + k wf_increment


def test_hdf5_layouts_read_as_h5py_reads_them(tmp_path, planned):
    h5py = pytest.importorskip("h5py", reason="flexshaft[measured] is not installed")
    sig = _signals()
    path = tmp_path / "h.h5"
    with h5py.File(path, "w") as f:
        layouts = {
            "contiguous f8": dict(data=sig["f8"]),
            "chunked >f4": dict(data=sig["f4"].astype(">f4"), chunks=(700,)),
            "chunked i2": dict(data=sig["i2"], chunks=(1000,)),
            "contiguous >i4": dict(data=sig["i4"].astype(">i4")),
            "deflated f8": dict(data=sig["f8"], chunks=(700,), compression="gzip", shuffle=True),
        }
        for name, kwargs in layouts.items():
            d = f.create_dataset(name, **kwargs)
            d.attrs["units"] = "Nm"
            d.attrs["rate_hz"] = 1000.0
    table = read_measured(path, list(layouts))
    with h5py.File(path) as f:
        for name in layouts:
            assert np.array_equal(table.columns[name], f[name][()].astype(np.float64)), name
    # stored plainly: planned; compressed: h5py reads it
    assert planned == {name: name != "deflated f8" for name in layouts}


def test_mdf_records_across_blocks_read_as_asammdf_reads_them(tmp_path, planned):
    pytest.importorskip("asammdf", reason="flexshaft[measured] is not installed")
    from asammdf import MDF, Signal

    sig = _signals()
    t = np.arange(N) / 1000.0
    mdf = MDF(version="4.10")
    # data blocks of 1000 bytes: records of 8 + 2 + 4 + 8 + 4 = 26 bytes straddle every block's end
    mdf.configure(write_fragment_size=1000)
    mdf.append(
        [
            Signal(sig["i2"], t, name="scaled", unit="Nm", conversion={"a": 0.25, "b": -3.0}),
            Signal(sig["f4"], t, name="f4", unit="rpm"),
            Signal(sig["f8"], t, name="f8", unit="kNm"),
            Signal(sig["i4"], t, name="i4", unit="Nm"),
        ],
        acq_name="bench",
    )
    path = tmp_path / "r.mf4"
    mdf.save(path)
    mdf.close()
    with MDF(path) as peer:
        assert len(list(peer.groups[0].get_data_blocks())) > 50
        want = {k: peer.get(k) for k in ("scaled", "f4", "f8", "i4")}
    table = read_measured(path, list(want))
    assert all(planned[f"0/{k}"] for k in want) and planned["0/time"]
    factors = {"Nm": 1.0, "rpm": math.pi / 30.0, "kNm": 1e3}
    for k, s in want.items():
        assert np.array_equal(table.columns[k], s.samples.astype(np.float64) * factors[s.unit]), k
    assert np.array_equal(want["scaled"].samples, sig["i2"] * 0.25 - 3.0)  # asammdf's conversion, as planned
    assert np.array_equal(table.time, want["f8"].timestamps)


def test_what_no_plan_reads_the_library_reads(tmp_path, planned):
    pytest.importorskip("asammdf", reason="flexshaft[measured] is not installed")
    from asammdf import MDF, Signal

    sig = _signals()
    t = np.arange(N) / 1000.0
    mdf = MDF(version="4.10")
    mdf.append([Signal(sig["f8"], t, name="x", unit="Nm")], acq_name="bench")
    path = tmp_path / "z.mf4"
    mdf.save(path, compression=2)  # transposed and deflated data blocks (DZ)
    mdf.close()
    table = read_measured(path, ["x"])
    assert np.array_equal(table.columns["x"], sig["f8"]) and planned == {"0/x": False, "0/time": False}


@pytest.mark.parametrize("forked", [False, True], ids=["in-process", "forked"])
def test_a_plan_that_disagrees_with_the_library_gives_way_to_it(tmp_path, monkeypatch, forked):
    # a plan pointing one sample late: its first samples differ from h5py's, so the file is read again
    # through h5py - the right numbers, never the plan's
    h5py = pytest.importorskip("h5py", reason="flexshaft[measured] is not installed")
    from flexshaft.measurement.files import hdf5

    x = np.random.default_rng(5).normal(size=20_000)  # 160 kB: beyond the file object's 64 kB buffer
    path = tmp_path / "h.h5"
    with h5py.File(path, "w") as f:
        d = f.create_dataset("x", data=np.concatenate([x, [0.0]]))
        d.attrs["units"] = "Nm"
        d.attrs["rate_hz"] = 1000.0
    real, plans = hdf5._plan, []

    def late(*args):
        p = real(*args)
        ((run, field, count),) = p.pieces
        (offset, nbytes) = run.extents[0]
        plans.append(p)
        return Planned(((Run(((offset + 8, nbytes - 8),), 8), 0, count - 1),), p.dtype, p.head, p.tail)

    monkeypatch.setattr(hdf5, "_plan", late)
    if forked:  # two readings in two children, the first having moved the shared file offset
        table = read_measured(path, ["x"])
        assert np.array_equal(table.columns["x"], np.concatenate([x, [0.0]]))
        return
    seen = _planned(monkeypatch)
    table = read_measured(path, ["x"])
    assert plans and np.array_equal(table.columns["x"], np.concatenate([x, [0.0]]))
    assert seen == {"x": False}  # the second survey: the library read it


def test_a_plan_beyond_the_file_is_refused(tmp_path):
    path = tmp_path / "f.bin"
    path.write_bytes(np.arange(10.0).tobytes())
    head, tail = np.arange(8.0), np.arange(2.0, 10.0)
    with open(path, "rb") as fh:
        ok = Planned(((Run(((0, 80),), 8), 0, 10),), "<f8", head, tail)
        arrays, finite = read_planned(fh, 80, path, {"x": ("x", ok)})
        assert np.array_equal(arrays["x"], np.arange(10.0)) and finite == {"x"}
        for extents, count in ((((0, 88),), 11), (((-8, 80),), 10), (((0, 40), (40, 32)), 10)):
            bad = Planned(((Run(extents, 8), 0, count),), "<f8", head, tail)
            with pytest.raises(ModelError, match="is damaged") as err:
                read_planned(fh, 80, path, {"x": ("x", bad)})
            assert err.value.field == "x" and str(err.value).startswith(str(path))
        with pytest.raises(ModelError, match="has samples of type"):
            read_planned(
                fh, 80, path, {"x": ("x", Planned(((Run(((0, 80),), 8), 0, 10),), "|O", head, tail))}
            )
