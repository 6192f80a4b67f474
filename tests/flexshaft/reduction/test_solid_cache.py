"""A solid part's results kept in the disk cache: read back exactly, never trusted when damaged, keyed
by everything they depend on, and bypassed by ``--no-cache``.

References: the freshly computed result itself (an entry must give back the very arrays stored, bit
for bit - a cache changes no number); the entry format's own promise (the SHA-256 of its arrays and
their shapes against the mesh: a damaged entry is found and rebuilt); the settings a result depends
on (another E, tie or mode count is another result, so never the old entry).
"""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from flexshaft.analysis.modal import part_modes
from flexshaft.analysis.twist import part_stiffness
from flexshaft.elements.materials import STEEL, Material
from flexshaft.parts.solidpart import solid_part_model
from flexshaft.reduction import solidbasis as reduction_module
from flexshaft.reduction.axisline import body_on_line
from tests.flexshaft.reduction import test_solid_body as tube

pytestmark = tube.pytestmark  # gmsh must load
mesh = tube.mesh  # the tube at 40 mm (a module fixture: meshed once in this module too)


def basis(mesh, material, *, dofs="full", interface="rigid", **how):
    """The solid part's Craig-Bampton basis (:func:`~flexshaft.reduction.solidbasis.solid_basis`, the
    building block the one front end and the assembly call), kept in ``cache``."""
    part = solid_part_model(mesh, material, dofs=dofs, interface=interface)
    return reduction_module.solid_basis(part, **how)


def stiffness(mesh, material, *, interface="rigid", **how):
    return part_stiffness(solid_part_model(mesh, material, interface=interface), **how)


def free_modes(mesh, material, *, count, **how):
    return part_modes(solid_part_model(mesh, material), count + 6, **how)  # elastic ones after 6 rigid


ARRAYS = ("K", "M", "eigenvalues", "full", "rigid_boundary", "rigid_mass_full")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    from flexshaft.input.solidcache import SOLID_RESULTS

    monkeypatch.setenv("FLEXSHAFT_CACHE_DIR", str(tmp_path / "cache"))
    return SOLID_RESULTS


def _entries(tmp_path):
    return sorted((tmp_path / "cache" / "solids").glob("*.npz"))


def _no_solving(monkeypatch):
    """Make any solid reduction's work an error: what comes back was read."""

    def refuse(*args, **kwargs):
        raise AssertionError("solved, not read from the cache")

    monkeypatch.setattr(reduction_module, "_reduction", refuse)


def _same_reduction(a, b):
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape
        np.testing.assert_array_equal(x, y)  # exactly: the cache stores the arrays, it computes nothing
    assert (a.dofs, a.n_residual, a.slab, a.static_residual) == (
        b.dofs,
        b.n_residual,
        b.slab,
        b.static_residual,
    )
    np.testing.assert_array_equal(a.shapes.U, b.shapes.U)
    np.testing.assert_array_equal(a.shapes.triangles, b.shapes.triangles)
    assert a.shapes.interface == b.shapes.interface


