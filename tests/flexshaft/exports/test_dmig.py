"""Nastran DMIG punch of a flexible body: the deck's form, round trip, units, overwrite, and a peer reader."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.linalg as la

import flexshaft as fs
from flexshaft.exports.bodies import UNITS, read_flexible_body, write_flexible_body
from flexshaft.exports.dmig import HEADER_PREFIX, _read_real, dmig_text, parse_dmig, real16
from flexshaft.parts.model import part_model
from flexshaft.reduction import FlexibleBody, craig_bampton
from flexshaft.sections import table_from_segments

TABLE = table_from_segments([{"length": 1.0, "od": 0.2, "id": 0.1}, {"length": 0.8, "od": 0.12}], name="p")
# What a 15-character D field holds (module notes): >= 9 significant digits for any 1e-99 < |v| < 1e99,
# >= 11 for 1 <= |v| < 1e12 - a half unit in the last digit, relative.
REL_ANY = 0.5e-8
REL_MID = 0.5e-10
EXACT = ("T", "free_modes", "free_hz", "fixed_interface_hz", "damping_ratios", "boundary_x", "boundary_nodes")


def _body(dofs: str, *, damping_ratio=0.0053, nodes=(), residual=False):
    # Textbook Craig–Bampton by default, so the deck's SPOINT count is the 4 modes.
    pm = part_model(TABLE, fs.STEEL, dofs=dofs, max_element_length=0.1)
    return craig_bampton(pm, modes=4, damping_ratio=damping_ratio, nodes=nodes, residual=residual)


def _assert_printed_precision(back: np.ndarray, ref: np.ndarray) -> None:
    assert np.array_equal(back, back.T)  # one triangle written, mirrored on reading
    assert np.all(np.abs(back - ref) <= REL_ANY * np.abs(ref))  # zeros stay zero
    assert np.max(np.abs(back - ref)) <= REL_MID * np.max(np.abs(ref))


# --- the number field -------------------------------------------------------------------------


def test_real16_fits_the_field_and_keeps_the_digits_it_claims():
    rng = np.random.default_rng(1)
    values = rng.uniform(1, 10, 4000) * 10.0 ** rng.integers(-98, 98, 4000) * rng.choice([-1, 1], 4000)
    for v in values:
        s = real16(float(v))
        assert len(s) == 16 and s[0] == " " and "D" in s  # TIN = 2 needs a D exponent (QRG DMIG remark 8)
        back = float(s.replace("D", "E"))
        assert abs(back - v) <= REL_ANY * abs(v)
        if 1 <= abs(v) < 1e12:
            assert abs(back - v) <= REL_MID * abs(v)
    # Short decimals are written as they are, so they come back bit-identical.
    for v in (1.0, 0.4, 1.8, -0.29, 7850.0, 2.1e11, 1e-5):
        assert float(real16(v).replace("D", "E")) == v
    assert real16(1.8, "E").strip() == "1.8" and real16(0.0).strip() == "0."
    # The point moves to save exponent characters: 12 digits where "d.ddd" would leave 10.
    assert real16(1.23456789012345e12).strip() == "1234.56789012D9"
    with pytest.raises(fs.ModelError, match="value = nan: is not a finite number"):
        real16(float("nan"))
    # The reader also takes Nastran's other real forms, as a deck saved by another tool may have them.
    assert [_read_real(s) for s in ("1.5-3", "-2.+4", "1.5E-3", " .7D1 ", "7.")] == [
        1.5e-3,
        -2e4,
        1.5e-3,
        7.0,
        7.0,
    ]


# --- the deck ---------------------------------------------------------------------------------


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_punch_is_a_plain_nastran_include(dofs):
    fb = _body(dofs, nodes=(7,))
    text = dmig_text(fb, material=fs.STEEL)
    lines = text.splitlines()
    assert text.isascii() and max(map(len, lines)) <= 80
    cards = [ln for ln in lines if not ln.startswith("$")]
    grids = [ln for ln in cards if ln.startswith("GRID*")]
    assert [int(ln[8:24]) for ln in grids] == [1001, 1002, 1003]
    # On the basic X axis at the boundary nodes' x (m).
    assert [float(ln[40:56]) for ln in grids] == list(fb.boundary_x)
    assert "SPOINT      9001    THRU    9004" in cards
    # Symmetric (IFO 6), double input (TIN 2), precision by the machine (TOUT 0).
    for name in ("KAAX", "MAAX", "BAAX"):
        assert f"DMIG    {name:<8s}       0       6       2       0" in cards
    comps = {int(ln[40:56]) for ln in cards if ln.startswith("DMIG*")} | {
        int(ln[24:40]) for ln in cards if ln.startswith("*      ") and ln[40:56].strip()
    }
    assert comps == ({0, 4} if dofs == "torsion" else {0, 1, 2, 3, 4, 5, 6})  # SPOINTs are component 0
    assert "$ Case Control: K2GG = KAAX, M2GG = MAAX, B2GG = BAAX" in lines


def test_each_term_once_lower_triangle():
    # QRG DMIG remark 4: an element given both above and below the diagonal is a fatal error.
    fb = _body("full")
    text = dmig_text(fb)
    order = {(g, c): k for k, (g, c) in enumerate([(g, c) for g in (1001, 1002) for c in range(1, 7)])}
    order |= {(9000 + m, 0): 12 + m - 1 for m in range(1, 5)}
    col, seen = None, set()
    for ln in text.splitlines():
        if ln.startswith("DMIG*   KAAX"):
            col = order[(int(ln[24:40]), int(ln[40:56]))]
        elif ln.startswith("*") and col is not None and ln[40:56].strip():
            row = order[(int(ln[8:24]), int(ln[24:40]))]
            assert row >= col and (row, col) not in seen
            seen.add((row, col))
        elif ln.startswith("DMIG    MAAX"):
            break
    assert seen == {(i, j) for i, j in zip(*np.nonzero(np.tril(fb.K)))}


def test_no_damping_matrix_when_undamped_and_options():
    fb = _body("torsion", damping_ratio=0.0)
    text = dmig_text(fb, grid_offset=100, spoint_offset=200, k_name="kshaft", m_name="MSHAFT")
    assert (
        "BAAX" not in text
        and "B2GG" not in text
        and "DMIG    KSHAFT" in text
        and "GRID*                101" in text
    )
    back = parse_dmig(text)
    assert np.array_equal(back["C"], np.zeros_like(fb.C)) and back["metadata"]["dmig"]["spoints"][0] == 201
    _assert_printed_precision(back["K"], fb.K)
    with pytest.raises(fs.ModelError, match="spoint_offset = 1000: GRID ids 1001-1002 overlap SPOINT ids"):
        dmig_text(fb, spoint_offset=1000)
    with pytest.raises(
        fs.ModelError, match="k_name = 'K-SHAFT': is not a Nastran matrix name; valid: 1 to 8"
    ):
        dmig_text(fb, k_name="K-SHAFT")
    with pytest.raises(fs.ModelError, match="grid_offset = -1: must be an integer >= 0"):
        dmig_text(fb, grid_offset=-1)
    with pytest.raises(fs.ModelError, match="must differ"):
        dmig_text(fb, m_name="KAAX")


# --- round trip -------------------------------------------------------------------------------


@pytest.mark.parametrize("residual", [False, True])
@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_round_trip(tmp_path, dofs, residual):
    fb = _body(dofs, residual=residual)
    assert fb.n_residual == (fb.n_boundary if residual else 0)
    path = write_flexible_body(fb, tmp_path / "p.pch", material=fs.STEEL)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["p.pch", "p.pch.json"]
    _read = read_flexible_body(path)
    back, meta = _read.body, _read.metadata
    for name in ("K", "M", "C"):
        _assert_printed_precision(getattr(back, name), getattr(fb, name))
    for name in EXACT:  # from the sidecar and the header: exact
        np.testing.assert_array_equal(getattr(back, name), getattr(fb, name))
    assert back.n_residual == fb.n_residual
    assert (
        back.name == "p"
        and back.dofs == dofs
        and meta["material"]
        == {
            "name": "steel",
            "E": fs.STEEL.E,
            "nu": fs.STEEL.nu,
            "rho": fs.STEEL.rho,
        }
    )
    # The deck alone carries the same metadata, exactly (JSON floats round-trip).
    deck = parse_dmig(path.read_text())
    assert deck["metadata"]["free_hz"] == fb.free_hz.tolist()
    assert deck["metadata"]["dof_order"] == meta["dof_order"] and deck["metadata"]["units"] == UNITS
    np.testing.assert_array_equal(deck["K"], back.K)
    # What the numbers are for: the free-free frequencies of the read-back part, to the printed precision.
    # The print rounds each entry by a relative ρ <= REL_ANY (REL_MID for 1 <= |v| < 1e12: the inertias
    # below 1 keep only 9 digits), which moves each λ = ω² of a mass-normalised mode φ by at most
    # |φ|ᵀ(ρ|K| + λρ|M|)|φ| to first order - twice that inside a degenerate bending pair. That bound
    # (3e-8 ... 3e-7 of λ on the low modes, 7e-6 on the 10-16 kHz residual-vector modes), plus the two
    # eigen-solves' round-off, ~eps·λ_max each, is the tolerance. (The roundings are the same on every
    # machine, the matrices agreeing to their 9th digit: they move the low frequencies by 6e-10 here, 2 %
    # of the bound at most; a digit or an exponent read wrong moves them by far more.)
    w2, phi = la.eigh(back.K, back.M)
    elastic = fb.free_hz > 0

    def rounding(A):
        a = np.abs(A)
        return np.where((a >= 1) & (a < 1e12), REL_MID, REL_ANY) * a

    p = np.abs(phi)
    moved_k = np.einsum("ji,jk,ki->i", p, rounding(back.K), p)
    moved_m = np.einsum("ji,jk,ki->i", p, rounding(back.M), p)
    bound = 2 * (moved_k + w2 * moved_m)
    bound += 2 * 100 * np.finfo(float).eps * w2.max()
    err = np.abs(w2 - (2 * np.pi * fb.free_hz) ** 2)
    assert np.all(err[elastic] <= bound[elastic]), (err / bound)[elastic]


# --- refusals ---------------------------------------------------------------------------------


def test_other_units_refused_naming_both(tmp_path):
    path = write_flexible_body(_body("torsion"), tmp_path / "p.pch")
    text = path.read_text()
    assert text.count('"length": "m"') == 1  # the header breaks lines only after commas
    path.write_text(text.replace('"length": "m"', '"length": "mm"'))
    msg = "units.length = 'mm': the file's length unit is 'mm', flexshaft's is 'm'; valid: 'm'"
    with pytest.raises(fs.ModelError, match=msg):
        read_flexible_body(path)
    with pytest.raises(fs.ModelError, match=msg):
        parse_dmig(path.read_text())


def test_text_without_our_header_refused():
    # pyyeti's rddmig example: a valid DMIG, but nothing says what units it is in.
    foreign = "DMIG    MAT            0       1       2       0\nDMIG*   MAT                            1\n"
    with pytest.raises(
        fs.ModelError,
        match=r"<dmig>: header = 'DMIG    MAT            0       1       2': has no flexshaft header; "
        r"valid: a punch written by flexshaft",
    ):
        parse_dmig(foreign)


def test_deck_errors_nastran_would_also_refuse():
    text = dmig_text(_body("torsion"))
    lines = text.splitlines()
    first = next(k for k, ln in enumerate(lines) if ln.startswith("DMIG*   KAAX"))
    # The diagonal's column again, with its first row term: an element given twice.
    twice = lines[: first + 2] + lines[first : first + 2] + lines[first + 2 :]
    with pytest.raises(fs.ModelError, match=r"KAAX: term \(1, 1\) is given twice"):
        parse_dmig("\n".join(twice))
    with pytest.raises(fs.ModelError, match="KAAX: has IFO = 1, TIN = 2; valid: IFO = 6"):
        parse_dmig(text.replace("KAAX           0       6", "KAAX           0       1"))
    stray = text.replace(
        "*                   1002               4", "*                   1003               4", 1
    )
    with pytest.raises(fs.ModelError, match="row 1003 component 4 is not a coordinate of this body"):
        parse_dmig(stray)


def test_sidecar_required_and_must_match(tmp_path):
    write_flexible_body(_body("torsion"), tmp_path / "a.pch")
    write_flexible_body(_body("full"), tmp_path / "b.pch")
    (tmp_path / "a.pch.json").replace(tmp_path / "c.pch.json")
    with pytest.raises(
        fs.ModelError, match="its units sidecar is missing; valid: the .pch.json written with it"
    ):
        read_flexible_body(tmp_path / "a.pch")
    (tmp_path / "b.pch.json").replace(tmp_path / "a.pch.json")
    with pytest.raises(fs.ModelError, match="dofs = 'torsion': the punch and its sidecar describe different"):
        read_flexible_body(tmp_path / "a.pch")


def test_never_overwrites_and_never_half_writes(tmp_path):
    fb = _body("torsion")
    path = tmp_path / "p.pch"
    write_flexible_body(fb, path)
    before = {q.name: q.read_bytes() for q in tmp_path.iterdir()}
    with pytest.raises(fs.ModelError, match="output = '.*p.pch': file exists"):
        write_flexible_body(fb, path)
    (tmp_path / "p.pch").unlink()  # the sidecar alone still blocks: the pair is written together
    with pytest.raises(fs.ModelError, match="p.pch.json': file exists"):
        write_flexible_body(fb, path)
    path.write_bytes(before["p.pch"])
    # A body the punch cannot hold fails before anything is written, even with overwrite=True.
    K = fb.K.copy()
    K[0, 1] += 1.0e-3 * np.max(np.abs(K))
    bad = FlexibleBody(**(vars(fb) | {"K": K}))
    with pytest.raises(fs.ModelError, match="K: is not symmetric"):
        write_flexible_body(bad, path, overwrite=True)
    assert {q.name: q.read_bytes() for q in tmp_path.iterdir()} == before  # untouched, no temp files
    with pytest.raises(fs.ModelError, match="is not symmetric"):
        write_flexible_body(bad, tmp_path / "new.pch")
    assert sorted(q.name for q in tmp_path.iterdir()) == ["p.pch", "p.pch.json"]
    write_flexible_body(fb, path, overwrite=True)


# --- peer reader ------------------------------------------------------------------------------

PYYETI_MISSING = "pyyeti (the peer reader, from the test extra: pip install -e '.[test]') is not installed"


def test_pyyeti_reads_our_punch(tmp_path):
    # Peer check: pyyeti's rddmig indexes the matrices by (GRID, component) and (SPOINT, 0); mapped back to
    # our order they must be ours, bit for bit (both parse the same decimal text), and its rdgrids must find
    # the grids on the X axis.
    nastran = pytest.importorskip("pyyeti.nastran", reason=PYYETI_MISSING)
    for dofs in ("torsion", "full"):
        fb = _body(dofs, nodes=(7,))
        path = tmp_path / f"{dofs}.pch"
        write_flexible_body(fb, path)
        ours = parse_dmig(path.read_text())
        ids = ours["metadata"]["dmig"]
        labels = [(g, c) for g in ids["grids"] for c in ids["components"]] + [(s, 0) for s in ids["spoints"]]
        theirs = nastran.rddmig(str(path))
        assert sorted(theirs) == ["baax", "kaax", "maax"]
        for key, name in (("K", "kaax"), ("M", "maax"), ("C", "baax")):
            np.testing.assert_array_equal(theirs[name].loc[labels, labels].to_numpy(), ours[key])
        grids = nastran.rdgrids(str(path))
        np.testing.assert_array_equal(grids[:, 0], ids["grids"])
        np.testing.assert_array_equal(grids[:, 2], fb.boundary_x)
        np.testing.assert_array_equal(grids[:, 3:5], 0.0)


def test_header_lines_are_json_pieces():
    text = dmig_text(_body("torsion"), material=fs.STEEL)
    pieces = [ln[len(HEADER_PREFIX) :] for ln in text.splitlines() if ln.startswith(HEADER_PREFIX)]
    assert len(pieces) > 1 and all(not p.endswith(" ") for p in pieces)  # nothing an editor would trim
    assert json.loads("".join(pieces))["material"]["name"] == "steel"
