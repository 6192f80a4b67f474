"""The C heap's tuning kept for the benchmarks (benchmarks/heap.py), out of the library since issue 34."""

from __future__ import annotations

from benchmarks import heap


def test_the_heap_setting_nests_and_is_put_back():
    with heap.reused_blocks():
        with heap.reused_blocks():
            assert heap._depth == 2
        assert heap._depth == 1
    assert heap._depth == 0


def test_the_freed_heap_can_be_handed_back():
    heap.release_free_heap()  # glibc: malloc_trim; elsewhere nothing - never an error
