"""Exported bodies whose integrity someone tried to switch off, read back by ``flexshaft body FILE``.

Each setup writes a small torsion body (a two-step shaft, 3 fixed-interface modes) the way
``flexshaft reduce`` does, then damages it as the issue found: a sidecar checksum deleted, a digit of
an OP4 or a punch edited, a JSON body whose K is negated or C negative and sealed again (checksums
that agree: only the physics can tell).
"""

from __future__ import annotations

import json

import numpy as np

from tests.flexshaft.catalogue import Case


def _body():
    from tests.flexshaft.exports.test_body_integrity import _body as small

    return small("torsion")


def _written(name: str):
    from flexshaft.exports.bodies import write_flexible_body

    def setup(d):
        write_flexible_body(_body(), d / name)
        return ["body", name]

    return setup


def _sidecar_without(key: str, suffix: str, edit_digit: bool):
    def setup(d):
        argv = _written(f"b{suffix}")(d)
        side = d / f"b{suffix}.json"
        doc = json.loads(side.read_text())
        del doc[key]
        side.write_text(json.dumps(doc))
        if edit_digit:
            from tests.flexshaft.exports.test_body_integrity import _digit_edits

            path = d / f"b{suffix}"
            path.write_text(_digit_edits(path.read_text(), suffix)[0])
        return argv

    return setup


def _digit(suffix: str):
    def setup(d):
        from tests.flexshaft.exports.test_body_integrity import _digit_edits

        argv = _written(f"b{suffix}")(d)
        path = d / f"b{suffix}"
        path.write_text(_digit_edits(path.read_text(), suffix)[2])
        return argv

    return setup


def _json_sealed(edit):
    """A JSON body edited by ``edit(arrays)`` and sealed again (its checksum agrees)."""

    def setup(d):
        from tests.flexshaft.exports.test_body_integrity import _load_raw, _reseal_json, _store_raw

        argv = _written("b.json")(d)
        path = d / "b.json"
        meta, arrays = _load_raw(path)
        arrays = {k: np.asarray(v, dtype=float) for k, v in arrays.items()}
        edit(arrays)
        _store_raw(path, meta, arrays)
        _reseal_json(path)
        return argv

    return setup


def _negate_k(a):
    a["K"] = -a["K"]


def _negative_c(a):
    a["C"] = a["C"] - 2.0 * np.abs(a["C"]).max() * np.eye(len(a["C"]))


def _asymmetric_k(a):
    a["K"][0, 1] *= 1.01


def _frequency_off(a):
    a["free_hz"][-1] *= 1.01


CASES = {
    **{
        f"a good {s} body is read and summarised": Case(_written(f"b{s}"), exit=0)
        for s in (".npz", ".json", ".mat", ".op4", ".pch")
    },
    "op4 sidecar without data_sha256, op4 edited": Case(
        _sidecar_without("data_sha256", ".op4", True), says=("b.op4.json", "sidecar_sha256", "valid")
    ),
    "op4 sidecar without its own checksum": Case(
        _sidecar_without("sidecar_sha256", ".op4", False), says=("sidecar_sha256", "valid")
    ),
    "pch sidecar without its own checksum": Case(
        _sidecar_without("sidecar_sha256", ".pch", False), says=("sidecar_sha256", "valid")
    ),
    "a digit of the op4 edited": Case(_digit(".op4"), says=("b.op4", "data_sha256", "valid")),
    "a digit of the punch edited": Case(_digit(".pch"), says=("b.pch", "data_sha256", "valid")),
    "json body with K negated, sealed again": Case(_json_sealed(_negate_k), says=("b.json", "K", "valid")),
    "json body with a negative C, sealed again": Case(
        _json_sealed(_negative_c), says=("b.json", "C", "valid")
    ),
    "json body with an asymmetric K, sealed again": Case(_json_sealed(_asymmetric_k), says=("K", "valid")),
    "json body with a frequency that is not K's and M's": Case(
        _json_sealed(_frequency_off), says=("free_hz", "valid")
    ),
}
