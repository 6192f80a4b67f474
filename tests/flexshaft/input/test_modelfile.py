"""The model file: the shipped examples load, and every bad input gets one clear message."""

import textwrap

import numpy as np
import pytest

import flexshaft as fs
from tests.conftest import EXAMPLES

RIGID = '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n'


def _load(text: str):
    return fs.loads_model(textwrap.dedent(text), source="m.toml")


def test_examples_reproduce_the_published_parameters():
    # Values restated in docs/theory/08-test-bench.md (the published parameters): typed into the test,
    # not read from our code.
    c1 = fs.load_model(EXAMPLES / "customer1.toml")
    got = [(c.name, c.type, getattr(c, "stiffness", None), c.inertia) for c in c1.components]
    assert got == [
        ("motor", "rigid", None, 58.10),
        ("part 1", "shaft", 307933.18, 0.44),
        ("part 2", "shaft", 156591.02, 0.75),
        ("part 3", "coupling", 55120.04, 0.06),
        ("part 4", "shaft", 295285.92, 0.03),
        ("generator", "rigid", None, 6.67),
    ]
    assert [getattr(c, "damping_ratio", 0.0) for c in c1.components] == [0, 0.0053, 0.0053, 0, 0.0053, 0]
    c2 = fs.load_model(EXAMPLES / "customer2.toml")
    assert (c2.component("part 3").stiffness, c2.component("part 3").inertia) == (42429.35, 0.58)
    assert c2.component("generator").inertia == 35.0
    wd = fs.load_model(EXAMPLES / "without_dut.toml")
    assert [c.name for c in wd.components] == ["motor", "part 1", "part 2"]


def test_packaged_demo_models_are_the_examples():
    from importlib import resources

    for name in ("customer1.toml", "customer2.toml", "without_dut.toml"):
        packaged = resources.files("flexshaft.data").joinpath(name).read_text(encoding="utf-8")
        assert packaged == (EXAMPLES / name).read_text(encoding="utf-8"), name


def test_defaults():
    dt = _load(RIGID)
    assert dt.name == "m" and dt.inertia_model == "consistent" and dt.rayleigh is None


def test_rayleigh_from_two_targets():
    dt = _load(
        "[model]\nrayleigh = {frequencies_hz = [10.0, 100.0], damping_ratios = [0.01, 0.01]}\n" + RIGID
    )
    assert fs.rayleigh_ratio(dt.rayleigh.alpha, dt.rayleigh.beta, [10.0, 100.0]) == pytest.approx(
        [0.01, 0.01]
    )


