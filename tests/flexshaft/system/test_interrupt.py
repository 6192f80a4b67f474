"""SIGTERM and Ctrl-C end the ``flexshaft`` command within seconds, whatever it is doing.

A Python signal handler runs only between bytecodes; LAPACK's dense eigen-solve holds the
interpreter lock for its whole run (a SIGTERM waited 37 s for it here, 150 s in the issue). The
command's watchdog (:mod:`flexshaft.system.watchdog`) passes the signal on, gives the work
:data:`~flexshaft.system.watchdog.GRACE_S` to stop by itself, then kills it and removes its temporary files.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time

import pytest

from flexshaft.system.watchdog import GRACE_S, Terminated, is_stop, received, stopping
from tests.conftest import EXAMPLES, gmsh_loads, solid_shaft_model

pytestmark = pytest.mark.skipif(
    not hasattr(os, "fork"), reason="the watchdog runs the work in a forked child"
)

# A chain of 5 001 DOFs: `--modes 2000` is more than a third of them, so the modes come from one dense
# LAPACK eigh of order 5 001 - about 40 s on one core, in one native call.
DENSE = """
[[chain]]
name = "motor"
type = "rigid"
inertia = 58.1
[[chain]]
name = "shaft"
type = "shaft"
stiffness = 3e5
inertia = 0.44
elements = 4999
[[chain]]
name = "generator"
type = "rigid"
inertia = 6.67
"""
# What "within seconds" allows after the signal: the grace, then the kill, the temporary file's removal
# and the interpreter's exit, each waiting for a core on a loaded machine. 1.5 s was too little there:
# with both cores oversubscribed (two test workers, two BLAS threads each) the stuck-write case took
# longer in 1 of 3 full runs and in most runs beside a second suite.
PROMPT_S = GRACE_S + 4.0


def _children(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as fh:
            return [int(p) for p in fh.read().split()]
    except OSError:
        return []


def _gone(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] == "Z"  # a zombie has ended
    except OSError:
        return True


@pytest.fixture
def dense_model(tmp_path):
    model = tmp_path / "dense.toml"
    model.write_text(DENSE)
    return model


def _start(argv, cwd):
    return subprocess.Popen(
        [sys.executable, "-m", "flexshaft", *argv],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "FLEXSHAFT_WATCHDOG": "1"},
    )


@pytest.mark.slow  # waits 4 s to be inside the eigen-solve: 6 s
def test_sigterm_ends_a_long_native_solve_within_seconds(tmp_path, dense_model):
    out = tmp_path / "modes.txt"
    proc = _start(["modes", str(dense_model), "--modes", "2000", "--no-mesh-check", "-o", str(out)], tmp_path)
    try:
        time.sleep(4.0)  # loaded and assembled in about a second: inside the eigen-solve now
        assert proc.poll() is None, proc.communicate()
        sent = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
        took = time.monotonic() - sent
    finally:
        proc.kill()
    assert proc.returncode == 143, err
    assert err == "flexshaft: terminated\n"
    assert took < PROMPT_S, f"{took:.1f} s after SIGTERM"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dense.toml"]  # no output, no temporary file


STUCK_WRITER = """
import os, signal, sys, time
# A terminal delivers Ctrl-C; a test started in the background inherits SIGINT ignored: give the
# command Python's own handler, as an interactive run has.
signal.signal(signal.SIGINT, signal.default_int_handler)
real = os.replace
def stuck(*args):
    # The temporary file is written and not yet in place; the work now turns as deaf to signals as a
    # native call is.
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    print("ready", flush=True)
    time.sleep(60)
    real(*args)
