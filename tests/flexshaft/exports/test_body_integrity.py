"""Integrity of exported flexible bodies: checksums that cannot be switched off, and the physics.

Every format carries SHA-256 checksums the reader requires (``body_sha256`` in npz/json/mat,
``data_sha256`` and ``sidecar_sha256`` in an OP4/DMIG sidecar): deleting, mangling or outdating one
is refused with the advice to export again. A file whose checksums agree but whose body cannot be -
written by another tool, or sealed again after an edit - is refused by the physics checks: K and M
symmetric, M positive definite, K positive semidefinite with the body's rigid-body modes, C positive
semidefinite, the stored frequencies those of K and M.
"""

from __future__ import annotations

import dataclasses
import json
import re
import warnings

import numpy as np
import pytest
from scipy.io import loadmat, savemat

import flexshaft as fs
from flexshaft.exports.bodies import read_flexible_body, write_flexible_body
from flexshaft.exports.bodyformat import (
    BODY_SHA256,
    DATA_SHA256,
    SIDECAR_SHA256,
    VERSION,
    body_sha256,
    canonical_json,
    check_physics,
    sidecar_sha256,
)
from flexshaft.reduction import ModalDamping, craig_bampton
from flexshaft.sections import table_from_segments

FORMATS = (".npz", ".json", ".mat", ".op4", ".pch")
SELF_CONTAINED = (".npz", ".json", ".mat")
PAIRS = (".op4", ".pch")
ARRAYS = (
    "boundary_nodes",
    "boundary_x",
    "K",
    "M",
    "C",
    "T",
    "fixed_interface_hz",
    "free_hz",
    "free_modes",
    "damping_ratios",
)
TABLE = table_from_segments([{"length": 1.0, "od": 0.1}, {"length": 0.5, "od": 0.14, "id": 0.06}], name="p")


def _body(dofs="torsion", **kw):
    pm = fs.part_model(TABLE, fs.STEEL, dofs=dofs, max_element_length=0.1)
    return craig_bampton(pm, **({"modes": 3} | kw))


@pytest.fixture(scope="module")
def torsion():
    return _body("torsion")


@pytest.fixture(scope="module")
def full():
    return _body("full")


def _read(path):
    return read_flexible_body(path)


def _refused(path, field: str, *says: str, file=None) -> fs.ModelError:
    """Reading ``path`` is one error line naming ``file`` (default: ``path``), ``field`` and ``says``."""
    with pytest.raises(fs.ModelError) as err:
        _read(path)
    text = str(err.value)
    assert err.value.field == field, text
    assert "\n" not in text and err.value.file == str(file or path), text
    for s in says:
        assert s in text, text
    return err.value


def _write(body, path):
    return write_flexible_body(body, path, overwrite=True)


# --- raw access to what a file holds, bypassing the reader's checks -----------------------------


def _load_raw(path):
    """(metadata, arrays) of a self-contained file, as stored."""
    suffix = path.suffix
    if suffix == ".json":
        doc = json.loads(path.read_text())
        return {k: v for k, v in doc.items() if k not in ARRAYS}, {k: doc[k] for k in ARRAYS}
    if suffix == ".npz":
        with np.load(path) as data:
            return json.loads(str(data["metadata"])), {k: np.array(data[k]) for k in ARRAYS}
    data = {k: v for k, v in loadmat(path).items() if not k.startswith("__")}
    return json.loads(str(np.atleast_1d(data.pop("flexshaft_metadata"))[0])), data


def _store_raw(path, meta, arrays):
    if path.suffix == ".json":
        path.write_text(json.dumps(meta | {k: np.asarray(v).tolist() for k, v in arrays.items()}))
    elif path.suffix == ".npz":
        np.savez_compressed(path, metadata=np.array(json.dumps(meta)), **arrays)
    else:
        savemat(path, arrays | {"flexshaft_metadata": json.dumps(meta)}, do_compression=True)


def _reseal_json(path):
    """Seal an edited JSON body again, as a tool that writes the format correctly would."""
    meta, arrays = _load_raw(path)
    typed = {k: np.asarray(v, dtype=int if k == "boundary_nodes" else float) for k, v in arrays.items()}
    meta[BODY_SHA256] = body_sha256(meta, typed)
    _store_raw(path, meta, arrays)


# --- what flexshaft writes reads back, in every format -------------------------------------------


