"""The nonlinear laws of couplings and gear meshes: their keys in the model file, their one-line
errors, the curves they build, and the linear model every linear analysis takes from them."""

import math

import numpy as np
import pytest

from flexshaft import ModelError
from flexshaft.analysis.modal import modal_analysis
from flexshaft.input.modelfile import loads_model
from flexshaft.model.assembly import assemble
from flexshaft.model.components import Coupling, Drivetrain, Gear, Rigid
from flexshaft.model.nonlinear import CURVE_TOLERANCE, TorqueCurve

CHAIN = """
[model]
name = "nl"
[[chain]]
name = "motor"
type = "rigid"
inertia = 2.0
[[chain]]
name = "c"
type = "coupling"
{coupling}
[[chain]]
name = "load"
type = "rigid"
inertia = 3.0
"""


def _load(coupling: str):
    return loads_model(CHAIN.format(coupling=coupling), "nl.toml")


def test_model_file_keys_build_the_laws():
    slip = _load('stiffness = 1e4\nslip_torque = "2 kN*m"\nslip_kinetic_torque = 1500.0\nslip_damping = 3.0')
    law = slip.components[1].law
    assert (law.kind, law.torque, law.kinetic_torque, law.damping) == ("slip", 2000.0, 1500.0, 3.0)
    gap = _load('stiffness = 1e4\nbacklash = "0.5 deg"').components[1].law
    assert gap.kind == "backlash" and gap.gap == pytest.approx(math.radians(0.5), rel=1e-12)
    curve = _load("torque_curve = [[0.01, 100.0], [0.02, 300.0]]").components[1]
    assert curve.law.kind == "curve" and curve.stiffness == pytest.approx(1e4, rel=1e-12)


@pytest.mark.parametrize(
    "keys, field, words",
    [
        ("stiffness = 1e4\nslip_torque = -5.0", "slip_torque", "out of range"),
        (
            "stiffness = 1e4\nslip_torque = 10.0\nslip_kinetic_torque = 20.0",
            "slip_kinetic_torque",
            "above the static",
        ),
        ("backlash = 0.01", "stiffness", "needs the element's stiffness"),
        ("stiffness = 1e4\nbacklash = 0.01\nslip_torque = 5.0", "backlash", "one nonlinear law"),
        ("stiffness = 1e4\nslip_damping = 2.0", "slip_damping", "belongs to a slipping coupling"),
        (
            "stiffness = 1e4\ntorque_curve = [[0.01, 100.0], [0.02, 300.0]]",
            "stiffness",
            "comes from the torque_curve",
        ),
        ("torque_curve = [[0.0, 0.0], [0.02, 300.0], [0.01, 400.0]]", "torque_curve[2][0]", "monotone"),
        ("torque_curve = [[-0.01, -50.0], [0.02, 300.0]]", "torque_curve", "(0 rad, 0 N·m)"),
        ("stiffness_curve = [[0.0, 1e4], [100.0, -1.0]]", "stiffness_curve[1][1]", "out of range"),
        ("stiffness_curve = [[0.0, 1e4]]", "stiffness_curve", "at least two points"),
        ("stiffness = 1e4\nbacklash = 7.0", "backlash", "out of range"),
        ("slip_torque = 5.0", "stiffness", "needs the element's stiffness"),
    ],
)
def test_bad_values_get_one_line_naming_the_key(keys, field, words):
    with pytest.raises(ModelError) as err:
        _load(keys)
    text = str(err.value)
    assert "\n" not in text and err.value.field == field and words in text
    assert "'c'" in text  # the component


def test_gear_backlash_needs_the_mesh_stiffness():
    with pytest.raises(ModelError, match="mesh_stiffness") as err:
        Gear("g", 2.0, backlash=0.01)
    assert err.value.field == "mesh_stiffness"
    assert Gear("g", 2.0, mesh_stiffness=1e5, backlash=0.01).law.gap == 0.01
    assert Gear("g", 2.0, torque_curve=[[0.01, 1e3], [0.02, 3e3]]).mesh_stiffness == pytest.approx(1e5)


