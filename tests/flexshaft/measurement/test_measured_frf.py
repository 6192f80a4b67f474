"""A test lab's frequency responses (universal file, dataset 58, function type 4), written by pyuff as a
lab would write them: read in SI, their peaks and half-power damping against the closed form of the
1-DOF responses they were made from, and the command's refusals."""

import json

import numpy as np
import pytest

from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.measurement.measuredfrf import analyse_frf, read_measured_frfs
from tests.conftest import EXAMPLES

pyuff = pytest.importorskip("pyuff", reason="pyuff is not installed (the uff extra)")

STEP = 0.05  # Hz: the lab's line spacing
F = np.arange(0.0, 400.0 + STEP / 2, STEP)
# (natural frequency Hz, damping ratio): the half-power bands 2ξf span 2.3, 36 and 19 lines
MODES = ((11.6, 0.005), (91.0, 0.01), (243.0, 0.002))


def one_dof(f_n: float, zeta: float, f=F) -> np.ndarray:
    """Speed per torque of one mode (unit modal inertia), rad/s per N·m: iω/(ωn² − ω² + 2iξωnω)."""
    w, wn = 2 * np.pi * f, 2 * np.pi * f_n
    return 1j * w / (wn**2 - w**2 + 2j * zeta * wn * w)


def record(name: str, H, *, unit="rad/s", per="N m", f=F, spacing=1, binary=1) -> dict:
    return pyuff.prepare_58(
        binary=binary,
        id1=name,
        id2="NONE",
        id3="NONE",
        id4="NONE",
        id5="NONE",
        func_type=4,
        ver_num=1,
        load_case_id=0,
        rsp_ent_name="bench",
        rsp_node=2,
        rsp_dir=4,
        ref_ent_name="bench",
        ref_node=1,
        ref_dir=4,
        ord_data_type=6,  # complex double
        num_pts=f.size,
        abscissa_spacing=spacing,
        abscissa_min=float(f[0]),
        abscissa_inc=float(f[1] - f[0]),
        abscissa_spec_data_type=18,
        abscissa_axis_units_lab="Hz",
        ordinate_spec_data_type=11,
        ordinate_axis_units_lab=unit,
        orddenom_spec_data_type=13,
        orddenom_axis_units_lab=per,
        z_axis_spec_data_type=0,
        data=np.asarray(H, dtype=complex),
        x=f,
    )


def write(path, *records) -> str:
    u = pyuff.UFF(str(path))
    u.write_sets(list(records), mode="add")
    return str(path)


@pytest.fixture
def lab_file(tmp_path):
    """One record per mode, and one of all three together (kN·m as the reference unit)."""
    each = [record(f"mode {k + 1}", one_dof(f, z)) for k, (f, z) in enumerate(MODES)]
    total = sum(one_dof(f, z) for f, z in MODES)
    return write(tmp_path / "lab.uff", *each, record("all", total * 1e3, per="kN m"))


def test_the_records_in_si(lab_file):
    frfs = read_measured_frfs(lab_file)
    assert [f.name for f in frfs] == ["mode 1", "mode 2", "mode 3", "all"]
    assert all(f.unit == "rad/s/N·m" for f in frfs)
    np.testing.assert_allclose(frfs[0].frequencies_hz, F, rtol=1e-12)  # min + k·inc, in doubles
    np.testing.assert_array_equal(frfs[0].H, one_dof(*MODES[0]))  # 58b complex doubles, bit for bit
    # per kN·m -> per N·m: the written values were 1000 times the SI ones
    np.testing.assert_allclose(frfs[3].H, sum(one_dof(f, z) for f, z in MODES), rtol=1e-15)


def test_a_single_mode_gives_its_frequency_and_damping(lab_file):
    """The half-power fit of an exact 1-DOF response, its band 2.3 to 36 lines wide: what is left is the
    fit's reading between lines, 1.3e-5 of the damping and 0.002 of a line in frequency at the
    narrowest band (measured); 1e-4 and a tenth of a line asked."""
    for frf, (f_n, zeta) in zip(read_measured_frfs(lab_file)[:3], MODES):
        (peak,) = analyse_frf(frf, count=1).peaks
        # a speed response peaks at the undamped natural frequency exactly
        assert abs(peak["frequency_hz"] - f_n) < 0.1 * STEP
        assert peak["damping_ratio"] == pytest.approx(zeta, rel=1e-4)


def test_several_modes_are_each_found_and_named(lab_file):
    frf = read_measured_frfs(lab_file)[3]
    analysis = analyse_frf(frf, eigenfrequencies=[(1, 11.5), (2, 92.0), (3, 240.0)])
    found = sorted(analysis.peaks, key=lambda p: p["frequency_hz"])
    assert [p["mode"] for p in found] == [1, 2, 3]
    for p, (f_n, _) in zip(found, MODES):
        # a neighbour's tail tilts each peak: within 0.1 % of its mode (0.07 % measured for mode 2)
        assert p["frequency_hz"] == pytest.approx(f_n, rel=1e-3)


def test_the_command(lab_file, tmp_path, capsys):
    model = str(EXAMPLES / "customer1.toml")
    assert main(["spectrum", lab_file, "--column", "mode 2", "--model", model, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["kind"] == "frequency response" and doc["unit"] == "rad/s/N·m"
    assert doc["peaks"][0]["mode"] == 2  # Customer 1's second elastic mode is at 91.05 Hz
    assert main(["spectrum", lab_file, "--column", "all", "--plot", str(tmp_path / "frf.png")]) == 0
    assert "measured frequency response" in capsys.readouterr().out
    assert (tmp_path / "frf.png").stat().st_size > 0
    assert main(["spectrum", lab_file, "--column", "all", "--decay"]) == 2
    assert "--decay" in capsys.readouterr().err


def test_refusals(tmp_path):
    H = one_dof(*MODES[0])
    path = write(tmp_path / "g.uff", record("x", H, unit="g"))  # an acceleration: no torsion unit
    with pytest.raises(ModelError, match="states no unit flexshaft reads"):
        read_measured_frfs(path)
    path = write(tmp_path / "none.uff", record("x", H, per=""))
    with pytest.raises(ModelError, match="states no unit"):
        read_measured_frfs(path)
    uneven = np.sort(np.r_[F[:100], F[100:200:2]])
    path = write(tmp_path / "uneven.uff", record("x", one_dof(11.6, 0.005, uneven), f=uneven, spacing=0))
    with pytest.raises(ModelError, match="unevenly spaced"):
        analyse_frf(read_measured_frfs(path)[0])
    # a damaged file: the claim of points checked against its bytes, one line naming the file
    good = write(tmp_path / "good.uff", record("x", H))
    data = open(good, "rb").read()
    cut = tmp_path / "cut.uff"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(ModelError) as err:
        read_measured_frfs(cut)
    assert "cut.uff" in str(err.value)
