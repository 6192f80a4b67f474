"""The study file: defaults that make a set-ups-only file a modal study, and one error per mistake.

Every refusal names the file, the table and the key, as a model file's errors do; the values are
read in SI with the unit in the key's name (a string with a unit is converted).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flexshaft.errors import ModelError
from flexshaft.study.studyfile import EXPORT_FORMATS, loads_study, read_study

MINIMAL = '[[setup]]\nmodel = "m.toml"\n'


def test_a_file_with_only_set_ups_is_the_modal_study(tmp_path):
    s = loads_study(MINIMAL, source=str(tmp_path / "bench.toml"), folder=tmp_path)
    assert s.name == "bench"
    assert [(x.name, x.model) for x in s.setups] == [("m", tmp_path / "m.toml")]  # relative to the file
    assert s.damping == "parts" and s.variants == ("parts",)
    assert s.modes.count is None and s.modes.mesh_check
    assert s.frf == () and s.simulate == () and s.campbell is None and s.calibration is None
    assert s.views.modes is None  # the first three elastic modes


def test_every_table_is_read_with_its_units(tmp_path):
    text = (
        '[study]\nname = "bench"\nmax_hz = "0.4 kHz"\ndamping = "both"\nsystem_damping_ratio = 0.006\n'
        '[[setup]]\nname = "C1"\nmodel = "/abs/c1.toml"\n[[setup]]\nname = "WD"\nmodel = "wd.toml"\n'
        "[modes]\ncount = 12\nmesh_check = false\n"
        '[[frf]]\nsetups = "C1"\ninput = "motor"\noutputs = ["speed:motor"]\nto_hz = 300\n'
        "[[forced]]\namplitude = 500\n"
        '[[simulate]]\nname = "ramp"\nend_speed_rpm = 1800\nramp_time_s = "10000 ms"\n'
        'outputs = ["torque:part 3"]\norders = [1, 6]\n'
        "[campbell]\nspeed_rpm = [0, 1800]\n"
        '[calibration]\ntargets = "t.toml"\n'
        '[[export]]\nsetups = ["C1"]\npart = "part 2"\nformats = ["npz", "op4"]\ncutoff_hz = 2000\n'
        "[views]\nmodes = [1, 2]\n"
    )
    s = loads_study(text, source="bench.toml", folder=Path("/base"))
    assert s.max_hz == pytest.approx(400.0)
    assert s.variants == ("parts", "system") and s.system_damping_ratio == 0.006
    assert s.setups[0].model == Path("/abs/c1.toml") and s.setups[1].model == Path("/base/wd.toml")
    assert s.frf[0].setups == ("C1",) and s.frf[0].to_hz == 300.0
    assert s.forced[0].amplitude == 500.0 and s.forced[0].input is None  # the driving end, found at run time
    run = s.simulate[0]
    assert run.options == {"end_speed_rpm": 1800.0, "ramp_time": pytest.approx(10.0)}
    assert run.orders == (1.0, 6.0)
    assert s.campbell.speed_rpm == (0.0, 1800.0)
    assert s.calibration.targets == Path("/base/t.toml")
    assert s.exports[0].formats == ("npz", "op4") and s.exports[0].cutoff_hz == 2000.0
    assert s.views.modes == (1, 2)
    assert s.setups_of(None) == ("C1", "WD")


@pytest.mark.parametrize(
    "text, says",
    [
        ("", "setup"),
        ('[[setup]]\nname = "x"\n', "model"),
        (MINIMAL + "[study]\nmax_hz = -1\n", "max_hz"),
        (MINIMAL + '[study]\ndamping = "modal"\n', "'parts', 'system', 'both'"),
        (MINIMAL + "[study]\ncolour = 1\n", "colour"),
        (MINIMAL + "[plots]\nx = 1\n", "plots"),
        (MINIMAL + '[[frf]]\ninput = "motor"\n', "outputs"),
        (MINIMAL + '[[frf]]\nsetups = ["nowhere"]\noutputs = ["speed:motor"]\n', "no such set-up"),
        (MINIMAL + '[[frf]]\noutputs = ["speed:motor"]\nfrom_hz = 50\nto_hz = 10\n', "to_hz"),
        (MINIMAL + '[[simulate]]\noutputs = ["a"]\n', "name"),
        (MINIMAL + '[[simulate]]\nname = "r"\noutputs = ["a"]\n', "end_speed_rpm"),
        (MINIMAL + '[[simulate]]\nname = "r"\nscenario = "csv"\noutputs = ["a"]\n', "series"),
        (
            MINIMAL + '[[simulate]]\nname = "r"\nscenario = "step"\noutputs = ["a"]\nspectra = ["b"]\n',
            "spectra",
        ),
        (
            MINIMAL
            + '[[simulate]]\nname = "r"\nscenario = "step"\noutputs = ["a"]\nramp_time_s = "9**9**9 s"\n',
            "ramp_time_s",
        ),
        (MINIMAL + "[campbell]\nspeed_rpm = [1800, 0]\n", "speed_rpm"),
        (MINIMAL + '[[export]]\npart = "p"\nformats = ["step"]\n', "formats"),
        (MINIMAL + "[views]\nmodes = [-1]\n", "modes"),
        (MINIMAL + '[[setup]]\nname = "m"\nmodel = "other.toml"\n', "two set-ups"),
        # names that become one file-name piece (slug) would write each other's files
        (
            '[[setup]]\nname = "Customer 1"\nmodel = "a.toml"\n'
            '[[setup]]\nname = "customer-1"\nmodel = "b.toml"\n',
            "names its files 'customer-1', as the set-up 'Customer 1' does",
        ),
        (
            MINIMAL + '[[simulate]]\nname = "Ramp"\nscenario = "step"\noutputs = ["a"]\n'
            '[[simulate]]\nname = "ramp!"\nscenario = "step"\noutputs = ["a"]\n',
            "names its files 'ramp'",
        ),
        (MINIMAL + '[[export]]\npart = "part 2"\n[[export]]\npart = "Part-2"\n', "exported part"),
        ("[[setup]\n", "TOML"),
    ],
)
def test_each_mistake_is_one_error_naming_its_key(tmp_path, text, says):
    with pytest.raises(ModelError) as err:
        loads_study(text, source="bench.toml", folder=tmp_path)
    message = str(err.value)
    assert "\n" not in message and message.startswith("bench.toml")
    assert says in message


def test_the_file_is_read_as_every_input(tmp_path):
    (tmp_path / "s.toml").write_text(MINIMAL)
    assert read_study(tmp_path / "s.toml").setups[0].model == tmp_path / "m.toml"
    with pytest.raises(ModelError, match="not found|no such|does not exist"):
        read_study(tmp_path / "missing.toml")
    (tmp_path / "big.toml").write_bytes(b"#" * (2 << 20))  # over the study file's 1 MB ceiling
    with pytest.raises(ModelError, match="study file"):
        read_study(tmp_path / "big.toml")


def test_export_formats_default_to_all_five():
    s = loads_study(MINIMAL + '[[export]]\npart = "p"\n')
    assert s.exports[0].formats == EXPORT_FORMATS == ("npz", "json", "mat", "op4", "pch")
