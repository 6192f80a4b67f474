"""The mesh-convergence estimate against the exact frequencies of a uniform free-free shaft."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.convergence import mesh_convergence
from flexshaft.cli import main
from tests.conftest import EXAMPLES


@pytest.mark.parametrize("inertia", ["consistent", "lumped"])
def test_estimate_equals_the_true_error_of_a_uniform_shaft(inertia):
    # A uniform free-free shaft of stiffness K and inertia I has f_k = (k/2)·√(K/I) exactly.
    # Richardson removes the h² term of the error, so estimate/true − 1 is of the order of the next
    # term relative to the first, O((kπ/n)²); both series' coefficients give less than 1/10 of it.
    K, I, n = 1e5, 2.0, 16
    d = fs.Drivetrain("rod", [fs.Shaft("s", stiffness=K, inertia=I, elements=n)], inertia_model=inertia)
    r = fs.modal_analysis(d, 6)
    mc = mesh_convergence(r)
    k = np.arange(1, 6)
    exact = 0.5 * k * np.sqrt(K / I)
    true = np.abs(r.frequencies_hz[1:] - exact) / exact
    assert np.all(np.abs(mc.error[1:] / true - 1) <= (k * np.pi / n) ** 2 / 10)
    assert mc.error[0] == 0.0  # the rigid-body mode: set, not estimated
    np.testing.assert_allclose(mc.extrapolated_hz[1:], exact, rtol=float(np.max(true)) / 10)


def test_one_element_shafts_are_flagged(capsys):
    # Customer 1 is the study's one-element matrix model: its modes 2-4 move by 5-50 % with a finer mesh.
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "--mesh-check"]) == 0
    out = capsys.readouterr().out
    assert "mesh: modes 2, 3, 4 are estimated more than 1 %" in out
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "--mesh-check", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["mesh_check"]["flagged_modes"] == [2, 3, 4]
    assert doc["modes"][1]["mesh_error"] < 1e-4  # mode 1 is the coupling's: shafts barely matter
    # A fine mesh is not flagged.
    d = fs.load_model(EXAMPLES / "customer1.toml")
    fine = fs.Drivetrain(
        d.name,
        [
            fs.Shaft(c.name, c.stiffness, c.inertia, elements=200) if c.type == "shaft" else c
            for c in d.components
        ],
    )
    assert mesh_convergence(fs.modal_analysis(fine, 5)).flagged.size == 0


def test_default_check_steps_aside_when_it_cannot_run(monkeypatch, capsys):
    # The default check must never cost the user the modes: if the doubled mesh cannot be built or
    # solved (a budget or guard), the table comes without it; asked for explicitly, it is an error.
    import flexshaft.analysis.convergence as conv

    def refuse(result, tolerance=0.01, **options):
        raise fs.ModelError("over the element budget", field="elements")

    monkeypatch.setattr(conv, "mesh_convergence", refuse)
    model = str(EXAMPLES / "customer1.toml")
    assert main(["modes", model]) == 0
    out = capsys.readouterr().out
    assert "rigid-body mode" in out and "mesh:" not in out
    assert main(["modes", model, "--mesh-check"]) == 2
    assert "element budget" in capsys.readouterr().err
    assert main(["modes", model, "--no-mesh-check"]) == 0
    assert "mesh:" not in capsys.readouterr().out
