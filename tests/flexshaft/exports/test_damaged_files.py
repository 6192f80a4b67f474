"""Reading a damaged or hostile flexible-body file: the body as written, or one ModelError.

Never a foreign exception (UnicodeDecodeError, zlib.error, BadZipFile, KeyError, MemoryError) and
never different data accepted (the checksums see every change of content): the corruptions are
deterministic (fixed seed), a sample of what a copy, a truncated download or a hand edit does to a
file. Hand edits sealed again with a valid checksum (as another tool writing the format would) meet
the shape and physics checks, each naming its field.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.exports.bodies import read_flexible_body, write_flexible_body
from flexshaft.exports.bodyformat import BODY_SHA256, body_sha256
from flexshaft.reduction import craig_bampton
from flexshaft.sections import table_from_segments

FORMATS = (".npz", ".json", ".mat", ".op4", ".pch")


@pytest.fixture(scope="module")
def body():
    t = table_from_segments([{"length": 1.0, "od": 0.1}], name="p")
    return craig_bampton(fs.part_model(t, fs.STEEL, dofs="torsion", max_element_length=0.1), modes=3)


def _read_or_refuse(path):
    """Read: either one ModelError line (None), or the body."""
    try:
        return read_flexible_body(path)
    except fs.ModelError as err:
        assert "\n" not in str(err)
        return None


@pytest.mark.parametrize("suffix", FORMATS)
def test_truncated_and_bit_flipped_files_are_refused_or_pass_the_checks(tmp_path, body, suffix):
    good = tmp_path / f"good{suffix}"
    write_flexible_body(body, good)
    data = good.read_bytes()
    original = read_flexible_body(good).body
    rng = np.random.default_rng(20261122)
    bad = tmp_path / f"bad{suffix}"
    side = tmp_path / f"bad{suffix}.json"
    if suffix in (".op4", ".pch"):
        side.write_bytes((tmp_path / f"good{suffix}.json").read_bytes())
    variants = [data[: int(f * len(data))] for f in (0.0, 0.1, 0.5, 0.9, 0.99)]
    for _ in range(25):
        b = bytearray(data)
        for pos in rng.integers(0, len(b), size=int(rng.integers(1, 6))):
            b[pos] = int(rng.integers(0, 256))
        variants.append(bytes(b))
    accepted = 0
    for v in variants:
        bad.write_bytes(v)
        got = _read_or_refuse(bad)
        if got is not None:
            accepted += 1
            # Only a change that is no change of content passes (a blank in JSON, a zip's spare byte).
            for name in ("K", "M", "C", "T", "free_hz", "free_modes", "damping_ratios", "boundary_x"):
                np.testing.assert_array_equal(getattr(got.body, name), getattr(original, name))
    assert accepted < len(variants)


def _json_doc(tmp_path, body):
    path = tmp_path / "b.json"
    write_flexible_body(body, path)
    return path, json.loads(path.read_text())


@pytest.mark.parametrize(
    "edit, field",
    [
        (lambda d: d.update(K=[[1.0, 0.0], [0.0, 1.0]]), "K"),  # a 2 × 2 K
        (lambda d: d["K"][0].__setitem__(0, float("nan")), "K"),  # NaN (JSON writes it as NaN)
        (lambda d: d["K"][0].__setitem__(1, 2 * d["K"][0][1] + 1e6), "K"),  # asymmetric
        (lambda d: d.update(dofs="bogus"), "dofs"),
        (lambda d: d.update(residual_vectors=-2), "residual_vectors"),
        (lambda d: d.update(damping_ratios=[2.0] * len(d["damping_ratios"])), "damping_ratios"),
        (lambda d: d.update(name=["p"]), "name"),
        (lambda d: d.update(boundary_nodes=[0, 999]), "boundary_nodes"),
        (lambda d: d.update(M=[[0.0] * len(d["M"])] * len(d["M"])), "M"),
    ],
)
def test_edited_metadata_and_arrays_are_refused_naming_the_field(tmp_path, body, edit, field):
    path, doc = _json_doc(tmp_path, body)
    edit(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(fs.ModelError) as err:
        read_flexible_body(path)
    assert err.value.field == BODY_SHA256  # an edit alone: the checksum no longer matches
    # Sealed again (a tool that writes the format): the checks behind the checksum name the field.
    meta = {k: v for k, v in doc.items() if k not in _ARRAYS}
    path.write_text(json.dumps(doc | {BODY_SHA256: body_sha256(meta, _typed(doc))}))
    with pytest.raises(fs.ModelError) as err:
        read_flexible_body(path)
    assert err.value.field == field


_ARRAYS = ("boundary_nodes", "boundary_x", "K", "M", "C", "T", "fixed_interface_hz", "free_hz")
_ARRAYS += ("free_modes", "damping_ratios")


def _typed(doc: dict) -> dict:
    """The arrays of a JSON body as the reader types them (what the checksum covers)."""
    return {k: np.asarray(doc[k], dtype=int if k == "boundary_nodes" else float) for k in _ARRAYS}


def test_a_header_claiming_a_huge_matrix_allocates_nothing(tmp_path, body):
    # OP4: 99999999 × 99999999 would be 80 PB; refused from the header.
    path = tmp_path / "h.op4"
    write_flexible_body(body, path)
    text = path.read_text().splitlines()  # read before the checksum is compared: OP4 text first
    text[0] = f"{99999999:8d}{99999999:8d}" + text[0][16:]
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(fs.ModelError, match="claims 99999999 × 99999999"):
        read_flexible_body(path)
    # npz: an array header claiming 1e12 entries.
    import io
    import zipfile

    npz = tmp_path / "h.npz"
    write_flexible_body(body, npz)
    members = {}
    with zipfile.ZipFile(npz) as zf:
        for name in zf.namelist():
            members[name] = zf.read(name)
    buf = io.BytesIO()  # magic and header of a float array of 1e6 × 1e6, and no data
    header = {"descr": "<f8", "fortran_order": False, "shape": (10**6, 10**6)}
    np.lib.format.write_array_header_1_0(buf, header)
    members["K.npy"] = buf.getvalue()
    with zipfile.ZipFile(npz, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    with pytest.raises(fs.ModelError, match=r"K: array claims shape \(1000000, 1000000\)"):
        read_flexible_body(npz)


def _mat_matrix(name: str, dims, data: bytes, *, claim: int | None = None) -> bytes:
    """A MAT v5 miMATRIX element of class double, laid out as The MathWorks' "MAT-File Format"
    (2019) gives it: array flags, dimensions, name, real part (``claim``: the bytes its tag says)."""
    import struct

    def sub(mdtype: int, payload: bytes, nbytes: int | None = None) -> bytes:
        pad = -len(payload) % 8
        return struct.pack("<II", mdtype, len(payload) if nbytes is None else nbytes) + payload + b"\0" * pad

    body = sub(6, struct.pack("<II", 6, 0))  # miUINT32 flags: mxDOUBLE_CLASS
    body += sub(5, struct.pack("<" + "i" * len(dims), *dims))  # miINT32 dimensions
    body += sub(1, name.encode())  # miINT8 name
    body += sub(9, data, claim)  # miDOUBLE real part
    return struct.pack("<II", 14, len(body)) + body


def _mat_file(tmp_path, element: bytes, *, compress: bool):
    import struct
    import zlib

    head = b"MATLAB 5.0 MAT-file, crafted".ljust(116) + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    if compress:
        z = zlib.compress(element)
        element = struct.pack("<II", 15, len(z)) + z
    path = tmp_path / "bomb.mat"
    path.write_bytes(head + element)
    return path


@pytest.mark.parametrize(
    "dims, data, compress, says",
    [
        # 10^4 x 10^4 doubles (800 MB) claimed by a header of a few bytes: refused before loadmat
        ((10_000, 10_000), b"", True, "K: claims 100,000,000 entries"),
        # a 10 x 10 header whose compressed data inflate to 8 MB: counted, not kept
        ((10, 10), bytes(8 << 20), True, "inflate to more than its (10, 10) double entries"),
        # an uncompressed 1000 x 1000 claim over 800 bytes of data
        ((1000, 1000), bytes(800), False, "claims 1,000,000 entries, 8,000,000 bytes at least"),
    ],
)
def test_a_mat_header_claiming_more_than_the_file_holds_is_refused_before_reading(
    tmp_path, dims, data, compress, says
):
    path = _mat_file(tmp_path, _mat_matrix("K", dims, data), compress=compress)
    with pytest.raises(fs.ModelError, match=re.escape(says)) as err:
        read_flexible_body(path)
    assert "\n" not in str(err.value) and "bomb.mat" in str(err.value)