@pytest.mark.parametrize("suffix", FORMATS)
@pytest.mark.parametrize(
    "dofs, options",
    [
        ("torsion", {}),
        ("torsion", {"modes": 0}),
        ("torsion", {"modes": 4, "residual": False, "damping_ratio": 0.0}),
        ("torsion", {"modes": 2, "damping_ratio": ModalDamping(rayleigh=(0.0, 1e-5))}),
        ("full", {}),
        ("full", {"modes": 2, "damping_ratio": ModalDamping(rayleigh=(2.0, 1e-6))}),
    ],
)
def test_every_body_flexshaft_writes_passes_every_check(tmp_path, suffix, dofs, options):
    body = _body(dofs, **options)
    got = _read(_write(body, tmp_path / f"b{suffix}")).body
    assert got.K.shape == body.K.shape
    if suffix != ".pch":  # doubles: bit-identical (a punch keeps 9-12 digits, see test_dmig)
        np.testing.assert_array_equal(got.K, body.K)
        np.testing.assert_array_equal(got.C, body.C)


def test_the_checksum_of_a_body_is_the_same_in_every_self_contained_format(tmp_path, torsion):
    # Canonical metadata + arrays as int64/float64: the digest does not depend on the container.
    sums = {s: _load_raw(_write(torsion, tmp_path / f"b{s}"))[0][BODY_SHA256] for s in SELF_CONTAINED}
    assert len(set(sums.values())) == 1, sums


def test_canonical_json_is_sorted_ascii_and_round_trips_floats():
    doc = {"b": [0.1, 1e-300, 2.0], "a": "N·m", "c": {"y": 1, "x": None}}
    text = canonical_json(doc)
    assert text == b'{"a":"N\\u00b7m","b":[0.1,1e-300,2.0],"c":{"x":null,"y":1}}'
    assert canonical_json(json.loads(text)) == text


# --- the checksums cannot be switched off --------------------------------------------------------


@pytest.mark.parametrize("suffix", SELF_CONTAINED)
def test_self_contained_checksum_missing_malformed_or_different_is_refused(tmp_path, torsion, suffix):
    path = _write(torsion, tmp_path / f"b{suffix}")
    meta, arrays = _load_raw(path)
    again = "export the part again (`flexshaft reduce"
    del meta[BODY_SHA256]
    _store_raw(path, meta, arrays)
    _refused(path, BODY_SHA256, "is missing", again)
    _store_raw(path, meta | {BODY_SHA256: "sha256:abc"}, arrays)
    _refused(path, BODY_SHA256, "is not a SHA-256", again)
    _store_raw(path, meta | {BODY_SHA256: 12}, arrays)
    _refused(path, BODY_SHA256, "is not a SHA-256", again)
    # A digit of K changed: the checksum no longer matches (the physics alone would not see it).
    good = _load_raw(_write(torsion, tmp_path / f"b{suffix}"))
    meta, arrays = good
    K = np.array(arrays["K"], dtype=float)
    K[1, 1] *= 1 + 1e-9
    _store_raw(path, meta, arrays | {"K": K})
    _refused(path, BODY_SHA256, "does not match the file's metadata and arrays", again)
    # The metadata is covered too: another material, and nothing else changed.
    _store_raw(path, meta | {"name": "another part"}, arrays)
    _refused(path, BODY_SHA256, "does not match")


@pytest.mark.parametrize("suffix", PAIRS)
def test_sidecar_checksums_are_required_and_cover_the_sidecar(tmp_path, torsion, suffix):
    path = _write(torsion, tmp_path / f"b{suffix}")
    side = path.with_name(path.name + ".json")
    good = json.loads(side.read_text())
    assert set(good) >= {DATA_SHA256, SIDECAR_SHA256} and good["version"] == VERSION

    def store(doc):
        side.write_text(json.dumps(doc))

    # Deleting data_sha256 (the finding): the sidecar's own checksum no longer matches ...
    store({k: v for k, v in good.items() if k != DATA_SHA256})
    _refused(path, SIDECAR_SHA256, "does not match the sidecar's content", "export the part again", file=side)
    # ... and sealing the sidecar again without it still leaves the data unchecked: refused.
    doc = {k: v for k, v in good.items() if k not in (DATA_SHA256, SIDECAR_SHA256)}
    store(doc | {SIDECAR_SHA256: sidecar_sha256(doc)})
    _refused(path, DATA_SHA256, "is missing", "export the part again")
    # The sidecar's own checksum deleted, or edited, or the sidecar edited.
    store({k: v for k, v in good.items() if k != SIDECAR_SHA256})
    _refused(path, SIDECAR_SHA256, "is missing", file=side)
    store(good | {SIDECAR_SHA256: "0" * 64})
    _refused(path, SIDECAR_SHA256, "does not match", file=side)
    store(good | {SIDECAR_SHA256: None})
    _refused(path, SIDECAR_SHA256, "is not a SHA-256", file=side)
    edited = json.loads(json.dumps(good))
    edited["free_hz"][1] *= 1.0001
    store(edited)
    _refused(path, SIDECAR_SHA256, "does not match", file=side)
    store(good)
    _read(path)  # the pair as written reads