BAD = [
    # (file text, pinned message)
    (
        '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = -58.1\n',
        "m.toml: [[chain]] #1 'motor': inertia = -58.1 kg·m²: out of range; "
        "valid: a finite number > 0 (kg·m²)",
    ),
    (
        '[[chain]]\nname = "p"\ntype = "shaft"\nstiffness = nan\ninertia = 1.0\n',
        "m.toml: [[chain]] #1 'p': stiffness = nan N·m/rad: not finite; valid: a finite number > 0 (N·m/rad)",
    ),
    (
        '[[chain]]\nname = "p"\ntype = "shaft"\nstiffness = inf\ninertia = 1.0\n',
        "m.toml: [[chain]] #1 'p': stiffness = inf N·m/rad: not finite; valid: a finite number > 0 (N·m/rad)",
    ),
    (
        '[[chain]]\nname = "p"\ntype = "shaft"\nstiffness = 1e5\ninertia = 1.0\nstifness = 3\n',
        "m.toml: [[chain]] #1 'p': stifness: unknown key; "
        "valid: one of name, type, stiffness, inertia, elements, damping_ratio, damping, material, segments, "
        "max_element_length, stations, reduce, damping_bands, rayleigh, fe, mesh_size, interface",
    ),
    # A number with a unit is read (tests/flexshaft/input/test_units.py); one of the wrong dimension is not.
    (
        '[[chain]]\nname = "p"\ntype = "shaft"\nstiffness = "307.9 kN·m/s"\ninertia = 1.0\n',
        "m.toml: [[chain]] #1 'p': stiffness = '307.9 kN·m/s': has the unit kilonewton * meter / second, "
        "which is not a N·m/rad; valid: a quantity in N·m/rad or a unit of the same dimension",
    ),
    (
        '[[chain]]\nname = "p"\ntype = "spring"\n',
        "m.toml: [[chain]] #1 'p': type = 'spring': unknown component type; "
        "valid: one of 'rigid', 'shaft', 'cad', 'coupling', 'gear'",
    ),
    (
        '[[chain]]\nname = "p"\n',
        "m.toml: [[chain]] #1 'p': type: missing key; "
        "valid: one of 'rigid', 'shaft', 'cad', 'coupling', 'gear'",
    ),
    (
        '[[chain]]\nname = "p"\ntype = "shaft"\ninertia = 1\n',
        "m.toml: [[chain]] #1 'p': stiffness: missing key for a shaft; "
        "valid: either stiffness (N·m/rad) and inertia (kg·m²), or material and segments (m)",
    ),
    (
        '[[chain]]\ntype = "rigid"\ninertia = 1\n',
        "m.toml: [[chain]] #1: name: missing key; valid: a unique name for the component",
    ),
    (
        RIGID + RIGID,
        "m.toml: [[chain]] #2 'motor': name = 'motor': duplicate component name; "
        "valid: a name not used by [[chain]] #1",
    ),
    (
        '[model]\nname = "x"\n',
        "m.toml: chain: no [[chain]] components; "
        "valid: at least one [[chain]] table (rigid, shaft, coupling or gear)",
    ),
    (
        '[modle]\nname = "x"\n' + RIGID,
        "m.toml: modle: unknown key; valid: one of model, materials, chain, bearings",
    ),
    (
        '[model]\ninertia_model = "lumpy"\n' + RIGID,
        "m.toml: [model]: inertia_model = 'lumpy': unknown option; valid: one of 'consistent', 'lumped'",
    ),
    (
        '[model]\ndofs = "6"\n' + RIGID,
        "m.toml: [model]: dofs = '6': unknown option; valid: one of 'torsion', 'full'",
    ),
    (
        '[[bearings]]\nstation = "motor"\nstiffness = -1\n' + RIGID,
        "m.toml: [[bearings]] #1: stiffness = -1.0 N/m: out of range; valid: a finite number > 0 (N/m)",
    ),
    (
        '[[bearings]]\nstation = "motor"\nstiffness = 1e9\n' + RIGID,
        "m.toml: bearings = 'motor': bearings act on lateral DOFs; "
        'valid: [model] dofs = "full" (a torsion model has no lateral DOFs)',
    ),
    (
        '[[chain]]\nname = "s"\ntype = "shaft"\nstiffness = 1e5\ninertia = 1\nelements = 2.5\n',
        "m.toml: [[chain]] #1 's': elements = 2.5: not an integer; valid: an integer >= 1",
    ),
    (
        '[[chain]]\nname = "s"\ntype = "shaft"\nstiffness = 1e5\ninertia = 1\ndamping_ratio = 1.5\n',
        "m.toml: [[chain]] #1 's': damping_ratio = 1.5: out of range; valid: a finite number >= 0 and < 1",
    ),
    (
        '[[chain]]\nname = "c"\ntype = "coupling"\nstiffness = 1e5\ndamping = -3\n',
        "m.toml: [[chain]] #1 'c': damping = -3.0 N·m·s/rad: out of range; "
        "valid: a finite number >= 0 (N·m·s/rad)",
    ),
    (
        '[[chain]]\nname = "c"\ntype = "coupling"\nstiffness = 1e5\ndamping_ratio = 0.01\n',
        "m.toml: [[chain]] #1 'c': damping_ratio: unknown key; valid: one of name, type, stiffness, inertia, "
        "damping, inertia_split, slip_torque, slip_kinetic_torque, slip_damping, backlash, stiffness_curve,"
        " torque_curve",
    ),
    (
        '[[chain]]\nname = "s"\ntype = "shaft"\nstiffness = 1e5\ninertia = 0\ndamping_ratio = 0.01\n',
        "m.toml: [[chain]] #1 's': inertia = 0.0 kg·m²: modal damping per shaft mode needs the shaft's own "
        "modes, so an inertia; valid: > 0 when damping_ratio > 0 (or use `damping` in N·m·s/rad)",
    ),
    (
        "[model]\nrayleigh = {alpha = -1}\n" + RIGID,
        "m.toml: [model]: rayleigh.alpha = -1.0 1/s: out of range; "
        "valid: a finite number >= 0 and <= 1e+06 (1/s)",
    ),
    (
        "[model]\nrayleigh = {gamma = 1}\n" + RIGID,
        "m.toml: [model]: rayleigh: unknown keys gamma; valid: {alpha = 1/s, beta = s} or "
        "{frequencies_hz = [f1, f2], damping_ratios = [z1, z2]}",
    ),
    (
        '[[chain]\nname = "p"\n',
        "m.toml: not valid TOML (Expected ']]' at the end of an array declaration (at line 1, column 8))",
    ),
    (
        '[[chain]]\nname = ""\ntype = "rigid"\ninertia = 1\n',
        "m.toml: [[chain]] #1 '': name = '': unusable name; valid: a non-empty string on one line",
    ),
]


