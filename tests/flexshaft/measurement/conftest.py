"""Fixtures of the io tests."""

from __future__ import annotations

import tracemalloc

import pytest

import flexshaft.measurement.files as measured


@pytest.fixture
def in_process(monkeypatch):
    """A measured file's reading in this process, so tracemalloc sees what it allocates."""
    monkeypatch.setattr(measured, "run_isolated", lambda work, **_: work(lambda *message: None))
    tracemalloc.start()
    yield
    tracemalloc.stop()
