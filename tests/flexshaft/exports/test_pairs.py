"""A Nastran file and its sidecar are one body: a half-replaced pair is refused, not mixed."""

from __future__ import annotations

import pytest

import flexshaft as fs
from flexshaft.exports.bodies import read_flexible_body, write_flexible_body
from flexshaft.reduction import craig_bampton
from flexshaft.sections import table_from_segments


def body(length):
    t = table_from_segments([{"length": length, "od": 0.1}], name="p")
    # 20 elements whatever the length: the two bodies differ in their numbers only.
    pm = fs.part_model(t, fs.STEEL, dofs="torsion", max_element_length=length / 20)
    return craig_bampton(pm, modes=3)


@pytest.mark.parametrize("suffix", [".op4", ".pch"])
def test_a_data_file_from_another_write_is_refused(tmp_path, suffix):
    a, b = tmp_path / f"a{suffix}", tmp_path / f"b{suffix}"
    write_flexible_body(body(1.0), a)
    write_flexible_body(body(1.3), b)  # same name, DOFs and sizes: only the numbers differ
    assert read_flexible_body(a).body.K.shape == read_flexible_body(b).body.K.shape
    # As a write killed between the two files would leave it: a's sidecar beside b's matrices.
    b.replace(a)
    with pytest.raises(fs.ModelError, match="does not match its sidecar"):
        read_flexible_body(a)
