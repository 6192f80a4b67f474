"""The thread policy: one BLAS/OpenMP thread unless the user says otherwise; the caller's settings kept."""

import inspect
import os
import subprocess
import sys

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import flexshaft
from flexshaft.errors import ModelError
from flexshaft.system.threads import USER_THREAD_VARIABLES, follows_policy, requested_threads, thread_policy

# Exported functions that do no linear algebra (arithmetic on a few numbers, names, reading a small
# TOML file, reading a signal file: parsing and copying): they need no policy, and applying one would
# import scipy.linalg for nothing (0.2 s, as long as reading a 300 MB record).
BOOKKEEPING = {
    "frequency_grid",
    "parameters",
    "rayleigh_coefficients",
    "rayleigh_ratio",
    "signal_names",
    "order_lines",
    "with_parameters",
    "read_targets",
    "read_study",
    "read_measured",
    "read_signals",
}


def _blas_threads() -> list[int]:
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


probe = follows_policy(_blas_threads)


@pytest.fixture
def clean_env(monkeypatch):
    for var in (*USER_THREAD_VARIABLES, "FLEXSHAFT_THREADS"):
        monkeypatch.delenv(var, raising=False)
    return monkeypatch


def test_an_entry_point_runs_on_one_thread_and_restores_the_callers_setting(clean_env):
    import scipy.linalg  # noqa: F401 - both BLAS libraries loaded, so the probe sees both

    with threadpool_limits(limits=2):
        before = _blas_threads()
        assert probe() == [1] * len(before)
        assert _blas_threads() == before


def test_flexshaft_threads_and_the_cli_option_win(clean_env):
    clean_env.setenv("FLEXSHAFT_THREADS", "2")
    clean_env.setenv("OPENBLAS_NUM_THREADS", "1")  # FLEXSHAFT_THREADS is the more specific one
    assert requested_threads() == 2
    assert requested_threads(3) == 3  # --threads over the environment
    with threadpool_limits(limits=1):
        inside = probe()
    # OpenBLAS may cap a request at the cores it found; it never leaves the count at the caller's 1
    # on a machine with two or more cores.
    if (os.cpu_count() or 1) >= 2:
        assert min(inside) == 2


def test_the_users_own_blas_variables_are_left_alone(clean_env):
    clean_env.setenv("OMP_NUM_THREADS", "2")
    assert requested_threads() is None
    with threadpool_limits(limits=2):
        before = _blas_threads()
        assert probe() == before


@pytest.mark.parametrize("text", ["x", "0", "-1", "1.5", "99999"])
def test_a_bad_thread_count_is_one_error_naming_the_setting(clean_env, text):
    clean_env.setenv("FLEXSHAFT_THREADS", text)
    with pytest.raises(ModelError, match=r"FLEXSHAFT_THREADS = .*valid: a whole number from 1 to 1024"):
        probe()


def test_nested_calls_apply_the_policy_once_at_the_outermost(clean_env):
    with thread_policy(2):
        inner = probe()  # an inner entry point does not undo the outer (explicit) choice
    if (os.cpu_count() or 1) >= 2:
        assert min(inner) == 2


def test_every_exported_function_follows_the_policy():
    missing = []
    for name in flexshaft.__all__:
        value = getattr(flexshaft, name)
        if inspect.isfunction(value) and name not in BOOKKEEPING:
            if not getattr(value, "__flexshaft_thread_policy__", False):
                missing.append(name)
    assert not missing, f"exported functions outside the thread policy: {missing}"


def _fresh(code: str, *args: str, env: dict | None = None) -> str:
    base = {k: v for k, v in os.environ.items() if k not in (*USER_THREAD_VARIABLES, "FLEXSHAFT_THREADS")}
    out = subprocess.run(
        [sys.executable, "-c", code, *args], env={**base, **(env or {})}, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


CLI_THREADS = """
import sys
from flexshaft.system.threads import cli_threads
cli_threads(int(sys.argv[1]) if len(sys.argv) > 1 else None)
import numpy, scipy.linalg, threadpoolctl, os
print(sorted({i["num_threads"] for i in threadpoolctl.threadpool_info()}), os.environ.get("OMP_NUM_THREADS"))
"""


def test_the_cli_settles_threads_before_numpy_loads_for_the_process_and_its_workers():
    # The libraries start with one thread and a worker process inherits the variables.
    assert _fresh(CLI_THREADS) == "[1] 1"
    assert _fresh(CLI_THREADS, "2").endswith(" 2")
    # the user's own variable stands
    assert _fresh(CLI_THREADS, env={"OMP_NUM_THREADS": "2"}).endswith(" 2")


def test_cli_threads_option_is_checked():
    from flexshaft.cli import main

    assert main(["demo", "--threads", "0"]) == 2
    assert main(["demo", "--threads", "1"]) == 0