_OP4_VALUE = re.compile(r"[ -]\d\.\d{16}E[+-]\d\d")


def _digit_edits(text: str, suffix: str) -> list[str]:
    """Six texts, each with one mantissa digit of a matrix value changed (the value stays a number)."""
    lines = text.splitlines()
    spots = []
    for k, ln in enumerate(lines):
        if suffix == ".op4":  # value lines: fields of 23 characters, " d.dddddddddddddddddE+ee"
            fields = [f for f in range(0, len(ln), 23) if _OP4_VALUE.fullmatch(ln[f : f + 23])]
            if fields and ln.strip() != "1.0000000000000000E+00":  # not a matrix's closing record
                spots.append((k, fields[len(spots) % len(fields)] + 4 + len(spots)))
        elif ln.startswith("*   ") and "D" in ln[40:]:  # DMIG* column entry: the value in columns 41-56
            mantissa = [c for c in range(40, ln.index("D", 40)) if ln[c].isdigit()]
            spots.append((k, mantissa[min(len(spots), len(mantissa) - 1)]))
        if len(spots) == 6:
            break
    out = []
    for k, c in spots:
        edited = list(lines)
        edited[k] = lines[k][:c] + str((int(lines[k][c]) + 1) % 10) + lines[k][c + 1 :]
        out.append("\n".join(edited) + "\n")
    assert len(out) == 6
    return out


@pytest.mark.parametrize("suffix", PAIRS)
def test_every_digit_edit_in_a_nastran_file_is_refused(tmp_path, torsion, suffix):
    path = _write(torsion, tmp_path / f"b{suffix}")
    text = path.read_text()
    for edited in _digit_edits(text, suffix):
        path.write_text(edited)
        _refused(path, DATA_SHA256, "does not match its sidecar", "export the part again")
    path.write_text(text)
    _read(path)


def test_sidecar_tools_that_rewrite_it_keep_it_readable(tmp_path, torsion):
    # Key order and blanks are not content: the canonical form is what the checksum covers.
    path = _write(torsion, tmp_path / "b.op4")
    side = path.with_name("b.op4.json")
    doc = json.loads(side.read_text())
    side.write_text(json.dumps(dict(reversed(list(doc.items()))), indent=2))
    _read(path)


@pytest.mark.parametrize("suffix", FORMATS)
def test_files_of_format_version_1_are_refused_with_what_to_do(tmp_path, torsion, suffix):
    path = _write(torsion, tmp_path / f"b{suffix}")
    if suffix in PAIRS:  # as 0.1 wrote it: version 1, data_sha256 only (or no checksum at all)
        side = path.with_name(path.name + ".json")
        doc = json.loads(side.read_text())
        del doc[SIDECAR_SHA256]
        side.write_text(json.dumps(doc | {"version": 1}))
        where = side
    else:
        meta, arrays = _load_raw(path)
        del meta[BODY_SHA256]
        _store_raw(path, meta | {"version": 1}, arrays)
        where = path
    again = "export the part again with `flexshaft reduce`"
    _refused(path, "version", "earlier flexshaft", again, file=where)


# --- the physics of a body whose checksums agree -------------------------------------------------


def _variant(body, change: str):
    """A body that cannot be, written (and sealed) through the ordinary writer."""
    K, M, C = body.K.copy(), body.M.copy(), body.C.copy()
    if change == "negated K":
        K = -K
    elif change == "negative C":
        C = -C
    elif change == "negative M":
        M = -M
    elif change == "extra rigid mode":  # a modal coordinate with no stiffness
        K[-1, :] = K[:, -1] = 0.0
    elif change == "no rigid mode":  # grounded: every mode elastic
        K = K + 1e-3 * np.max(np.abs(K)) * np.eye(K.shape[0])
    elif change == "asymmetric K":
        K[0, 1] *= 1.001
    return dataclasses.replace(body, K=K, M=M, C=C)


