"""The three test-bench set-ups with parts from geometry are on one scale, and it is the one they say.

examples/customer1_cad.toml, without_dut_cad.toml and customer2_cad.toml share parts 1 and 2 (the
build123d PTSS parts, real size); motor, coupling and generator are the study's per-unit values
(docs/theory/08-test-bench.md) times the factors that map the per-unit part 1 onto the geometry's part 1:
s_k = k1 / 307933.18, s_j = j1 / 0.44. The references here are closed forms over the section
tables (springs in series, ρ·Σ Ip·L), the published per-unit values and the two-inertia formula,
never the files' own output.
"""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from tests.conftest import EXAMPLES

pytest.importorskip("build123d")

SETUPS = ("customer1_cad", "without_dut_cad", "customer2_cad")
# The material the files give parts 1 and 2 (shaft_steel) and part 4 (the built-in steel): the same.
E, NU, RHO = 210e9, 0.29, 7850.0
G = E / (2 * (1 + NU))
# Published per-unit values (docs/theory/08-test-bench.md): part 1, and per set-up motor, coupling, generator.
K1_PU, J1_PU = 307933.18, 0.44
PER_UNIT = {
    "customer1_cad": {"motor": 58.10, "part 3": (55120.04, 0.06), "generator": 6.67},
    "without_dut_cad": {"motor": 58.10},
    "customer2_cad": {"motor": 58.10, "part 3": (42429.35, 0.58), "generator": 35.0},
}
# The per-unit models of the same set-ups, for the frequency pattern.
PER_UNIT_FILES = {
    "customer1_cad": "customer1",
    "without_dut_cad": "without_dut",
    "customer2_cad": "customer2",
}
# The files write the scaled values to 8 significant digits: rounding <= 5e-8 relative.
WRITTEN = 1e-7


@pytest.fixture(scope="module")
def models():
    return {name: fs.load_model(EXAMPLES / f"{name}.toml") for name in SETUPS}


def _series_stiffness(table) -> float:
    """1 / Σ L/(G·J): the intervals of a section table as torsion springs in series, N·m/rad."""
    return 1.0 / float(np.sum(np.diff(table.x) / (G * table.j)))


def _axial_inertia(table) -> float:
    """ρ·Σ Ip·L, kg·m²."""
    return RHO * float(np.sum(table.ip * np.diff(table.x)))


def _factors(d) -> tuple[float, float]:
    table = d.component("part 1").sections
    return _series_stiffness(table) / K1_PU, _axial_inertia(table) / J1_PU


def test_the_set_ups_share_parts_1_and_2(models):
    ref = models["customer1_cad"]
    for name in SETUPS:
        for part in ("part 1", "part 2"):
            a, b = ref.component(part), models[name].component(part)
            assert (a.geometry, a.material) == (b.geometry, b.material)
            np.testing.assert_array_equal(a.sections.x, b.sections.x)
            np.testing.assert_array_equal(a.sections.j, b.sections.j)
    p4 = ref.component("part 4").sections, models["customer2_cad"].component("part 4").sections
    np.testing.assert_array_equal(p4[0].j, p4[1].j)
    assert [c.name for c in models["without_dut_cad"].components] == ["motor", "part 1", "part 2"]


@pytest.mark.parametrize("name", SETUPS)
def test_twist_test_stiffness_is_the_series_sum_of_the_section_table(models, name):
    d = models[name]
    twist = fs.twist_test(d, 86e3)  # the motor's nominal torque, N·m
    for p in twist.parts:
        comp = d.component(p.name)
        if comp.type == "coupling":
            ref = comp.stiffness
        else:
            ref = _series_stiffness(comp.sections)
            # and the inertia the chain carries is ρ·Σ Ip·L (a sum: round-off ~1e-15)
            assert comp.inertia == pytest.approx(_axial_inertia(comp.sections), rel=1e-12)
        # The clamped solve's round-off: condition ~ k_max/k_min over ~100 elements, ~1e-13; 1e-10 is loose.
        assert p.stiffness == pytest.approx(ref, rel=1e-10)


@pytest.mark.parametrize("name", SETUPS)
def test_per_unit_components_are_scaled_by_the_part_1_factors(models, name):
    d = models[name]
    s_k, s_j = _factors(d)
    # the factors the headers quote (written to 8 digits)
    assert s_k == pytest.approx(48.150657, rel=WRITTEN) and s_j == pytest.approx(43.267098, rel=WRITTEN)
    pu = PER_UNIT[name]
    assert d.component("motor").inertia == pytest.approx(pu["motor"] * s_j, rel=WRITTEN)
    if "part 3" in pu:
        k3, j3 = pu["part 3"]
        assert d.component("part 3").stiffness == pytest.approx(k3 * s_k, rel=WRITTEN)
        assert d.component("part 3").inertia == pytest.approx(j3 * s_j, rel=WRITTEN)
        assert d.component("generator").inertia == pytest.approx(pu["generator"] * s_j, rel=WRITTEN)
        # Physically plausible: the motor's nominal torque twists the coupling 1-3 degrees (the per-unit
        # stiffness among real-size parts twisted it 89 degrees).
        twist = np.degrees(86e3 / d.component("part 3").stiffness)
        assert 1.0 < twist < 3.0


@pytest.mark.parametrize("name", ["customer1_cad", "customer2_cad"])
def test_first_mode_is_the_two_inertia_mode_across_the_chain(models, name):
    # Motor and generator swing against each other across the whole chain: the two-inertia closed form
    # f = sqrt(k (Ja + Jb) / (Ja Jb)) / 2π with k the series stiffness of every part, Ja the motor with
    # parts 1, 2 and half the coupling, Jb the generator with part 4 and the other half. It neglects
    # the shafts' own deflection shape (their inertia is < 3 % of the rigid ones'): within 1 %.
    d = models[name]
    k = 1.0 / sum(1.0 / d.component(p).stiffness for p in ("part 1", "part 2", "part 3", "part 4"))
    j = {c.name: c.inertia for c in d.components}
    ja = j["motor"] + j["part 1"] + j["part 2"] + j["part 3"] / 2
    jb = j["generator"] + j["part 4"] + j["part 3"] / 2
    f_ref = np.sqrt(k * (ja + jb) / (ja * jb)) / (2 * np.pi)
    r = fs.modal_analysis(d, 4, damped=False)
    assert r.frequencies_hz[1] == pytest.approx(f_ref, rel=0.01)


@pytest.mark.parametrize("name", SETUPS)
def test_frequency_pattern_is_the_per_unit_models_on_the_new_scale(models, name):
    # Scaling every stiffness by s_k and inertia by s_j scales every frequency by sqrt(s_k/s_j); parts
    # 2 and 4 are the geometry's own (part 2: +24 % inertia, part 4: 3.3x stiffer than per-unit x s),
    # so the set-ups land near, not on, the scaled per-unit model: f1 within 10 %, f2/f1 within 20 %,
    # and the same component dominates mode 1 (the coupling with a DUT, part 1 without).
    d = models[name]
    s_k, s_j = _factors(d)
    pu = fs.modal_analysis(fs.load_model(EXAMPLES / f"{PER_UNIT_FILES[name]}.toml"), damped=False)
    r = fs.modal_analysis(d, 4, damped=False)
    f_pu, f = pu.frequencies_hz[1:3], r.frequencies_hz[1:3]
    assert f[0] == pytest.approx(f_pu[0] * np.sqrt(s_k / s_j), rel=0.10)
    assert f[1] / f[0] == pytest.approx(f_pu[1] / f_pu[0], rel=0.20)
    assert r.dominant_components()[1] == pu.dominant_components()[1]
