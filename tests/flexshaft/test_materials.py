"""Materials and the error type."""

import pytest

import flexshaft as fs


def test_shear_modulus_is_derived():
    # G = E / (2 (1 + ν)); the study's steel: E = 210 GPa, ν = 0.29 -> 81.395 GPa.
    # 2·(1 + 0.29) and the literal 2.58 may differ by an ulp, then one division: <= 2 eps apart.
    assert fs.STEEL.G == pytest.approx(210e9 / 2.58, rel=1e-15)
    assert fs.Material(E=200e9, nu=0.25, rho=7800).G == pytest.approx(80e9)


def test_material_is_frozen_and_validated():
    with pytest.raises(AttributeError):
        fs.STEEL.E = 1.0
    with pytest.raises(fs.ModelError,
                       match=r"^nu = 0.5: out of range; valid: a finite number > -1 and < 0.5$"):
        fs.Material(E=1e9, nu=0.5, rho=1000)
    with pytest.raises(fs.ModelError, match=r"^rho = nan kg/m³: not finite"):
        fs.Material(E=1e9, nu=0.3, rho=float("nan"))


def test_model_error_is_a_value_error_with_fields():
    err = fs.ModelError("out of range", file="m.toml", component="'p'", field="inertia", value=-1.0,
                        unit="kg·m²", valid="> 0")
    assert isinstance(err, ValueError)
    assert str(err) == "m.toml: 'p': inertia = -1.0 kg·m²: out of range; valid: > 0"
    assert (err.field, err.value, err.unit) == ("inertia", -1.0, "kg·m²")
