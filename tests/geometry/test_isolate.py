"""Foreign native code in a forked child (geometry.isolate): results, messages and every way it can end."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

from flexshaft.errors import ModelError
from geometry.isolate import run_isolated


def error(reason: str) -> ModelError:
    return ModelError(f"the work {reason}", component="part")


def test_the_result_and_the_messages_come_back():
    seen = []

    def work(send):
        send("half", 0.5)
        return {"pid": os.getpid(), "array": np.arange(5.0)}

    out = run_isolated(work, timeout=60.0, error=error, on_message=lambda *m: seen.append(m))
    assert out["pid"] != os.getpid()  # it ran in a child
    assert np.array_equal(out["array"], np.arange(5.0)) and seen == [("half", 0.5)]


def test_a_model_error_in_the_child_is_raised_as_it_was():
    def work(send):
        raise ModelError("is odd", component="part", field="size", value=3.0, unit="m", valid="even")

    with pytest.raises(ModelError) as err:
        run_isolated(work, timeout=60.0, error=error)
    assert (err.value.field, err.value.value, err.value.unit) == ("size", 3.0, "m")
    assert str(err.value) == "part: size = 3.0 m: is odd; valid: even"


def test_a_crash_a_failure_and_a_hang_are_each_one_error():
    with pytest.raises(ModelError, match=r"^part: the work crashed \(signal SIGSEGV\)$"):
        run_isolated(lambda send: os.kill(os.getpid(), signal.SIGSEGV), timeout=60.0, error=error)
    with pytest.raises(ModelError, match=r"^part: the work failed: RuntimeError: boom$"):
        run_isolated(lambda send: (_ for _ in ()).throw(RuntimeError("boom")), timeout=60.0, error=error)

    def talks_forever(send):
        while True:
            send("still here", None)

    with pytest.raises(ModelError, match=r"took more than 0\.3 s"):
        run_isolated(talks_forever, timeout=0.3, error=error)


def test_the_memory_cap_turns_runaway_allocation_into_a_failure():
    def hog(send):
        return np.ones(1 << 28)  # 2 GB

    with pytest.raises(ModelError, match="failed: MemoryError"):
        run_isolated(hog, timeout=60.0, error=error, memory=256 << 20)


def test_without_fork_the_work_runs_here(monkeypatch):
    monkeypatch.delattr(os, "fork")
    assert run_isolated(lambda send: os.getpid(), timeout=60.0, error=error) == os.getpid()
    with pytest.raises(ModelError, match="failed: ValueError: invalid literal"):
        run_isolated(lambda send: int("no"), timeout=60.0, error=error)
