"""Craig–Bampton reduction of part models: static exactness, convergence, rigid mass, damping per mode."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as la

import flexshaft as fs
from flexshaft.partmodel import part_model
from flexshaft.partmodes import part_modes
from flexshaft.reduction import cb_check, craig_bampton
from flexshaft.sections import table_from_segments

TABLE = table_from_segments([{"length": 1.0, "od": 0.2, "id": 0.1}, {"length": 0.8, "od": 0.12}], name="p")


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_static_exactness_and_rigid_mass(dofs):
    # Craig & Bampton (1968): the constraint modes make the reduced interface stiffness the exact static
    # condensation, and the rigid-body mass is carried exactly by the constraint modes.
    pm = part_model(TABLE, fs.STEEL, dofs=dofs, max_element_length=0.02)
    fb = craig_bampton(pm, modes=6)
    check = cb_check(fb, pm)
    assert check.static_error < 1e-10
    assert check.rigid_mass_error < 1e-10
    assert check.symmetry == 0.0
    assert fb.n_boundary == (2 if dofs == "torsion" else 12) and fb.n_modes == 6


def test_free_frequencies_converge_as_modes_are_added():
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.02)
    full = part_modes(pm, 20).frequencies_hz
    errs = []
    for n in (4, 8, 16, 32):
        fb = craig_bampton(pm, modes=n)
        errs.append(np.max(np.abs(fb.free_hz[6:12] / full[6:12] - 1)))
    assert np.all(np.diff(errs) < 0)  # monotone: CB is a Rayleigh–Ritz method on nested subspaces
    assert errs[-1] < 1e-3
    # Ritz values bound the full model's from above.
    fb = craig_bampton(pm, modes=8)
    assert np.all(fb.free_hz[6:12] >= full[6:12] * (1 - 1e-12))


def test_cutoff_keeps_every_fixed_interface_mode_below_it():
    pm = part_model(TABLE, fs.STEEL, dofs="torsion", max_element_length=0.01)
    fb = craig_bampton(pm, cutoff_hz=5000.0)
    all_fixed = craig_bampton(pm, modes=40).fixed_interface_hz
    assert np.array_equal(fb.fixed_interface_hz, all_fixed[all_fixed < 5000.0]) or np.allclose(
        fb.fixed_interface_hz, all_fixed[all_fixed < 5000.0], rtol=1e-10
    )


def test_damped_eigenvalues_carry_the_set_ratio():
    # First-order form of the reduced part: every elastic mode has λ = −ξω ± iω√(1−ξ²).
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.05)
    fb = craig_bampton(pm, modes=10, damping_ratio=0.0053)
    n = fb.K.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-fb.K, -fb.C]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), fb.M]])
    lam = la.eigvals(A, B)
    # The 6 rigid-body modes are zero eigenvalues (round-off sized); the elastic ones come in pairs.
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(np.abs(lam))][-(n - 6) :]
    zeta = -lam.real / np.abs(lam)
    np.testing.assert_allclose(zeta, 0.0053, rtol=1e-6)


def test_bad_reduction_input():
    pm = part_model(TABLE, fs.STEEL, dofs="torsion", max_element_length=0.05)
    with pytest.raises(fs.ModelError, match="give either modes or cutoff_hz"):
        craig_bampton(pm)
    with pytest.raises(fs.ModelError, match="damping_ratio = 1.5: must be in"):
        craig_bampton(pm, modes=3, damping_ratio=1.5)


@pytest.mark.parametrize("suffix", [".npz", ".json", ".mat", ".op4"])
def test_export_round_trip_and_unit_check(tmp_path, suffix):
    import json

    from flexshaft.exports import read_flexible_body, write_flexible_body

    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.1)
    fb = craig_bampton(pm, modes=4)
    path = tmp_path / f"p{suffix}"
    write_flexible_body(fb, path, material=fs.STEEL)
    with pytest.raises(fs.ModelError, match="file exists"):
        write_flexible_body(fb, path)
    back, meta = read_flexible_body(path)
    for name in (
        "K",
        "M",
        "C",
        "T",
        "free_hz",
        "fixed_interface_hz",
        "damping_ratios",
        "boundary_x",
        "boundary_nodes",
        "free_modes",
    ):
        np.testing.assert_array_equal(getattr(back, name), getattr(fb, name))  # bit-identical
    assert back.name == "p" and back.dofs == "full" and meta["material"]["name"] == "steel"
    assert meta["dof_order"][:7] == [
        "node 0 ux",
        "node 0 uy",
        "node 0 uz",
        "node 0 θx",
        "node 0 θy",
        "node 0 θz",
        f"node {pm.n_nodes - 1} ux",
    ]
    # A file in other units is refused, naming both.
    if suffix == ".json":
        doc = json.loads(path.read_text())
        doc["units"]["length"] = "mm"
        path.write_text(json.dumps(doc))
        with pytest.raises(fs.ModelError, match="the file's length unit is 'mm', flexshaft's is 'm'"):
            read_flexible_body(path)


def test_cli_reduce(tmp_path, capsys):
    from flexshaft.cli import main
    from flexshaft.exports import read_flexible_body

    model = tmp_path / "m.toml"
    model.write_text(
        '[model]\ndofs = "full"\n\n[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 5.0\n\n'
        '[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\ndamping_ratio = 0.01\n'
        "segments = [{length = 1.0, od = 0.1}]\nmax_element_length = 0.05\nstations = {journal = 0.4}\n"
    )
    out = tmp_path / "s.npz"
    assert main(["reduce", str(model), "--part", "s", "--modes", "5", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "18 boundary DOFs at x = 0, 0.4, 1 m + 5 fixed-interface modes" in text
    body, meta = read_flexible_body(out)
    assert body.n_boundary == 18 and meta["material"]["name"] == "steel"
    assert np.all(body.damping_ratios[~(body.free_hz == 0)] == 0.01)  # the part's damping_ratio
    assert main(["reduce", str(model), "--part", "s", "--modes", "5", "-o", str(out)]) == 2
    assert "file exists" in capsys.readouterr().err
    assert main(["reduce", str(model), "--part", "motor", "--modes", "5", "-o", str(out), "--force"]) == 2
    assert "--part = 'motor': has no geometry to reduce" in capsys.readouterr().err


def test_pyyeti_reads_our_op4_exactly(tmp_path):
    # Optional peer check: runs where benchmarks/setup_peers.sh installed pyyeti (its own virtualenv).
    import subprocess
    from pathlib import Path

    from flexshaft.exports import write_flexible_body

    peer = Path(__file__).resolve().parents[1] / "benchmarks" / ".venv-peers" / "bin" / "python"
    if (
        not peer.exists()
        or subprocess.run([str(peer), "-c", "import pyyeti"], capture_output=True).returncode
    ):
        pytest.skip("pyyeti not installed in benchmarks/.venv-peers")
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.1)
    fb = craig_bampton(pm, modes=4)
    write_flexible_body(fb, tmp_path / "p.op4")
    np.save(tmp_path / "K.npy", fb.K)
    np.save(tmp_path / "T.npy", fb.T)
    code = (
        "import numpy as np, sys; from pyyeti.nastran import op4; d = op4.read(sys.argv[1]); "
        "print(np.array_equal(d['kaa'], np.load(sys.argv[2])), "
        "np.array_equal(d['trec'], np.load(sys.argv[3])))"
    )
    out = subprocess.run(
        [str(peer), "-c", code, str(tmp_path / "p.op4"), str(tmp_path / "K.npy"), str(tmp_path / "T.npy")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.stdout.split()[-2:] == ["True", "True"], out.stderr
