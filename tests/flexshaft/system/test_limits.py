"""Ceilings (:mod:`flexshaft.system.limits`): each refuses above its value, naming the field, the value, the
ceiling and its reason; the environment sets another; the estimates of memory and dense work stop a
model, a response or a Campbell diagram before the work starts."""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.sections import table_from_segments
from flexshaft.system.limits import (
    CEILINGS,
    ceiling,
    check_ceiling,
    check_memory,
    dense_memory_bytes,
    dense_work,
    model_memory_bytes,
)


def test_every_ceiling_states_its_value_unit_and_reason():
    for name, c in CEILINGS.items():
        assert c.name == name and isinstance(c.value, int) and c.value >= 1, name
        assert c.what and c.unit and c.why, name
        # The reason sits in parentheses before "; valid:" in an error line: it holds neither.
        assert "(" not in c.why and ")" not in c.why and ";" not in c.why, name
        assert c.variable == "FLEXSHAFT_MAX_" + name.upper()


@pytest.mark.parametrize("name", list(CEILINGS))
def test_at_the_ceiling_passes_and_one_above_is_refused(name, monkeypatch):
    monkeypatch.delenv(CEILINGS[name].variable, raising=False)
    c = CEILINGS[name]
    assert check_ceiling(name, c.value) == c.value
    with pytest.raises(fs.ModelError) as err:
        check_ceiling(name, c.value + 1)
    text = str(err.value)
    assert text.startswith(f"{c.what} = {c.value + 1}: above the ceiling of {c.value} {c.unit} ({c.why})")
    assert text.endswith(f"valid: at most {c.value} {c.unit}; {c.variable}=N sets another ceiling")


def test_the_error_names_the_value_as_given_and_where_it_came_from():
    with pytest.raises(fs.ModelError) as err:
        check_ceiling(
            "elements",
            2e7,
            file="m.toml",
            component="'s'",
            field="max_element_length",
            value=1e-7,
            unit="m",
            detail="would cut the part into 2e+07 elements",
            hint="max_element_length >= 0.002 m",
        )
    e = err.value
    assert (e.file, e.component, e.field, e.value, e.unit) == (
        "m.toml",
        "'s'",
        "max_element_length",
        1e-7,
        "m",
    )
    assert str(e).startswith(
        "m.toml: 's': max_element_length = 1e-07 m: would cut the part into 2e+07 elements, above the "
        "ceiling of 1000000 elements per part"
    )
    assert "valid: at most 1000000 elements per part (max_element_length >= 0.002 m); " in str(e)


@pytest.mark.parametrize("amount", [float("nan"), float("inf")])
def test_no_number_is_within_a_ceiling(amount):
    with pytest.raises(fs.ModelError, match="above the ceiling"):
        check_ceiling("frf_points", amount)


def test_the_environment_sets_another_ceiling(monkeypatch):
    monkeypatch.setenv("FLEXSHAFT_MAX_FRF_POINTS", "200000")
    assert ceiling("frf_points") == 200_000
    assert check_ceiling("frf_points", 150_000) == 150_000
    monkeypatch.setenv("FLEXSHAFT_MAX_FRF_POINTS", "10")
    with pytest.raises(fs.ModelError, match="above the ceiling of 10 frequencies"):
        check_ceiling("frf_points", 11)
    for bad in ("abc", "0", "-5", "1.5"):
        monkeypatch.setenv("FLEXSHAFT_MAX_FRF_POINTS", bad)
        with pytest.raises(fs.ModelError, match=f"FLEXSHAFT_MAX_FRF_POINTS = '{bad}': not a whole number"):
            ceiling("frf_points")


def test_the_memory_estimate_is_on_the_safe_side_of_the_measured_peaks():
    # The benchmark of docs/theory/07-benchmarks.md: a uniform torsion shaft of 1e6 elements peaks at 574
    # MiB in its own process (interpreter and libraries included), 10 modes; measured here: 480 006 6-DOF
    # DOFs (80 000 Timoshenko elements, band half-width 11, 16 modes) at 1.45 GiB. The estimate must not
    # fall below either - and stay within 2x of them, or it would refuse models that fit.
    torsion = model_memory_bytes(1_000_001, 3 * 1_000_001, modes=10)
    assert 574 * 2**20 <= torsion <= 2 * 574 * 2**20
    full = model_memory_bytes(480_006, 23 * 480_006, modes=16)
    assert 1.37 * 2**30 <= full <= 2 * 1.45 * 2**30
    # dense: K and M as arrays and LAPACK's copies of both
    assert dense_memory_bytes(1000, 10) >= 4 * 1000 * 1000 * 8
    assert dense_work(50, 1000) == 50 and dense_work(1, 2000) == 8  # the cube of the order


def test_check_memory_gives_the_estimate_in_mb():
    with pytest.raises(
        fs.ModelError, match=r"a thing would take about 3072 MB, above the ceiling of 2048 MB"
    ):
        check_memory(3 * 2**30, field="count", value=5, detail="a thing")
    check_memory(2**30, field="count", value=5, detail="a thing")