@pytest.mark.parametrize("suffix", FORMATS)
@pytest.mark.parametrize(
    "change, field, says",
    [
        ("negated K", "K", ("negative eigenvalue", "N·m/rad", "imaginary", "exactly 1 rigid-body mode")),
        ("negative C", "C", ("has a negative eigenvalue", "N·m·s/rad", "positive semidefinite")),
        ("negative M", "M", ("is not positive definite", "kg·m²")),
        ("extra rigid mode", "K", ("has 2 rigid-body modes", "exactly 1 rigid-body mode")),
        ("no rigid mode", "K", ("has 0 rigid-body modes", "its free rotation")),
        ("asymmetric K", "K", ("is not symmetric", "a symmetric K (to round-off")),
    ],
)
def test_a_body_that_cannot_be_is_refused_in_every_format(tmp_path, torsion, suffix, change, field, says):
    bad = _variant(torsion, change)
    if suffix == ".pch" and change == "asymmetric K":
        with pytest.raises(fs.ModelError, match="is not symmetric"):  # a punch holds one triangle
            _write(bad, tmp_path / "b.pch")
        return
    path = _write(bad, tmp_path / f"b{suffix}")
    _refused(path, field, *says)


def test_a_6_dof_body_needs_its_six_rigid_body_modes(tmp_path, full):
    path = _write(_variant(full, "no rigid mode"), tmp_path / "b.json")
    _refused(path, "K", "has 0 rigid-body modes", "exactly 6", "three translations and three rotations")
    # One extra zero mode besides the six.
    path = _write(_variant(full, "extra rigid mode"), tmp_path / "c.json")
    _refused(path, "K", "has 7 rigid-body modes")


@pytest.mark.parametrize("suffix", FORMATS)
def test_stored_frequencies_must_be_those_of_k_and_m(tmp_path, torsion, suffix):
    for i, factor in ((2, 1.01), (1, 1 + 1e-5), (0, None)):
        hz = torsion.free_hz.copy()
        hz[i] = 3.0 if factor is None else hz[i] * factor  # mode 1 is the rigid one: 0 Hz
        path = _write(dataclasses.replace(torsion, free_hz=hz), tmp_path / f"b{i}{suffix}")
        _refused(path, "free_hz", f"mode {i + 1} is stored at", "K and M give")


def test_the_frequency_tolerance_comes_from_conditioning_and_the_punch_digits(torsion):
    # The tolerance is a first-order bound on each eigenvalue: a change of 1e-5 in λ is seen on every
    # mode of a body in doubles (the bound is at most 6e-12 of λ on this body's elastic modes), and of
    # 1e-3 through a punch's 5e-9 rounding (at most 1e-6 of λ here).
    arrays = {k: getattr(torsion, k) for k in ("K", "M", "C", "T", "free_hz")}
    meta = {"dofs": "torsion"}
    check_physics(arrays, meta, "b")
    check_physics(arrays, meta, "b", rounding=5e-9)
    for k in range(1, torsion.free_hz.size):
        for rel, rounding in ((1e-5, 0.0), (1e-3, 5e-9)):
            hz = torsion.free_hz.copy()
            hz[k] *= np.sqrt(1 + rel)
            with pytest.raises(fs.ModelError, match=f"free_hz: mode {k + 1} is stored"):
                check_physics(arrays | {"free_hz": hz}, meta, "b", rounding=rounding)


def test_the_json_edits_of_the_finding_are_refused_sealed_or_not(tmp_path, torsion):
    # Negated K, negative C: an edit alone is a checksum error; sealed again, a physics error.
    for key in ("K", "C"):
        path = _write(torsion, tmp_path / f"{key}.json")
        doc = json.loads(path.read_text())
        doc[key] = (-np.array(doc[key])).tolist()
        path.write_text(json.dumps(doc))
        _refused(path, BODY_SHA256, "does not match")
        _reseal_json(path)
        _refused(path, key, "has a negative eigenvalue")


def test_numbers_at_the_end_of_double_precision_are_one_error_not_a_warning(torsion):
    # K scaled to 1e307: its eigenvalues still come out, the tolerance's products overflow - refused
    # as the file's numbers, with no RuntimeWarning on the way.
    arrays = {k: getattr(torsion, k) for k in ("K", "M", "C", "T", "free_hz")}
    arrays["K"] = arrays["K"] / np.max(np.abs(arrays["K"])) * 1e307
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(fs.ModelError, match=r"^b: K, M, C: cannot be checked in double precision"):
            check_physics(arrays, {"dofs": "torsion"}, "b")