@pytest.mark.parametrize("text, message", BAD, ids=[m.split(": ", 2)[-1][:40] for _, m in BAD])
def test_bad_input_gets_one_pinned_message(text, message):
    with pytest.raises(fs.ModelError) as info:
        fs.loads_model(text, source="m.toml")
    assert str(info.value) == message
    assert "\n" not in str(info.value)


def test_unreadable_files(tmp_path):
    with pytest.raises(fs.ModelError, match=r"nope.toml: file not found; valid: an existing model file$"):
        fs.load_model(tmp_path / "nope.toml")
    with pytest.raises(fs.ModelError, match=r": is a directory, not a model file; valid: a regular file"):
        fs.load_model(tmp_path)
    bad = tmp_path / "bin.toml"
    bad.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(fs.ModelError, match=r"bin.toml: not a UTF-8 text file \(byte 0\); valid: a model"):
        fs.load_model(bad)


def test_massless_free_end_is_refused_at_assembly():
    dt = _load(RIGID + '[[chain]]\nname = "s"\ntype = "shaft"\nstiffness = 1e5\ninertia = 0\n')
    with pytest.raises(fs.ModelError) as info:
        fs.assemble(dt)
    assert str(info.value) == (
        "'s': inertia = 0.0 kg·m²: station 's end' carries no inertia, so the inertia matrix is singular; "
        "valid: give the shaft or coupling there an inertia > 0, or put a rigid inertia on it"
    )


def test_python_api_validates_too():
    with pytest.raises(fs.ModelError, match=r"^'motor': inertia = -1.0 kg·m²: out of range"):
        fs.Rigid("motor", -1.0)
    with pytest.raises(fs.ModelError, match=r"^chain: the chain is empty"):
        fs.Drivetrain("x", [])
    with pytest.raises(fs.ModelError, match=r"^chain\[1\]: name = 'a': duplicate component name"):
        fs.Drivetrain("x", [fs.Rigid("a", 1.0), fs.Rigid("a", 2.0)])
    with pytest.raises(fs.ModelError, match=r"^E = -1.0 Pa: out of range"):
        fs.Material(E=-1.0, nu=0.3, rho=7850)


# --- flexible bodies: reduce and per-mode damping -------------------------------------------------

_FLEX_PART = """
[model]
name = "free part"
[[chain]]
name = "p"
type = "shaft"
material = "steel"
segments = [{length = 0.5, od = 0.1}, {length = 0.4, od = 0.08}]
max_element_length = 0.02
reduce = {modes = 6}
"""


def _free_body_ratios(extra: str):
    """The free part's own modes (Hz) and the damped ratios of the chain made of it alone."""
    dt = fs.loads_model(_FLEX_PART + extra, source="m.toml")
    res = fs.modal_analysis(dt)
    el = ~res.rigid
    return res.frequencies_hz[el], res.damping_ratios[el]


def test_flexible_body_carries_its_damping_ratio_on_every_elastic_mode():
    # The chain of one free body: its own modes, each with the set ratio (0.53 % when none is given).
    f, z = _free_body_ratios("damping_ratio = 0.02\n")
    assert f.size >= 8
    np.testing.assert_allclose(z, 0.02, rtol=1e-6)
    _, z = _free_body_ratios("")
    np.testing.assert_allclose(z, 0.0053, rtol=1e-6)


