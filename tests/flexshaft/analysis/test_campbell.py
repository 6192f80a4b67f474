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
from tests.conftest import EXAMPLES, run_peer


def test_crossings_of_a_two_inertia_line_are_where_the_orders_meet_its_closed_form_mode():
    # f = sqrt(k(1/J1 + 1/J2))/2π; order k crosses it at n = 60·f/k rpm (a horizontal mode line, so the
    # crossing is exact: n = 60·f/k of a 2-DOF eigen-solve, good to a few eps; 1e-9 is loose).
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
    # the order lines are k·n/60 over the speed axis (an ulp or two: rtol 1e-7), the mode constant (the
    # same number tiled: ptp exactly 0; no speed-dependent terms)
    np.testing.assert_allclose(diagram.order_line(6), 6 * diagram.speeds_rpm / 60, rtol=1e-7)
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
    # The same f and ξ times 60 and the gear ratio: a few roundings.
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
    # JSON keeps every digit: 60·f/k in another order, a few roundings
    assert speeds == pytest.approx(sorted(60 * f1 / k for k in (1, 2, 6)), rel=1e-12)
    png = tmp_path / "c.png"
    assert main(["campbell", model, "--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "Campbell diagram" in capsys.readouterr().out
    for bad, field in [
        (["--speed", "1800"], "--speed"),
        (["--speed", "900:100"], "--speed"),  # the library's "speed (high)", named as the option
        (["--speed", "0:1e308"], "--speed"),  # order lines beyond 1e9 Hz
        (["--orders", "1,x"], "--orders"),
        (["--orders", "0"], "--orders"),
        (["--orders", "nan"], "--orders"),
        (["--orders", ""], "--orders"),
        (["--reference", "nowhere"], "reference"),
    ]:
        assert main(["campbell", model, *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and field in err


def _rotor(n=20, disc=False):
    """A uniform 1 m, 50 mm steel shaft on two 1e7 N/m bearings; with a disc at mid-span if asked."""
    from flexshaft.sections import table_from_segments

    def shaft(name, length, elements):
        t = table_from_segments([{"length": length, "od": 0.05}], name=name)
        return Shaft.from_sections(name, t, fs.STEEL, max_element_length=length / elements)

    if not disc:
        return Drivetrain(
            "rotor", (shaft("s", 1.0, n),), dofs="full", bearings=(("s start", 1e7), ("s end", 1e7))
        )
    comps = (
        shaft("a", 0.5, n // 2),
        Rigid("disc", 0.12, mass=12.0, diametral_inertia=0.06),
        shaft("b", 0.5, n // 2),
    )
    return Drivetrain("rotor", comps, dofs="full", bearings=(("a start", 1e7), ("b end", 1e7)))


def test_the_gyroscopic_element_turns_a_rigid_tilt_by_its_spinning_inertia():
    # A rigid tilt is represented exactly by the element's shape functions, so the gyroscopic coupling
    # of a tilt about z with a tilt about y is the element's spinning inertia ρ·Ip·L (the moment a
    # rigid disc of that polar inertia feels per unit spin and tilt rate), and G is skew-symmetric.
    from flexshaft.elements import timoshenko_gyroscopic

    L, rho, d = 0.3, 7850.0, 0.08
    ip = np.pi * d**4 / 32
    G = timoshenko_gyroscopic(L=L, E=210e9, G=81e9, rho=rho, Iy=ip / 2, Iz=ip / 2, Ip=ip, Asy=1e-3, Asz=1e-3)
    np.testing.assert_allclose(G, -G.T, atol=0)
    xc = L / 2
    tilt_z = np.zeros(12)  # θz = 1: uy = x − xc
    tilt_z[[1, 5, 7, 11]] = [-xc, 1.0, L - xc, 1.0]
    tilt_y = np.zeros(12)  # θy = 1: uz = −(x − xc)
    tilt_y[[2, 4, 8, 10]] = [xc, 1.0, -(L - xc), 1.0]
    # A 12 × 12 quadratic form whose terms (ρIp/30L × 36, 3L, 4L²...) cancel a few times: ~1e-15
    assert abs(tilt_z @ G @ tilt_y) == pytest.approx(rho * ip * L, rel=1e-12)


@pytest.fixture(scope="module")
def ross_whirl():
    """ROSS 2.3's whirl frequencies of the shaft without and with a disc, at 0 … 12 000 rpm (Hz).

    Both rotors in one run of the peer (its import alone takes seconds).
    """
    specs = []
    for disc in (False, True):
        spec = {"L": 1.0, "D": 0.05, "n": 20, "k_bearing": 1e7, "count": 8}
        spec |= {"E": fs.STEEL.E, "nu": fs.STEEL.nu, "rho": fs.STEEL.rho}
        spec["speeds"] = [s * 2 * math.pi / 60 for s in SPEEDS_RPM]  # rad/s
        if disc:
            spec["disk"] = {"node": 10, "m": 12.0, "Id": 0.06, "Ip": 0.12}
        specs.append(spec)
    out = run_peer("ross_campbell.py", specs, what="ROSS", timeout=600)
    return {disc: np.array(o["frequencies_hz"]) for disc, o in zip((False, True), out)}


SPEEDS_RPM = [0.0, 3000.0, 6000.0, 9000.0, 12000.0]


# Slow step: ROSS imports in its own virtualenv for ~11 s before it computes anything.
@pytest.mark.slow
@pytest.mark.parametrize("disc", [False, True], ids=["shaft", "shaft with a disc"])
def test_whirl_frequencies_of_a_spinning_shaft_equal_ross(disc, ross_whirl):
    # The same uniform steel shaft on two bearings in ROSS 2.3 (Timoshenko, gyroscopic), run in its own
    # virtualenv: forward and backward whirl frequencies at 0 … 12 000 rpm agree to round-off of the two
    # solvers, the split growing with speed. ROSS's first-order matrix is unscaled (M⁻¹K: norm ω_max²), so
    # its roots carry ~eps·(f_max/f₁)² = 9e-11 (f_max/f₁ = 630), 2e-10 with the disc (980; measured 4e-11,
    # 3e-10); ours, scaled to norm ω_max, eps·f_max/f₁ ≈ 2e-13. 1e-8 leaves 50x; a missing or mis-signed
    # gyroscopic, shear or rotary-inertia term moves them 1e-4 or more. With a disc at
    # mid-span (mass, diametral and polar inertia: a rigid component with mass and diametral_inertia)
    # its gyroscopic moment dominates - 245 Hz splits to 216/269 Hz - and must have the shaft's sign.
    ross = ross_whirl[disc]
    m = fs.assemble(_rotor(disc=disc))
    r = fs.modal_analysis(m, m.n_dof)
    diagram = campbell(r, (0.0, 12000.0), (1,), points=5, max_hz=1.01 * ross.max())
    assert diagram.speed_dependent
    np.testing.assert_allclose(diagram.frequencies_hz[:, :8], ross, rtol=1e-8)
    # the first bending pair is one frequency at standstill (its first-order matrix is then normal: the
    # split is round-off, eps·f_max/f₁ ≈ 2e-13 relative) and splits wider with every speed step
    split = diagram.frequencies_hz[:, 1] - diagram.frequencies_hz[:, 0]
    assert split[0] <= 1e-9 * diagram.frequencies_hz[0, 0] and np.all(np.diff(split) > 0)


def test_a_spinning_crossing_is_where_the_whirl_meets_the_order():
    # At every crossing the whirl frequency at that speed equals k·n/60 (bisection to 1e-9 rpm, 1e-12
    # of the speed; the roots' round-off eps·f_max/f ≈ 1e-13): 1e-9 leaves three orders.
    m = fs.assemble(_rotor(10))
    r = fs.modal_analysis(m, m.n_dof)
    diagram = campbell(r, (0.0, 12000.0), (1.0,), points=13, max_hz=400.0)
    forward = [c for c in diagram.crossings if c.mode == diagram.modes[1]]
    assert diagram.crossings and forward
    for c in diagram.crossings:
        assert c.frequency_hz == pytest.approx(c.order * c.speed_rpm / 60, rel=1e-9)