def test_stiffness_curve_angles_are_the_integral_of_one_over_k():
    """Tangent stiffness linear in torque, k = k0 + a·T: the twist at torque T is ln(k/k0)/a, exactly
    at the listed torques; between them the chords are within the stated tolerance."""
    k0, k1, top = 1e5, 3e5, 2000.0
    curve = TorqueCurve.from_stiffness([[0.0, k0], [top, k1]])
    a = (k1 - k0) / top
    torques = np.linspace(-top, top, 81)
    exact = np.sign(torques) * np.log((k0 + a * np.abs(torques)) / k0) / a
    twist_at_top = np.log(k1 / k0) / a
    assert curve.torque_at([twist_at_top, -twist_at_top]) == pytest.approx([top, -top], rel=1e-12)
    # the inverse of the chord curve against the exact integral: within the tolerance of the span
    chord_angle = np.interp(torques, curve.torque, curve.angle)
    np.testing.assert_allclose(chord_angle, exact, rtol=0, atol=2 * CURVE_TOLERANCE * twist_at_top)
    # beyond the last torque the stiffness stays the last one
    assert curve.torque_at(twist_at_top + 1e-3) == pytest.approx(top + k1 * 1e-3, rel=1e-12)
    # the linear analyses' stiffness: the tangent at zero torque, as the chords there have it
    assert curve.tangent_at_zero == pytest.approx(k0, rel=CURVE_TOLERANCE)


def test_linear_analyses_use_the_stuck_in_contact_tangent_element():
    """modes of a chain with each law equal those of the plain coupling it linearises to."""
    plain = modal_analysis(assemble(Drivetrain("p", (Rigid("a", 2.0), Coupling("c", 1e4), Rigid("b", 3.0)))))
    for kw in (
        {"stiffness": 1e4, "slip_torque": 10.0},
        {"stiffness": 1e4, "backlash": 0.01},
        {"torque_curve": [[0.0, 0.0], [0.01, 100.0], [0.02, 300.0]]},
    ):
        chain = Drivetrain("n", (Rigid("a", 2.0), Coupling("c", **kw), Rigid("b", 3.0)))
        np.testing.assert_allclose(
            modal_analysis(assemble(chain)).frequencies_hz, plain.frequencies_hz, rtol=1e-12
        )


def test_modes_table_and_json_say_the_model_is_linearised(tmp_path):
    from flexshaft.cli import main

    path = tmp_path / "nl.toml"
    path.write_text(CHAIN.format(coupling="stiffness = 1e4\nslip_torque = 100.0"), encoding="utf-8")
    import contextlib
    import io
    import json

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["modes", str(path)]) == 0
    assert "'c' (slip) stuck" in out.getvalue()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["modes", str(path), "--json"]) == 0
    doc = json.loads(out.getvalue())
    assert doc["linearised"] == [{"name": "c", "law": "slip", "linear_analyses": "stuck (it never slips)"}]


def test_forced_names_the_modes_that_would_slip_the_coupling(capsys):
    """The study's sliding-coupling check: at each eigenfrequency, the torque the stuck coupling would
    carry against its slip torque (Customer 2: mode 1 puts 58 N·m through part 3 per N·m of drive,
    mode 2 0.11 N·m - so 100 N·m slips it in mode 1 alone)."""
    import json

    from flexshaft.cli import main
    from tests.conftest import EXAMPLES

    model = str(EXAMPLES / "customer2_slip.toml")
    assert main(["forced", model, "--at", "motor", "--torque", "100", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    slips = doc["would_slip"]
    assert [s["mode"] for s in slips] == [1] and slips[0]["component"] == "part 3"
    ex = next(e for e in doc["excitations"] if e["mode"] == 1)
    assert slips[0]["torque"] == ex["amplitude"]["torque:part 3"] > slips[0]["slip_torque"] == 1000.0
    assert main(["forced", model, "--at", "motor", "--torque", "1"]) == 0
    assert "would carry" not in capsys.readouterr().out  # 58 N·m: it holds