os.replace = stuck
sys.argv = ["flexshaft", *sys.argv[1:]]
from flexshaft.cli import main
sys.exit(main())
"""


@pytest.mark.parametrize(
    "sig, code, line", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")]
)
def test_a_stuck_write_is_killed_and_its_temporary_file_removed(tmp_path, sig, code, line):
    target = tmp_path / "modes.txt"
    target.write_text("previous")
    model = str(EXAMPLES / "customer1.toml")
    proc = subprocess.Popen(
        [sys.executable, "-c", STUCK_WRITER, "modes", model, "-o", str(target), "--force"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "FLEXSHAFT_WATCHDOG": "1"},
    )
    try:
        assert proc.stdout.readline().strip() == "ready"
        assert list(tmp_path.glob(".modes.txt.*.tmp"))  # the write is in flight
        sent = time.monotonic()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=30)
        took = time.monotonic() - sent
    finally:
        proc.kill()
    assert proc.returncode == code and err == f"flexshaft: {line}\n", err
    assert GRACE_S - 0.5 < took < PROMPT_S  # it waited for the work to stop by itself, then killed it
    assert target.read_text() == "previous"
    assert [p.name for p in tmp_path.iterdir()] == ["modes.txt"]


@pytest.mark.skipif(
    not os.path.exists(f"/proc/{os.getpid()}/task/{os.getpid()}/children"),
    reason="needs /proc's children lists",
)
def test_the_work_dies_with_the_command(tmp_path, dense_model):
    # `kill -9` of the command cannot be passed on: the kernel ends the work (PR_SET_PDEATHSIG).
    proc = _start(["modes", str(dense_model), "--modes", "2000", "--no-mesh-check"], tmp_path)
    try:
        deadline = time.monotonic() + 10
        while not (work := _children(proc.pid)) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(work) == 1, work
        proc.kill()
        proc.wait(timeout=10)
        deadline = time.monotonic() + 3
        while not _gone(work[0]) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _gone(work[0])
    finally:
        proc.kill()


def _deliver(sig):
    os.kill(os.getpid(), sig)
    for _ in range(200):  # the handler runs at the next bytecode
        time.sleep(0.005)


def test_in_the_work_a_signal_raises_once_and_the_handlers_come_back():
    before = signal.getsignal(signal.SIGTERM)
    with stopping():
        with pytest.raises(Terminated) as stop:
            _deliver(signal.SIGTERM)
        assert received() == signal.SIGTERM and is_stop(stop.value)
        _deliver(signal.SIGTERM)  # a second one (Ctrl-C reaches every process of a job) is ignored
        assert not is_stop(ValueError("the part code's own error"))
    assert signal.getsignal(signal.SIGTERM) is before
    with stopping():
        assert received() is None  # each command starts afresh


def test_the_writer_tells_of_its_temporary_file_while_it_is_there(tmp_path, monkeypatch):
    from flexshaft.system import atomic

    monkeypatch.setattr(atomic, "_REPORT", [])  # only this test's listener
    seen = []
    atomic.report_temporaries(lambda live, path: seen.append((live, path, os.path.exists(path))))
    atomic.atomic_write_text(tmp_path / "x.txt", "x")
    (born, path, there), (gone, same, left) = seen
    assert (born, there) == (True, True) and (gone, left) == (False, False) and same == path
    assert os.path.dirname(path) == str(tmp_path) and not atomic.in_flight()


MESHING = solid_shaft_model("0.2", "8 mm")
# Ctrl-C at a terminal: the signal goes to the command's whole process group (the watchdog, the work
# and the work's gmsh child); a background test inherits SIGINT ignored, so the command gets Python's
# own handler first, as an interactive run has.
INTERACTIVE = """
import signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.argv = ["flexshaft", *sys.argv[1:]]
from flexshaft.cli import main
sys.exit(main())
"""


@pytest.mark.skipif(not gmsh_loads(), reason="the solid extra (gmsh) is not installed")
@pytest.mark.skipif(
    not os.path.exists(f"/proc/{os.getpid()}/task/{os.getpid()}/children"),
    reason="needs /proc's children lists",
)
@pytest.mark.slow  # builds the part and meshes ~800 000 DOFs until the signal: ~10 s
@pytest.mark.parametrize(
    "sig, code, line", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")]
)
def test_a_signal_to_the_process_group_ends_meshing_within_seconds(tmp_path, sig, code, line):
    model = tmp_path / "solid.toml"
    model.write_text(MESHING)
    scratch = tmp_path / "tmp"  # the mesher's temporary BREP file goes here: it must not be left
    scratch.mkdir()
    env = {**os.environ, "FLEXSHAFT_WATCHDOG": "1", "FLEXSHAFT_CACHE_DIR": str(tmp_path / "cache")}
    proc = subprocess.Popen(
        [sys.executable, "-c", INTERACTIVE, "twist", str(model)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**env, "TMPDIR": str(scratch)},
        start_new_session=True,  # its own process group, as a terminal's job is
    )
    try:
        # the watchdog's work, and the work's gmsh child once the part is built and meshing starts
        deadline = time.monotonic() + 120
        mesher = []
        while not mesher and time.monotonic() < deadline and proc.poll() is None:
            mesher = [c for w in _children(proc.pid) for c in _children(w)]
            time.sleep(0.05)
        assert len(mesher) == 1, proc.communicate()
        time.sleep(1.0)  # inside gmsh's C++ meshing now (its estimate and import take well under 1 s)
        assert proc.poll() is None, proc.communicate()
        sent = time.monotonic()
        os.killpg(proc.pid, sig)
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - sent
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert proc.returncode == code and err == f"flexshaft: {line}\n", err
    assert took < 10.0, f"{took:.1f} s after the signal"  # the bound
    deadline = time.monotonic() + 3
    while not _gone(mesher[0]) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _gone(mesher[0])
    assert list(scratch.iterdir()) == []
