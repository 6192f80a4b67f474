"""The Campbell diagram: crossings where k·n/60 meets a mode, against the closed-form frequency."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.campbell import campbell
from flexshaft.cli import main
from flexshaft.model.components import Drivetrain, Rigid, Shaft
from tests.conftest import EXAMPLES


def test_crossings_of_a_two_inertia_line_are_where_the_orders_meet_its_closed_form_mode():
    # f = sqrt(k(1/J1 + 1/J2))/2π; order k crosses it at n = 60·f/k rpm (a horizontal mode line, so the
    # crossing is exact: 1e-9 from the eigen-solve of a 2-DOF model).
    j1, j2, k = 2.0, 0.5, 4e4
    d = Drivetrain("two", (Rigid("a", j1), Shaft("s", stiffness=k, inertia=0.0), Rigid("b", j2)))
    f = math.sqrt(k * (1 / j1 + 1 / j2)) / (2 * math.pi)  # 50.3 Hz
    diagram = campbell(fs.modal_analysis(d), (0.0, 3500.0), (1, 2, 6))
    got = {c.order: c.speed_rpm for c in diagram.crossings}
    # order 1 would cross at 3 020 rpm, 2 at 1 510, 6 at 503: all inside 0 … 3500
    assert set(got) == {1.0, 2.0, 6.0}
    for order, n in got.items():
        assert n == pytest.approx(60 * f / order, rel=1e-9)
    assert [c.speed_rpm for c in diagram.crossings] == sorted(got.values())
    # the order lines are k·n/60 over the speed axis, the mode constant (no speed-dependent terms)
    np.testing.assert_allclose(diagram.order_line(6), 6 * diagram.speeds_rpm / 60)
    assert np.ptp(diagram.frequencies_hz[:, 0]) == 0.0 and not diagram.speed_dependent
    # a range below the crossing has none
    assert campbell(fs.modal_analysis(d), (0.0, 400.0), (1, 2, 6)).crossings == ()


def test_reference_past_a_gear_stage_uses_that_shafts_orders():
    # The NREL 5-MW drivetrain's one mode (2.2227 Hz, its closed form): the generator's first order crosses
    # it at 60·f rpm of the generator, 97 times faster than the rotor's crossing.
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "nrel5mw.toml"))
    f = r.frequencies_hz[1]
    gen = campbell(r, (0.0, 1500.0), (1,), reference="generator")
    rotor = campbell(r, (0.0, 1500.0), (97,), reference="rotor")
    assert gen.crossings[0].speed_rpm == pytest.approx(60 * f, rel=1e-12)
    assert rotor.crossings[0].speed_rpm == pytest.approx(60 * f / 97, rel=1e-12)
    assert gen.crossings[0].damping_ratio == pytest.approx(r.damping_ratios[1], rel=1e-12)


def test_cli_json_table_and_bad_input(capsys, tmp_path):
    model = str(EXAMPLES / "customer1.toml")
    assert main(["campbell", model, "--speed", "0:1800", "--orders", "1,2,6", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["units"]["speed"] == "rpm" and doc["reference"] == "motor"
    f1 = doc["modes"][0]["frequency_hz"]
    speeds = sorted(c["speed_rpm"] for c in doc["crossings"] if c["mode"] == 1)
    assert speeds == pytest.approx(sorted(60 * f1 / k for k in (1, 2, 6)), rel=1e-12)
    png = tmp_path / "c.png"
    assert main(["campbell", model, "--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "Campbell diagram" in capsys.readouterr().out
    for bad, field in [
        (["--speed", "1800"], "--speed"),
        (["--speed", "900:100"], "speed (high)"),
        (["--orders", "1,x"], "--orders"),
        (["--orders", "0"], "orders"),
        (["--reference", "nowhere"], "reference"),
    ]:
        assert main(["campbell", model, *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and field in err
