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
    with pytest.raises(
        fs.ModelError, match=r"^nu = 0.5: out of range; valid: a finite number > -1 and < 0.5$"
    ):
        fs.Material(E=1e9, nu=0.5, rho=1000)
    with pytest.raises(fs.ModelError, match=r"^rho = nan kg/m³: not finite"):
        fs.Material(E=1e9, nu=0.3, rho=float("nan"))


def test_model_error_is_a_value_error_with_fields():
    err = fs.ModelError(
        "out of range", file="m.toml", component="'p'", field="inertia", value=-1.0, unit="kg·m²", valid="> 0"
    )
    assert isinstance(err, ValueError)
    assert str(err) == "m.toml: 'p': inertia = -1.0 kg·m²: out of range; valid: > 0"
    assert (err.field, err.value, err.unit) == ("inertia", -1.0, "kg·m²")


@pytest.mark.parametrize(
    "kwargs, says",
    [
        ({"E": 1e308}, "E = 1e+308 Pa: out of range; valid: a finite number >= 1000 and <= 1e+15 (Pa)"),
        ({"E": 1e-10}, "E = 1e-10 Pa: out of range"),
        ({"rho": 1e20}, "rho = 1e+20 kg/m³: out of range; valid: a finite number > 0 and <= 1e+06 (kg/m³)"),
    ],
)
def test_material_constants_of_no_material_are_refused(kwargs, says):
    # E = 1e308 overflowed the 6-DOF element matrices (warnings, then an error); E = 1e-10 or
    # rho = 1e20 put a part's modes below the round-off of its rigid-body ones.
    with pytest.raises(fs.ModelError) as err:
        fs.Material(**({"E": 210e9, "nu": 0.29, "rho": 7850.0} | kwargs))
    assert str(err.value).startswith(says)


def test_numbers_in_messages_are_numbers_numpy_or_not():
    # numpy 2's repr of a scalar is np.float64(0.742): a message shows the number alone.
    import numpy as np

    from flexshaft.errors import format_value

    assert str(fs.ModelError("m", field="t", value=np.float64(0.742), unit="s")) == "t = 0.742 s: m"
    assert format_value(np.int64(3)) == "3" and format_value(np.float32(0.5)) == "0.5"
    assert format_value(np.array(2.5)) == "2.5" and format_value(np.bool_(True)) == "true"
    assert format_value(np.float64("nan")) == "nan" and format_value(np.float64("-inf")) == "-inf"
    assert format_value([np.float64(1.5), 2]) == "[1.5, 2]"
    assert format_value(np.array([1.0, 2.0])) == "[1.0, 2.0]"
    assert format_value(np.zeros(1000)) == "an array of 1000 values"
    long = format_value([1.0] * 100_000)  # a list from a file: the line stays readable
    assert len(long) < 250 and long.endswith("(500000 characters)")
