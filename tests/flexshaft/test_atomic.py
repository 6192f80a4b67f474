"""Safe writes: the umask, nothing but a regular file replaced, no temp file left, kills included."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys

import pytest

import flexshaft as fs
from flexshaft.atomic import atomic_write_text
from tests.conftest import EXAMPLES


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_a_written_file_honours_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        path = atomic_write_text(tmp_path / "out.txt", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask


def test_force_replaces_only_a_regular_file(tmp_path):
    target = tmp_path / "real.txt"
    target.write_text("keep")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for p in (link, fifo):
        with pytest.raises(fs.ModelError, match="is not a regular file, so it is not replaced"):
            atomic_write_text(p, "new", overwrite=True)
    assert target.read_text() == "keep" and link.is_symlink() and stat.S_ISFIFO(fifo.lstat().st_mode)
    atomic_write_text(target, "new", overwrite=True)
    assert target.read_text() == "new"


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_a_stale_temp_of_a_killed_writer_goes_with_the_next_write(tmp_path):
    stale = tmp_path / f".out.txt.{_dead_pid()}.abc123.tmp"
    stale.write_text("half")
    live = tmp_path / f".out.txt.{os.getpid()}.def456.tmp"  # a writer still running: left alone
    live.write_text("busy")
    atomic_write_text(tmp_path / "out.txt", "x")
    assert not stale.exists() and live.exists()


WRITER = """
import os, signal, sys, time
# A user's terminal delivers Ctrl-C; a test started in the background inherits SIGINT ignored, which
# the child would keep: give it Python's own handler, as an interactive run has.
signal.signal(signal.SIGINT, signal.default_int_handler)
real = os.replace
def slow(*a):
    print("ready", flush=True)
    time.sleep(60)
    real(*a)
os.replace = slow
from flexshaft.cli import main
sys.exit(main(sys.argv[1:]))
"""
COMMANDS = {
    "modes": lambda out: ["modes", str(EXAMPLES / "customer1.toml"), "-o", str(out), "--force"],
    "reduce": lambda out: [
        "reduce", str(EXAMPLES / "customer1_flex.toml"), "--part", "part 1", "-o", str(out), "--force"
    ],
}


@pytest.mark.parametrize(
    "command, name", [("modes", "modes.txt"), ("reduce", "part1.npz"), ("reduce", "p.op4")]
)
@pytest.mark.parametrize(
    "sig, code, temp_left",
    [(signal.SIGINT, 130, False), (signal.SIGTERM, 143, False), (signal.SIGKILL, -9, True)],
)
def test_a_write_killed_midway_leaves_the_previous_file(tmp_path, command, name, sig, code, temp_left):
    target = tmp_path / name
    target.write_text("previous")
    if name.endswith(".op4"):  # a pair: the sidecar is written first, and must survive too
        (tmp_path / (name + ".json")).write_text("previous sidecar")
    proc = subprocess.Popen(
        [sys.executable, "-c", WRITER, *COMMANDS[command](target)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline().strip() == "ready"  # the temp file is written, not yet in place
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == code
    assert target.read_text() == "previous"
    if name.endswith(".op4"):
        assert (tmp_path / (name + ".json")).read_text() == "previous sidecar"
    temps = list(tmp_path.glob(".*.tmp"))
    assert bool(temps) == temp_left
    if sig != signal.SIGKILL:
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    # The next write of the target (and of its sidecar) removes what a killed run left.
    atomic_write_text(target, "next", overwrite=True)
    if name.endswith(".op4"):
        atomic_write_text(tmp_path / (name + ".json"), "next", overwrite=True)
    assert target.read_text() == "next" and not list(tmp_path.glob(".*.tmp"))
