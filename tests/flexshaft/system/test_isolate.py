"""Foreign native code in a forked child (flexshaft.system.isolate): results, messages and every way it
can end."""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
from types import SimpleNamespace

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.system.isolate import Failure, run_isolated


def error(failure: Failure) -> ModelError:
    return ModelError(f"the work {failure.reason}", component="part")


def _ends(work, **options) -> tuple[Failure, ModelError]:
    """The Failure ``work`` ends in, and the error built of it."""
    seen = []

    def keep(failure: Failure) -> ModelError:
        seen.append(failure)
        return error(failure)

    with pytest.raises(ModelError) as err:
        run_isolated(work, error=keep, **{"timeout": 60.0, **options})
    assert len(seen) == 1
    return seen[0], err.value


def test_the_result_and_the_messages_come_back():
    seen = []

    def work(send):
        send("half", 0.5)
        return {"pid": os.getpid(), "array": np.arange(5.0)}

    out = run_isolated(work, timeout=60.0, error=error, on_message=lambda *m: seen.append(m))
    assert out["pid"] != os.getpid()  # it ran in a child
    assert np.array_equal(out["array"], np.arange(5.0)) and seen == [("half", 0.5)]


def test_arrays_come_back_whole_and_writeable():
    """Contiguous arrays travel apart from the pickle (protocol 5), the others inside it: either way the
    same bytes (a transport, not a computation: compared exactly) in a writeable array of the parent's."""
    rng = np.random.default_rng(20261124)
    sent = {
        "big": rng.standard_normal(1 << 20),  # 8 MB: larger than a pipe's buffer, sent in pieces
        "fortran": np.asfortranarray(rng.standard_normal((30, 7))),
        "strided": rng.standard_normal(101)[::3],  # not contiguous: pickled in-band
        "empty": np.empty(0),
        "ints": np.arange(10, dtype=np.int32),
        "text": "notes",
    }
    out = run_isolated(lambda send: sent, timeout=60.0, error=error)
    assert out.keys() == sent.keys() and out["text"] == "notes"
    for key in ("big", "fortran", "strided", "empty", "ints"):
        a, b = sent[key], out[key]
        assert (b.dtype, b.shape) == (a.dtype, a.shape) and np.array_equal(a, b), key
        assert b.flags.writeable, key
    out["big"][0] = 1.0  # the parent owns it


def test_a_model_error_in_the_child_is_raised_as_it_was():
    def work(send):
        raise ModelError("is odd", component="part", field="size", value=3.0, unit="m", valid="even")

    with pytest.raises(ModelError) as err:
        run_isolated(work, timeout=60.0, error=error)
    assert (err.value.field, err.value.value, err.value.unit) == ("size", 3.0, "m")
    assert str(err.value) == "part: size = 3.0 m: is odd; valid: even"


def test_a_model_error_whose_value_cannot_travel_shows_it_as_text():
    class Odd:
        def __reduce__(self):
            raise TypeError("not picklable")

        def __repr__(self):
            return "<odd>"

    def work(send):
        raise ModelError("is odd", field="shape", value=Odd())

    with pytest.raises(ModelError) as err:
        run_isolated(work, timeout=60.0, error=error)
    assert err.value.value == "<odd>"


def test_a_crash_a_failure_and_a_hang_are_each_one_error():
    failure, err = _ends(lambda send: os.kill(os.getpid(), signal.SIGSEGV))
    assert (failure.kind, failure.detail, failure.limit) == ("crashed", "signal SIGSEGV", 60.0)
    assert str(err) == "part: the work crashed (signal SIGSEGV)"
    failure, err = _ends(lambda send: os._exit(3))
    assert (failure.kind, failure.detail) == ("crashed", "exit code 3")
    failure, err = _ends(lambda send: (_ for _ in ()).throw(RuntimeError("boom")))
    assert (failure.kind, failure.detail) == ("failed", "RuntimeError: boom")
    assert str(err) == "part: the work failed: RuntimeError: boom"
    failure, err = _ends(lambda send: lambda: None)  # a result that cannot be pickled
    assert failure.kind == "failed"

    def talks_forever(send):
        while True:
            send("still here", None)

    failure, err = _ends(talks_forever, timeout=0.3)
    assert (failure.kind, failure.detail, failure.limit) == ("timeout", "", 0.3)
    assert str(err) == "part: the work took more than 0.3 s"


def test_a_silent_child_is_stopped_at_the_deadline():
    start = time.monotonic()
    failure, _ = _ends(lambda send: time.sleep(60), timeout=0.5)
    # the parent polls at most until the deadline: 0.5 s, the kill and the join, not the 60 s slept
    # (5 s: the fork and a loaded machine's scheduling, far below 60)
    assert failure.kind == "timeout" and time.monotonic() - start < 5.0


def test_the_memory_cap_turns_runaway_allocation_into_a_failure():
    def hog(send):
        return np.ones(1 << 28)  # 2 GB

    failure, _ = _ends(hog, memory=256 << 20)
    assert failure.kind == "failed" and failure.detail.startswith("MemoryError")


def test_a_crashing_child_leaves_no_core_file():
    """Under ``ulimit -c unlimited`` a child's crash wrote its whole heap (~400 MB with build123d) to
    the working directory; the child's own soft core limit is 0, the parent's stays as it was."""
    resource = pytest.importorskip("resource")

    soft, hard = resource.getrlimit(resource.RLIMIT_CORE)
    if hard == 0:
        pytest.skip("core files are off for this process and cannot be turned on")
    resource.setrlimit(resource.RLIMIT_CORE, (hard, hard))  # as under ulimit -c unlimited (or its most)
    try:
        child = run_isolated(lambda send: resource.getrlimit(resource.RLIMIT_CORE), timeout=60.0, error=error)
        assert child == (0, hard)
        assert resource.getrlimit(resource.RLIMIT_CORE) == (hard, hard)
    finally:
        resource.setrlimit(resource.RLIMIT_CORE, (soft, hard))


@pytest.mark.parametrize("where", ["no fork", "a daemonic process"])
def test_without_a_child_the_work_runs_here(monkeypatch, where):
    if where == "no fork":
        monkeypatch.delattr(os, "fork")
    else:
        monkeypatch.setattr(multiprocessing, "current_process", lambda: SimpleNamespace(daemon=True))
    seen = []
    out = run_isolated(
        lambda send: send("here") or os.getpid(), timeout=60.0, error=error, on_message=seen.append
    )
    assert out == os.getpid() and seen == ["here"]
    failure, err = _ends(lambda send: int("no"))
    assert failure.kind == "failed" and str(err).startswith(
        "part: the work failed: ValueError: invalid literal"
    )
    with pytest.raises(ModelError, match="is odd"):
        run_isolated(lambda send: (_ for _ in ()).throw(ModelError("is odd")), timeout=60.0, error=error)
