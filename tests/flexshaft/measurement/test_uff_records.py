"""Universal files' time records (dataset 58, function type 1), as a test lab writes them with pyuff:
read into the same signal table as the TDMS of the same samples, identified alike, and refused
in one line where damaged."""

import runpy

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.errors import ModelError
from flexshaft.measurement.files import read_measured
from flexshaft.measurement.identify import identify_modes
from tests.conftest import EXAMPLES

pyuff = pytest.importorskip("pyuff", reason="pyuff is not installed (the measured or uff extra)")
pytest.importorskip("nptdms", reason="npTDMS is not installed (the measured extra)")

EXAMPLE = runpy.run_path(str(EXAMPLES / "operational_run.py"))
UNITS_UFF = {"N·m": "N*m", "rad/s": "rad/s"}


def write_records(path, time, columns: dict, units: dict, binary: int = 1) -> None:
    """The channels as dataset 58 time records, each named by its ID line, as pyuff writes them."""
    sets = [
        pyuff.prepare_58(
            binary=binary,
            id1=name,
            id2="NONE",
            id3="NONE",
            id4="NONE",
            id5="NONE",
            func_type=1,
            ver_num=1,
            load_case_id=0,
            rsp_ent_name="bench",
            rsp_node=k + 1,
            rsp_dir=4,
            ref_ent_name="bench",
            ref_node=0,
            ref_dir=0,
            ord_data_type=4,
            num_pts=time.size,
            abscissa_spacing=1,
            abscissa_min=float(time[0]),
            abscissa_inc=float(time[1] - time[0]),
            abscissa_spec_data_type=17,
            abscissa_axis_units_lab="s",
            ordinate_spec_data_type=1,
            ordinate_axis_units_lab=UNITS_UFF[units[name]],
            orddenom_spec_data_type=0,
            orddenom_axis_units_lab="",
            z_axis_spec_data_type=0,
            data=np.asarray(values, dtype=float),
            x=time,
        )
        for k, (name, values) in enumerate(columns.items())
    ]
    pyuff.UFF(str(path)).write_sets(sets, mode="add")


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    out = tmp_path_factory.mktemp("uff")
    time, columns, units, truth = EXAMPLE["operational_run"](seed=3, duration=120.0)
    write_records(out / "run.uff", time, columns, units)
    fs.write_measured(out / "run.tdms", time, {n: (x, units[n]) for n, x in columns.items()})
    return out, time, columns, truth


def test_time_records_read_as_the_tdms_of_the_same_samples(bench):
    out, time, columns, _ = bench
    uff, tdms = read_measured(out / "run.uff"), read_measured(out / "run.tdms")
    assert list(uff.columns) == list(columns) == list(tdms.columns)
    assert uff.units == tdms.units
    np.testing.assert_allclose(uff.time, time, rtol=0, atol=1e-12 * time[-1])  # start + k·increment
    for name in columns:
        np.testing.assert_array_equal(uff.columns[name], tdms.columns[name])  # 58b: doubles, as TDMS's


def test_they_identify_the_same_modes(bench):
    out, _, columns, truth = bench
    channels = list(columns)[:2]  # the two shaft torques
    found = [
        identify_modes([read_measured(out / f)], channels=channels, max_hz=300.0)
        for f in ("run.uff", "run.tdms")
    ]
    a, b = ([m.frequency_hz for m in f.modes] for f in found)
    assert a == b  # the same samples: the same numbers
    # a sanity bound on the estimate itself (120 s of a record with 2 % noise; the guide's 300 s runs
    # land within 0.3 %): the test is the equality above
    np.testing.assert_allclose(a, truth["frequencies_hz"], rtol=5e-3)


def test_the_spectrum_command_reads_one(bench, capsys):
    from flexshaft.cli import main

    out, *_ = bench
    assert main(["spectrum", str(out / "run.uff"), "--column", "torque s1", "--json"]) == 0
    assert '"peaks"' in capsys.readouterr().out


def test_damaged_universal_files_get_one_line(tmp_path):
    bad = tmp_path / "bad.uff"
    bad.write_bytes(b"hello, not a universal file\n")
    with pytest.raises(ModelError, match="is not a universal file"):
        read_measured(bad)
    t = np.arange(0.0, 1.0, 1e-3)
    write_records(tmp_path / "good.uff", t, {"torque s1": np.sin(t)}, {"torque s1": "N·m"}, binary=0)
    text = (tmp_path / "good.uff").read_text()
    cut = tmp_path / "cut.uff"
    cut.write_text(text[: len(text) // 2])  # truncated in its values
    with pytest.raises(ModelError) as err:
        read_measured(cut)
    assert "\n" not in str(err.value) and "cut.uff" in str(err.value)
    claims = tmp_path / "claims.uff"
    claims.write_text(text.replace(f"{t.size:10d}", f"{10**9:10d}", 1))  # num_pts far beyond the file
    with pytest.raises(ModelError) as err:
        read_measured(claims)
    assert "\n" not in str(err.value) and "claims.uff" in str(err.value)