def test_flexible_body_damping_by_mode_list():
    f, z = _free_body_ratios("damping_ratio = [0.01, 0.02, 0.03]\n")
    # Elastic modes 1, 2, 3 as listed, every further mode the last value.
    np.testing.assert_allclose(z, [0.01, 0.02] + [0.03] * (f.size - 2), rtol=1e-6)


def test_flexible_body_damping_by_frequency_band():
    f, z = _free_body_ratios("damping_ratio = 0.004\ndamping_bands = [[0, 3000, 0.01], [3000, 6000, 0.02]]\n")
    want = np.where(f < 3000, 0.01, np.where(f < 6000, 0.02, 0.004))
    assert set(want) == {0.01, 0.02, 0.004}
    np.testing.assert_allclose(z, want, rtol=1e-6)


def test_flexible_body_rayleigh_damping():
    # Two target ratios at two frequencies give α, β; every mode then has ξ = α/(2ω) + βω/2.
    f, z = _free_body_ratios("rayleigh = {frequencies_hz = [1500, 6000], damping_ratios = [0.01, 0.01]}\n")
    alpha, beta = fs.rayleigh_coefficients(1500, 0.01, 6000, 0.01)
    w = 2 * np.pi * f
    np.testing.assert_allclose(z, alpha / (2 * w) + beta * w / 2, rtol=1e-6)
    assert z.min() < 0.01 < z.max()  # not one ratio: modes between the targets are damped less


def test_flexible_body_damping_errors_name_the_field():
    cases = {
        "damping_ratio = []\n": "damping_ratio",
        "damping_ratio = [0.01, 1.5]\n": "damping_ratio[1]",
        "damping_bands = [[0, 100]]\n": "damping_bands",
        "damping_bands = [[0, 100, 0.01], [50, 200, 0.02]]\n": "damping_bands[1]",
        "damping_ratio = [0.01]\ndamping_bands = [[0, 100, 0.01]]\n": "damping_bands",
        "rayleigh = {alpha = -1.0}\n": "rayleigh.alpha",
    }
    for extra, field in cases.items():
        with pytest.raises(fs.ModelError) as err:
            fs.loads_model(_FLEX_PART + extra, source="m.toml")
        assert err.value.field == field, (extra, str(err.value))
        assert str(err.value).startswith("m.toml: [[chain]] #1 'p': "), str(err.value)


def test_a_rigid_disc_in_a_full_model_file():
    # mass (kg, with a unit string) and diametral inertia reach the 6-DOF matrices of the disc's node.
    text = (
        '[model]\nname = "d"\ndofs = "full"\n'
        '[[chain]]\nname = "a"\ntype = "shaft"\nmaterial = "steel"\nsegments = [{length = 0.5, od = 0.05}]\n'
        '[[chain]]\nname = "disc"\ntype = "rigid"\ninertia = 0.12\n'
        'mass = "12000 g"\ndiametral_inertia = 0.06\n'
        '[[chain]]\nname = "b"\ntype = "shaft"\nmaterial = "steel"\nsegments = [{length = 0.5, od = 0.05}]\n'
    )
    d = fs.loads_model(text, source="d.toml")
    disc = d.component("disc")
    assert disc.mass == pytest.approx(12.0) and disc.diametral_inertia == 0.06
    bare = fs.loads_model(text.replace('mass = "12000 g"\ndiametral_inertia = 0.06\n', ""), source="d.toml")
    m, m0 = fs.assemble(d), fs.assemble(bare)
    dm = (m.M - m0.M).toarray()
    # the difference is the disc's own entries: 12 kg on three translations, 0.06 kg·m² on two tilts
    assert sorted(np.round(np.diag(dm)[np.abs(np.diag(dm)) > 0], 12)) == [0.06, 0.06, 12.0, 12.0, 12.0]
    for bad, message in [("mass = -1.0", "mass = -1.0 kg"), ('mass = "3 m"', "mass")]:
        with pytest.raises(fs.ModelError, match=message):
            fs.loads_model(text.replace('mass = "12000 g"', bad), source="d.toml")
