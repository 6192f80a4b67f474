"""The disk cache of section tables: a CAD part is sliced once; a stale or damaged entry never counts."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("build123d")

import flexshaft as fs  # noqa: E402
from flexshaft.input import cad  # noqa: E402

PARTS = """
from geometry.parts import stepped_shaft


def tube(*, length=1.0, od=0.2, id=0.08):
    return stepped_shaft([{"length": length, "od": od, "id": id}])
"""
MODEL = '[[chain]]\nname = "m"\ntype = "rigid"\ninertia = 5.0\n\n[[chain]]\nname = "t"\ntype = "cad"\n'
TUBE = MODEL + 'geometry = "my_parts:tube"\nmaterial = "steel"\nparams = {length = 0.9}\n'
HUB = MODEL + 'geometry = "geometry.parts.testbench:coupling_hub"\nmaterial = "steel"\n'


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("FLEXSHAFT_CACHE_DIR", str(folder))
    cad.clear_cache()  # the in-process cache would hide the disk one
    yield folder
    cad.clear_cache()


def _entries(folder):
    return sorted((folder / "sections").glob("*.npz")) if (folder / "sections").is_dir() else []


def _load(tmp_path, text, **kw):
    (tmp_path / "my_parts.py").write_text(PARTS)
    model = tmp_path / "m.toml"
    model.write_text(text)
    cad.clear_cache()
    return fs.load_model(model, allow_code=True, **kw)


def test_a_warm_table_is_the_cold_one(tmp_path, cache):
    cold = _load(tmp_path, TUBE).component("t").sections
    assert len(_entries(cache)) == 1
    warm = _load(tmp_path, TUBE).component("t").sections
    for k in ("x", "area", "ip", "iy", "iz", "j", "shear_area_y", "shear_area_z"):
        np.testing.assert_array_equal(getattr(warm, k), getattr(cold, k))
    assert warm.method == cold.method and warm.name == cold.name
    assert warm.meta["mass_check"] == cold.meta["mass_check"]


def test_a_warm_run_imports_no_cad_kernel(tmp_path, cache):
    # The point of the cache: the 3-6 s of importing build123d and slicing are gone on a warm run.
    _load(tmp_path, HUB)
    code = (
        "import sys, flexshaft as fs\n"
        f"fs.load_model({str(tmp_path / 'm.toml')!r})\n"
        "print('build123d' in sys.modules)\n"
    )
    env = {**os.environ, "FLEXSHAFT_CACHE_DIR": str(cache)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    assert out.stdout.strip() == "False"


def test_what_the_table_depends_on_is_in_the_key(tmp_path, cache):
    a = _load(tmp_path, TUBE).component("t").sections
    b = _load(tmp_path, TUBE.replace("length = 0.9", "length = 0.7")).component("t").sections
    assert b.length == pytest.approx(0.7) and a.length == pytest.approx(0.9)
    # The part code changed: the same name and parameters are sliced anew, not served stale.
    (tmp_path / "my_parts.py").write_text(PARTS.replace("od=0.2", "od=0.3"))
    model = tmp_path / "m.toml"
    cad.clear_cache()
    c = fs.load_model(model, allow_code=True).component("t").sections
    # the new code ran: the edit kept the file's size within the same second, which a cached .pyc
    # would not have noticed - the part module is compiled from its source each time
    assert c.area[0] > b.area[0]
    assert len(_entries(cache)) == 3
    assert not (tmp_path / "__pycache__").exists()  # nothing written beside the user's model


def test_a_damaged_entry_is_rebuilt_not_trusted(tmp_path, cache):
    cold = _load(tmp_path, TUBE).component("t").sections
    (entry,) = _entries(cache)
    entry.write_bytes(entry.read_bytes()[:200])  # truncated
    again = _load(tmp_path, TUBE).component("t").sections
    np.testing.assert_array_equal(again.j, cold.j)
    assert entry.stat().st_size > 200  # rewritten whole


def test_an_edited_table_entry_is_found_by_its_digest(tmp_path, cache):
    # A whole, well-formed entry whose numbers were changed (a flipped bit, an edit) is no longer the
    # one stored: the SHA-256 of its arrays says so, and the part is sliced again.
    cold = _load(tmp_path, TUBE).component("t").sections
    (entry,) = _entries(cache)
    with np.load(entry) as data:
        members = {k: data[k] for k in data.files}
    members["a_j"] = members["a_j"] * 2.0
    with open(entry, "wb") as fh:
        np.savez(fh, **members)
    again = _load(tmp_path, TUBE).component("t").sections
    np.testing.assert_array_equal(again.j, cold.j)


def test_no_cache_bypasses_it_and_trust_is_still_required(tmp_path, cache):
    _load(tmp_path, TUBE, use_cache=False)
    assert _entries(cache) == []
    _load(tmp_path, TUBE)
    cad.clear_cache()
    # A cached entry of user code never stands in for the trust the code needs.
    with pytest.raises(fs.ModelError, match="runs only when you trust it"):
        fs.load_model(tmp_path / "m.toml")


def test_the_parts_own_surface_is_kept_with_its_table(tmp_path, cache):
    # The part's tessellated surface (for its pictures) comes back from the cache as it went in, in
    # the table's frame: x from the table's first station to its last, radii within the part's.
    cold = _load(tmp_path, TUBE).component("t").sections
    warm = _load(tmp_path, TUBE).component("t").sections
    (pc, tc), (pw, tw) = cold.meta["surface"], warm.meta["surface"]
    np.testing.assert_array_equal(pw, pc)
    np.testing.assert_array_equal(tw, tc)
    # Both from the part's B-rep: its start face at x = 0 exactly; its end within the slicer's station
    # merge tolerance (1e-7 of the part's extent, 1e-7 m here).
    assert pc[:, 0].min() == pytest.approx(cold.x[0], abs=1e-9)
    assert pc[:, 0].max() == pytest.approx(cold.x[-1], abs=1e-6)
    r = np.hypot(pc[:, 1], pc[:, 2])
    assert r.max() == pytest.approx(0.1, rel=1e-6) and r.min() >= 0.04 - 1e-6  # od 0.2, id 0.08
