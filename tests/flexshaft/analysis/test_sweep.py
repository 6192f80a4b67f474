"""Sweeps: a grid and a hypercube of models, in-process, on local processes and on a local Dask cluster."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.parameters import parameter_value, with_parameters
from flexshaft.analysis.sweep import grid_points, lhs_points, parse_range, run_points, sweep
from flexshaft.cli import main
from tests.conftest import EXAMPLES

C1 = EXAMPLES / "customer1.toml"


def test_grid_points_are_the_models_one_by_one():
    # Every point of a grid equals the model built with those values and solved on its own (bit for bit:
    # the same dense eigen-solve of the same matrices, in this process - 8 points run in-process).
    d = fs.load_model(C1)
    name, stiff = parse_range("part 3.stiffness=40000:70000:4")
    np.testing.assert_allclose(stiff, [40000, 50000, 60000, 70000], rtol=1e-15)  # whole numbers: exact
    pts = grid_points({name: stiff, "generator.inertia": np.array([6.0, 7.0])})
    assert pts.shape == (8, 2)
    res = sweep(d, [name, "generator.inertia"], pts, modes=4)
    for row, f in zip(pts, res.frequencies_hz):
        r = fs.modal_analysis(with_parameters(d, {name: row[0], "generator.inertia": row[1]}))
        np.testing.assert_array_equal(f, r.frequencies_hz[1:5])
    assert (
        res.to_csv()
        .splitlines()[0]
        .startswith("part 3.stiffness [N·m/rad],generator.inertia [kg·m²],f1 [Hz]")
    )


def test_lhs_points_fill_their_bounds_once_per_stratum():
    pts = lhs_points({"a": (1.0, 2.0), "b": (10.0, 20.0)}, 50, seed=3)
    assert pts.shape == (50, 2)
    for k, (lo, hi) in enumerate([(1.0, 2.0), (10.0, 20.0)]):
        strata = np.floor((pts[:, k] - lo) / (hi - lo) * 50).astype(int)
        assert sorted(strata) == list(range(50))  # one point in each of the 50 strata


def test_a_refused_point_is_reported_not_fatal():
    # A massless shaft is a value its inertia can take, but not with modal damping on it: that point
    # is refused by the model, the others are solved.
    d = fs.load_model(C1)
    res = sweep(d, ["part 1.inertia"], np.array([[0.44], [0.0]]), modes=2)
    assert res.errors[0] == "" and "'part 1': part 1.inertia = 0.0" in res.errors[1]
    assert np.all(np.isnan(res.frequencies_hz[1])) and np.all(np.isfinite(res.frequencies_hz[0]))


@pytest.mark.parametrize(
    "name,value,valid",
    [
        ("part 3.stiffness", -1.0, "> 0 N·m/rad"),
        ("part 3.stiffness", 0.0, "> 0 N·m/rad"),
        ("motor.inertia", 0.0, "> 0 kg·m²"),  # a rigid body needs an inertia
        ("part 1.damping_ratio", 1.0, ">= 0 and < 1"),
        ("part 3.inertia", np.nan, ">= 0 kg·m²"),
    ],
)
def test_a_value_a_parameter_cannot_take_is_refused_before_any_solve(monkeypatch, name, value, valid):
    # Before: -1 on a stiffness was a refused row among the results; now the sweep refuses it at once.
    import flexshaft.analysis.sweep as sw

    def no_solve(*args):
        raise AssertionError("solved a point")

    monkeypatch.setattr(sw, "run_points", no_solve)
    d = fs.load_model(C1)
    value0 = parameter_value(d, name)
    with pytest.raises(fs.ModelError) as info:
        sweep(d, [name], np.array([[value0], [value]]))
    assert info.value.field == name and valid in str(info.value)


def test_sweep_modes_are_the_models_or_refused():
    d = fs.load_model(C1)  # 5 DOFs: mode 0 rigid, 4 elastic
    pts = np.array([[5e4]])
    assert sweep(d, ["part 3.stiffness"], pts).frequencies_hz.shape == (1, 4)  # default: up to 6
    assert sweep(d, ["part 3.stiffness"], pts, modes=4).frequencies_hz.shape == (1, 4)
    with pytest.raises(fs.ModelError, match="4 of them elastic") as info:
        sweep(d, ["part 3.stiffness"], pts, modes=5)
    assert info.value.field == "modes" and info.value.valid == "at most 4"


def test_parse_range_refuses_lo_above_hi():
    with pytest.raises(fs.ModelError, match="LO is above HI"):
        parse_range("part 3.stiffness=7e4:4e4:3")
    assert parse_range("part 3.stiffness=5e4:5e4:1")[1].tolist() == [5e4]  # LO = HI: one value


@pytest.mark.slow  # a local Dask cluster's start-up (~4 s) is most of it
def test_a_thousand_models_on_a_local_dask_cluster_equal_the_local_executor():
    # The check: 1 000 models on a local Dask cluster of 2 workers give the same numbers as local
    # processes (and as the in-process solve): each point is the same computation. Not to the bit: a
    # worker may run on another machine, with other BLAS kernels or thread counts, so to the solves'
    # round-off - f to eps·λ_max/λ₁/2 ≈ 3e-13 (λ_max/λ₁ ≈ 2300), ξ to eps·ω_max/ω₁ ≈ 1e-14 absolute (the
    # first-order matrix's norm is ω_max = 48 ω₁). Neighbouring points differ by 1e-4 in f and 1e-6 in
    # ξ, so a point run with another's values would still show.
    distributed = pytest.importorskip("distributed")
    d = fs.load_model(C1)
    pts = lhs_points({"part 3.stiffness": (4e4, 7e4), "part 1.stiffness": (2.8e5, 3.4e5)}, 1000, seed=1)
    names = ["part 3.stiffness", "part 1.stiffness"]
    local = sweep(d, names, pts, modes=4)  # local process pool (more than two chunks)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = sweep(d, names, pts, modes=4, executor=client.get_executor())
    np.testing.assert_allclose(remote.frequencies_hz, local.frequencies_hz, rtol=1e-11)
    np.testing.assert_allclose(remote.damping_ratios, local.damping_ratios, rtol=0, atol=1e-12)
    f, z, _ = run_points(d, names, pts[:50], 4)
    np.testing.assert_allclose(f, local.frequencies_hz[:50], rtol=1e-11)
    np.testing.assert_allclose(z, local.damping_ratios[:50], rtol=0, atol=1e-12)


def test_cli_sweep(tmp_path, capsys):
    out = tmp_path / "sweep.csv"
    args = ["sweep", str(C1), "--param", "part 3.stiffness=40000:70000:31", "-o", str(out)]
    assert main(args) == 0
    assert "31 models" in capsys.readouterr().out
    assert len(out.read_text().splitlines()) == 1 + 31  # the header, then one row per value
    assert main(args) == 2  # no overwrite without --force
    capsys.readouterr()
    assert main(["sweep", str(C1), "--param", "part 3.stiffness=4e4:7e4:5", "--lhs", "7", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["points"]) == 7 and all(4e4 <= p[0] <= 7e4 for p in doc["points"])
    for bad, field in [
        (["--param", "part 3.stiffness"], "--param"),
        (["--param", "part 3.stiffness=1:2:x"], "--param"),
        (["--param", "part 9.stiffness=1:2:3"], "--param"),
        (["--param", "part 3.stiffness=-1:2:3"], "--param"),
        (["--param", "part 3.stiffness=1:2:3", "--modes", "5"], "--modes"),
        (["--param", "part 3.stiffness=1:2:3", "--scheduler", "tcp://127.0.0.1:1"], "--scheduler"),
    ]:
        assert main(["sweep", str(C1), *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and field in err
