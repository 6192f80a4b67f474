"""Numbers with units in model files: converted to SI on read, a wrong dimension named."""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs

SI = """
[model]
rayleigh = {alpha = 0.1, beta = 2e-6}

[materials.s]
E = 2.1e11
nu = 0.29
rho = 7850

[[chain]]
name = "motor"
type = "rigid"
inertia = 58.1

[[chain]]
name = "p1"
type = "shaft"
stiffness = 307933.18
inertia = 0.44
damping = 12.0

[[chain]]
name = "p4"
type = "shaft"
material = "s"
segments = [{length = 0.3, od = 0.16, id = 0.04}]
stations = {j = 0.1}

[[chain]]
name = "gen"
type = "rigid"
inertia = 6670.0
"""

WITH_UNITS = (
    SI.replace("alpha = 0.1, beta = 2e-6", 'alpha = "0.1 1/s", beta = "2 us"')
    .replace("E = 2.1e11", 'E = "210 GPa"')
    .replace("rho = 7850", 'rho = "7.85 g/cm^3"')
    .replace("inertia = 58.1", 'inertia = "58.1 kg*m^2"')
    .replace("stiffness = 307933.18", 'stiffness = "307.93318 kN*m/rad"')
    .replace("damping = 12.0", 'damping = "0.012 kN*m*s/rad"')
    .replace("length = 0.3, od = 0.16, id = 0.04", 'length = "300 mm", od = "16 cm", id = "40 mm"')
    .replace("j = 0.1", 'j = "100 mm"')
    .replace("inertia = 6670.0", 'inertia = "6.67 t*m^2"')
)


def test_a_model_with_units_is_the_same_model_in_si():
    a = fs.modal_analysis(fs.loads_model(SI, source="si.toml"))
    b = fs.modal_analysis(fs.loads_model(WITH_UNITS, source="units.toml"))
    # Unit conversion is a multiplication by an exact-ish factor: inputs an ulp apart (three inertia
    # entries here), so two independent round-offs of the solve - eps·λ_max/λ/2 = 4e-11 on the 11.5 Hz
    # mode beside a 7 kHz one, eps·(ω_max/ω)/ξ = 6e-11 on its ratio (ξ = 0.0021). Any unit slip is 1e-3.
    np.testing.assert_allclose(b.frequencies_hz, a.frequencies_hz, rtol=1e-10)
    np.testing.assert_allclose(b.damping_ratios, a.damping_ratios, rtol=1e-9)


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("inertia = 58.1", 'inertia = "58.1 kg"', "inertia = '58.1 kg': has the unit kilogram, which is not"),
        ("stiffness = 307933.18", 'stiffness = "3 m"', "stiffness = '3 m': has the unit meter, which is not"),
        ("stiffness = 307933.18", 'stiffness = "a lot"', "stiffness = 'a lot': is not a number with a unit"),
        ("length = 0.3", 'length = "0.3 kg"', "segments[0].length = '0.3 kg': has the unit kilogram"),
        ("E = 2.1e11", 'E = "210 GN"', "E = '210 GN': has the unit giganewton, which is not a Pa"),
    ],
)
def test_a_unit_of_the_wrong_dimension_is_named(old, new, message):
    with pytest.raises(fs.ModelError) as err:
        fs.loads_model(SI.replace(old, new), source="m.toml")
    assert message in str(err.value) and "\n" not in str(err.value)