def test_a_kept_reduction_is_the_computed_one(mesh, cache, tmp_path, monkeypatch):
    fresh = basis(mesh, STEEL, dofs="torsion", modes=2, cache=cache)
    assert len(_entries(tmp_path)) == 1
    _no_solving(monkeypatch)
    kept = basis(mesh, STEEL, dofs="torsion", modes=2, cache=cache)
    _same_reduction(kept, fresh)
    assert kept.mesh is mesh  # the caller's mesh, whose digest keyed the entry
    line = np.linspace(0.0, mesh.length, 5)
    a, b = body_on_line(kept, line_x=line), body_on_line(fresh, line_x=line)
    for name in ("K", "M", "T"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def _damage_truncate(path):
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _damage_flip(path):
    # a byte inside the largest array's data (the end of the file is the zip's directory)
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as z:
        info = max(z.infolist(), key=lambda i: i.file_size)
    at = info.header_offset + 30 + len(info.filename) + len(info.extra) + info.file_size // 2
    data[at] ^= 0x10
    path.write_bytes(bytes(data))


def _rewrite(path, change, save=np.savez):
    """Rewrite the entry with ``change(arrays, doc)`` applied and its digest made to match again: a
    tampered entry that passes the format's own checks, which the reader's checks must catch."""
    from flexshaft.input.cache import arrays_digest

    with np.load(path) as data:
        doc = json.loads(str(data["meta"]))
        arrays = {k[2:]: np.array(data[k]) for k in data.files if k != "meta"}
    change(arrays, doc)
    doc["arrays"] = {k: [a.dtype.str, list(a.shape)] for k, a in arrays.items()}
    doc["sha256"] = arrays_digest(arrays)
    with path.open("wb") as fh:
        save(fh, meta=np.array(json.dumps(doc)), **{f"a_{k}": a for k, a in arrays.items()})


def _damage_shape(path):
    _rewrite(path, lambda arrays, doc: arrays.update(full=arrays["full"][:-3]))  # a node short


def _damage_nan(path):
    _rewrite(path, lambda arrays, doc: arrays["K"].__setitem__((0, 0), np.nan))


def _damage_count(path):
    _rewrite(path, lambda arrays, doc: doc["meta"].update(n_residual=99))


def _damage_compressed(path):
    # the same arrays, deflated: a member could then inflate to any size before a check - refused
    _rewrite(path, lambda arrays, doc: None, save=np.savez_compressed)


@pytest.mark.parametrize(
    "damage",
    [_damage_truncate, _damage_flip, _damage_shape, _damage_nan, _damage_count, _damage_compressed],
    ids=lambda f: f.__name__,
)
def test_a_damaged_entry_is_rebuilt(mesh, cache, tmp_path, damage):
    fresh = basis(mesh, STEEL, dofs="torsion", modes=1, cache=cache)
    (entry,) = _entries(tmp_path)
    damage(entry)
    assert cache.load(mesh, reduction_module.reduction_settings(STEEL, dofs="torsion", modes=1)) is None
    assert not entry.exists()  # removed, never trusted
    again = basis(mesh, STEEL, dofs="torsion", modes=1, cache=cache)
    _same_reduction(again, fresh)  # solved afresh (deterministic: the same direct solves)
    assert _entries(tmp_path) == [entry]  # and kept again


def test_the_key_follows_material_interface_and_modes(mesh, cache, tmp_path):
    base = {"dofs": "torsion", "modes": 1}
    basis(mesh, STEEL, cache=cache, **base)
    stiffer = Material(E=1.1 * STEEL.E, nu=STEEL.nu, rho=STEEL.rho, name="steel")
    for material, how in [
        (stiffer, base),  # another E: another result
        (STEEL, base | {"interface": "average"}),
        (STEEL, base | {"modes": 2}),
        (STEEL, base | {"residual": False}),
    ]:
        settings = reduction_module.reduction_settings(material, **how)
        assert cache.load(mesh, settings) is None  # never the old entry
    n_before = len(_entries(tmp_path))
    soft = basis(mesh, stiffer, cache=cache, **base)
    assert len(_entries(tmp_path)) == n_before + 1
    first = basis(mesh, STEEL, cache=cache, **base)
    # torsion stiffness ∝ G ∝ E: the new entry is the stiffer part's (to the solve's round-off)
    assert soft.K[1, 1] / first.K[1, 1] == pytest.approx(1.1, rel=1e-9)


def test_the_key_follows_the_mesh(mesh, cache):
    from flexshaft.elements.tetmesh import TetMesh

    basis(mesh, STEEL, dofs="torsion", modes=1, cache=cache)
    moved = TetMesh(mesh.name, mesh.nodes * 1.01, mesh.tets, mesh.faces, mesh.size, mesh.source)
    assert cache.load(moved, reduction_module.reduction_settings(STEEL, dofs="torsion", modes=1)) is None


def test_stiffness_and_modes_are_kept_exactly(mesh, cache, tmp_path, monkeypatch):
    from flexshaft.parts import solidpart

    fresh = stiffness(mesh, STEEL, cache=cache)
    modes = free_modes(mesh, STEEL, count=2, cache=cache)

    def refuse(*args, **kwargs):
        raise AssertionError("assembled and solved, not read from the cache")

    # a second solve would give the same bits too: what comes back now can only have been read
    with monkeypatch.context() as m:
        m.setattr(solidpart, "solid_matrices", refuse)
        kept = stiffness(mesh, STEEL, cache=cache)
        again = free_modes(mesh, STEEL, count=2, cache=cache)
    np.testing.assert_array_equal(kept.compliance, fresh.compliance)
    np.testing.assert_array_equal(kept.stiffness, fresh.stiffness)
    assert kept.to_dict() == fresh.to_dict()
    np.testing.assert_array_equal(again.frequencies_hz, modes.frequencies_hz)
    np.testing.assert_array_equal(again.shapes, modes.shapes)
    np.testing.assert_array_equal(again.rigid, modes.rigid)
    assert len(_entries(tmp_path)) == 2
    assert stiffness(mesh, STEEL, interface="average", cache=cache).torsion >= 0  # another entry
    assert len(_entries(tmp_path)) == 3


def test_a_model_file_part_is_solved_once_and_no_cache_bypasses(tmp_path, monkeypatch, capsys):
    from flexshaft.cli import main
    from flexshaft.model import shaftparts as assembly  # where the assembly keeps solid reductions

    monkeypatch.setenv("FLEXSHAFT_CACHE_DIR", str(tmp_path / "cache"))
    model = tmp_path / "tube.toml"
    model.write_text(tube.TUBE)
    solved = []
    work = reduction_module._reduction
    monkeypatch.setattr(reduction_module, "_reduction", lambda *a: solved.append(a[1]) or work(*a))

    def run(*argv):
        monkeypatch.setattr(assembly, "_SOLID_BODIES", {})  # a new process: nothing in memory
        assert main(["modes", str(model), "--json", *argv]) == 0
        return [m["frequency_hz"] for m in json.loads(capsys.readouterr().out)["modes"]]

    first = run()
    assert len(solved) == 1 and len(_entries(tmp_path)) == 1
    assert run() == first and len(solved) == 1  # read back: the same modes, nothing solved
    bypassed = run("--no-cache")
    assert len(solved) == 2  # solved again although an entry is there
    np.testing.assert_allclose(bypassed, first, rtol=1e-9, atol=1e-9)  # the same LU solves
    # the twist test of a later run reads the reduction with modes (its static part is the same)
    monkeypatch.setattr(assembly, "_SOLID_BODIES", {})
    assert main(["twist", str(model), "--json"]) == 0
    capsys.readouterr()
    assert len(solved) == 2


def test_no_cache_writes_nothing(tmp_path, monkeypatch, capsys):
    from flexshaft.cli import main
    from flexshaft.model import shaftparts as assembly  # where the assembly keeps solid reductions

    monkeypatch.setenv("FLEXSHAFT_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(assembly, "_SOLID_BODIES", {})
    model = tmp_path / "tube.toml"
    model.write_text(tube.TUBE)
    assert main(["twist", str(model), "--no-cache"]) == 0
    capsys.readouterr()
    assert not (tmp_path / "cache").exists()
