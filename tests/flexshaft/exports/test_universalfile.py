"""Universal files read by pyuff, the modal-test side's reader (not by flexshaft): the modes (units 164,
stations 2411, modes 55) and the frequency responses (58, binary)."""

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.statespace import frequency_grid, frequency_response, state_space
from flexshaft.cli import main
from flexshaft.exports.universalfile import TORSION_DIRECTION, write_frf_uff, write_modes_uff
from flexshaft.linalg.mac import mac
from tests.conftest import EXAMPLES, run_peer

pyuff = pytest.importorskip("pyuff", reason="pyuff is not installed (the uff extra)")

# Dataset 55's records are written as E13.5, six significant digits (the format, not flexshaft):
# a value read back is within half a unit of the fifth decimal of its mantissa.
E13_5 = 5e-6


@pytest.fixture(scope="module")
def customer1():
    return fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))


def test_the_modes_as_modal_test_software_reads_them(customer1, tmp_path):
    path = write_modes_uff(customer1, tmp_path / "c1.uff")
    sets = pyuff.UFF(str(path)).read_sets()
    assert [s["type"] for s in sets] == [164, 2411] + [55] * customer1.count
    assert sets[0]["units_code"] == 1 and sets[0]["length"] == 1.0 and sets[0]["force"] == 1.0
    model = customer1.model
    np.testing.assert_allclose(
        sets[1]["x"],
        [model.x[st.node] for st in model.stations],
        rtol=1e-15,
        atol=0,  # 2411: D25.16
    )
    modes = sets[2:]
    freqs = np.array([m["freq"] for m in modes])
    np.testing.assert_allclose(freqs, customer1.frequencies_hz, rtol=E13_5, atol=0.0)
    np.testing.assert_allclose(
        [m["modal_damp_vis"] for m in modes], customer1.damping_ratios, rtol=E13_5, atol=1e-30
    )
    # the torsion shapes at the stations, against flexshaft's own: the same vectors
    ours = customer1.station_shapes()
    for k, m in enumerate(modes):
        assert m["mode_n"] == k + 1 and m["modal_m"] == 1.0
        assert m["id3"].startswith("damping: per part")  # the damping variant, stated
        assert np.all(m["r1"] == 0.0) and np.all(m["r5"] == 0.0)  # a torsion model: θx alone
        assert mac(np.asarray(m["r4"]), ours[:, k]) >= 1 - 1e-9


def test_sdynpy_reads_the_same_modes(customer1, tmp_path):
    """SDynPy (the peers' virtualenv), a second reader nobody here wrote: its geometry from dataset 2411,
    its shapes from 55 - the frequencies, damping and shapes pyuff reads."""
    path = write_modes_uff(customer1, tmp_path / "c1.uff")
    got = run_peer("sdynpy_modes.py", {"path": str(path)}, what="SDynPy", timeout=120)
    if "missing" in got:
        pytest.skip(f"{got['missing']} in the peers' virtualenv (benchmarks/setup_peers.sh)")
    model = customer1.model
    assert got["node_ids"] == list(range(1, len(model.stations) + 1))
    np.testing.assert_allclose(got["node_x"], [model.x[st.node] for st in model.stations], rtol=1e-15, atol=0)
    np.testing.assert_allclose(got["frequencies_hz"], customer1.frequencies_hz, rtol=E13_5, atol=0.0)
    np.testing.assert_allclose(got["damping_ratios"], customer1.damping_ratios, rtol=E13_5, atol=1e-12)
    rx = [k for k, c in enumerate(got["coordinates"]) if c.endswith("RX+")]
    shapes = np.asarray(got["shapes"])[:, rx].T  # each station's θx, per mode
    ours = customer1.station_shapes()
    # six significant digits per value (E13.5): MAC within ~1e-10 of 1
    assert np.all(np.diag(mac(shapes, ours)) > 1 - 1e-9)


def test_the_modes_are_mass_normalised(customer1, tmp_path):
    """Dataset 55 says modal mass 1: φᵀMφ = 1 with φ read back (kinetic energy of the rigid chain of
    station inertias cannot check it; the model's own mass matrix on its coordinates can)."""
    sets = pyuff.UFF(str(write_modes_uff(customer1, tmp_path / "m.unv"))).read_sets()
    rows = customer1.model.node_dof(customer1.model.station_nodes)
    exact = customer1.node_shapes[rows]
    for k, m in enumerate(sets[2:]):
        np.testing.assert_allclose(m["r4"], exact[:, k], rtol=E13_5, atol=E13_5 * np.abs(exact[:, k]).max())