def _three_shafts(elements: int) -> fs.Drivetrain:
    shafts = [fs.Shaft(f"s{k}", stiffness=3e5, inertia=0.44, elements=elements) for k in range(3)]
    return fs.Drivetrain("three", (fs.Rigid("motor", 58.1), *shafts))


def test_a_model_beyond_the_memory_ceiling_is_refused_before_it_is_built():
    # 3 million torsion DOFs: about 2.9 GB by the estimate, refused at once naming the largest shaft.
    with pytest.raises(fs.ModelError) as err:
        fs.assemble(_three_shafts(1_000_000))
    assert err.value.component == "'s0'" and err.value.field == "elements" and "MB" in str(err.value)
    assert fs.assemble(_three_shafts(1_000)).n_dof == 3001


def test_a_dense_solve_beyond_the_memory_ceiling_is_refused_before_it_starts():
    model = fs.assemble(
        fs.Drivetrain(
            "dense", (fs.Rigid("motor", 58.1), fs.Shaft("s", stiffness=3e5, inertia=0.44, elements=9999))
        )
    )
    with pytest.raises(fs.ModelError, match="count = 4000: a dense eigen-solve of all 10000 DOFs would take"):
        fs.modal_analysis(model, 4000)


def _coupled(m: int) -> fs.StateSpace:
    """A modal state space of m modes whose damping couples them (every entry of Dm set)."""
    w2 = np.diag((2 * np.pi * np.arange(1.0, m + 1)) ** 2)
    dm = np.full((m, m), 0.01) + np.eye(m)
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-w2, -dm]])
    B = np.vstack([np.zeros((m, 1)), np.ones((m, 1))])
    C = np.hstack([np.ones((1, m)), np.zeros((1, m))])
    states = tuple(f"q{k}" for k in range(2 * m))
    return fs.StateSpace(
        A,
        B,
        C,
        np.zeros((1, 1)),
        ("in",),
        ("out",),
        ("N·m",),
        ("rad",),
        states,
        np.arange(m),
        np.arange(1.0, m + 1),
    )


def test_a_response_of_coupled_modes_beyond_the_work_ceiling_is_refused_before_it_starts():
    # 10 000 frequencies of 200 coupled modes: 10 000 dense solves of order 200, the work of 80 of order 1000.
    with pytest.raises(
        fs.ModelError, match=r"frequencies = 10000 frequencies: each a dense solve of the 200"
    ):
        fs.frequency_response(_coupled(200), np.linspace(0.5, 100.0, 10_000))
    assert fs.frequency_response(_coupled(200), np.linspace(0.5, 100.0, 100)).H.shape == (100, 1, 1)


def test_a_campbell_diagram_beyond_the_work_ceiling_is_refused_before_the_tracking(monkeypatch):
    shaft = fs.Shaft.from_sections(
        "s", table_from_segments([{"length": 1.0, "od": 0.1}], name="s"), fs.STEEL, max_element_length=0.05
    )
    line = fs.Drivetrain(
        "spinning", (fs.Rigid("motor", 1.0), shaft), dofs="full", bearings=(("motor", 1e8), ("s end", 1e8))
    )
    model = fs.assemble(line)
    result = fs.modal_analysis(model, model.n_dof)  # 20 elements: 126 DOFs, all their modes
    # 181 speeds and a few crossings, eigen-solves of order 252: the work of about 3 solves of order 1000
    assert fs.campbell(result, (0.0, 3000.0)).speed_dependent
    monkeypatch.setenv("FLEXSHAFT_MAX_DENSE_WORK", "1")
    with pytest.raises(fs.ModelError, match=r"speed \(high\) = 3000.0 rpm: about .* crossings to find"):
        fs.campbell(result, (0.0, 3000.0))


def test_sweep_sizes_are_counted_before_the_points_are_made():
    from flexshaft.analysis.sweep import grid_points, lhs_points, parse_range

    with pytest.raises(fs.ModelError, match="1000001 values, above the ceiling of 100000 values"):
        parse_range("a=1:2:1000001")
    with pytest.raises(fs.ModelError, match="100001 values"):
        parse_range("a=" + ",".join(["1"] * 100_001))
    with pytest.raises(fs.ModelError, match="a grid of 1002001 points"):
        grid_points({"a": np.zeros(1001), "b": np.zeros(1001)})
    with pytest.raises(fs.ModelError, match="samples = 1000001: above the ceiling of 1000000 points"):
        lhs_points({"a": (0.0, 1.0)}, 1_000_001)


def test_a_model_file_chain_and_segments_are_counted_before_they_are_read():
    chain = "".join(f'[[chain]]\nname = "r{k}"\ntype = "rigid"\ninertia = 1\n' for k in range(501))
    with pytest.raises(fs.ModelError, match="m.toml: chain = 501: above the ceiling of 500 components"):
        fs.loads_model(chain, source="m.toml")
    segments = ", ".join(["{length = 0.001, od = 0.1}"] * 1001)
    shaft = f'[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\nsegments = [{segments}]\n'
    with pytest.raises(fs.ModelError, match=r"'s': segments = 1001: above the ceiling of 1000 segments"):
        fs.loads_model(shaft, source="m.toml")