def test_frequency_responses_to_the_last_bit(customer1, tmp_path):
    ss = state_space(customer1, ["motor"], ["speed:generator", "torque:part 3"])
    resp = frequency_response(ss, frequency_grid(ss, 1.0, 100.0, 300))
    sets = pyuff.UFF(str(write_frf_uff(resp, customer1.model, tmp_path / "frf.uff"))).read_sets()
    assert [s["type"] for s in sets] == [164, 58, 58]
    names = [st.name for st in customer1.model.stations]
    for i, s in enumerate(sets[1:]):
        assert s["func_type"] == 4 and s["rsp_dir"] == TORSION_DIRECTION and s["ref_dir"] == TORSION_DIRECTION
        assert s["ref_node"] == names.index("motor") + 1
        np.testing.assert_array_equal(s["x"], resp.frequencies_hz)  # 58b: doubles, bit for bit
        np.testing.assert_array_equal(s["data"], resp.H[:, i, 0])
    assert sets[1]["rsp_node"] == names.index("generator") + 1
    assert (
        sets[1]["ordinate_axis_units_lab"].strip() == "rad/s"
        and sets[2]["ordinate_axis_units_lab"].strip() == "N·m"
    )


def test_the_command_line_writes_them(tmp_path, capsys):
    model = EXAMPLES / "customer1.toml"
    assert main(["modes", str(model), "--json", "--uff", str(tmp_path / "m.uff")]) == 0
    out = capsys.readouterr().out
    doc = json.loads(out[: out.rindex("}") + 1])
    sets = pyuff.UFF(str(tmp_path / "m.uff")).read_sets()
    np.testing.assert_allclose(
        [s["freq"] for s in sets if s["type"] == 55], [m["frequency_hz"] for m in doc["modes"]], rtol=E13_5
    )
    # each mode's fourth ID line holds its frequency to the last bit: equal to modes --json, as text
    exact = [float(s["id4"].split()[1]) for s in sets if s["type"] == 55]
    assert exact == [m["frequency_hz"] for m in doc["modes"]]
    assert (
        main(
            [
                "frf",
                str(model),
                "--at",
                "motor",
                "--measure",
                "speed:generator",
                "-o",
                str(tmp_path / "f.unv"),
            ]
        )
        == 0
    )
    assert [s["type"] for s in pyuff.UFF(str(tmp_path / "f.unv")).read_sets()] == [164, 58]
    capsys.readouterr()
    assert main(["modes", str(model), "--uff", str(tmp_path / "m.txt")]) == 2
    assert "--uff" in capsys.readouterr().err
    assert main(["modes", str(model), "--uff", str(tmp_path / "m.uff")]) == 2  # exists: needs --force
    assert main(["modes", str(model), "--uff", str(tmp_path / "m.uff"), "--force"]) == 0


def test_a_bodys_free_free_modes_for_the_test_lab(tmp_path, capsys):
    """``reduce -o PART.uff``: the body's free-free modes on the part's mesh nodes, as pyuff reads them."""
    model = EXAMPLES / "customer1_flex.toml"
    path = tmp_path / "part2.uff"
    assert main(["reduce", str(model), "--part", "part 2", "-o", str(path)]) == 0
    capsys.readouterr()
    reduction = fs.reduce_part(fs.load_model(model), "part 2")
    body = reduction.body
    sets = pyuff.UFF(str(path)).read_sets()
    assert [s["type"] for s in sets] == [164, 2411] + [55] * body.free_hz.size
    np.testing.assert_allclose(sets[1]["x"], reduction.part_model.x, rtol=1e-15, atol=0)  # 2411: D25.16
    modes = sets[2:]
    np.testing.assert_allclose([m["freq"] for m in modes], body.free_hz, rtol=E13_5, atol=1e-9)
    recovered = body.T @ body.free_modes  # every mesh node's θx, per free-free mode
    for k, m in enumerate(modes):
        assert m["id3"].startswith("damping: the body's own")
        if body.free_hz[k] > 0:  # a rigid-body mode's shape is any rotation: its MAC is 1 as well
            assert mac(np.asarray(m["r4"]), recovered[:, k]) >= 1 - 1e-9
    # a shaft given by numbers has no positions in metres: refused, naming -o
    numbers = EXAMPLES / "customer1.toml"
    assert (
        main(["reduce", str(numbers), "--part", "part 2", "--modes", "2", "-o", str(tmp_path / "n.uff")]) == 2
    )
    assert "-o" in capsys.readouterr().err
