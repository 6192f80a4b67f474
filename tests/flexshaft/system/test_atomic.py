"""Safe writes: the umask, nothing but a regular file replaced, no temp file left, kills included."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys

import pytest

import flexshaft as fs
from flexshaft.system.atomic import atomic_write_text
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
        "reduce",
        str(EXAMPLES / "customer1_flex.toml"),
        "--part",
        "part 1",
        "-o",
        str(out),
        "--force",
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


# --- output folders (a report): new, empty or flexshaft's own; never a link, /, a home or a foreign one -----


def _tree(folder) -> dict:
    """Every path under ``folder`` with its content (links as their target): to show nothing changed."""
    return {
        p.relative_to(folder): (
            f"-> {os.readlink(p)}" if p.is_symlink() else p.read_bytes() if p.is_file() else "dir"
        )
        for p in sorted(folder.rglob("*"))
    }


def test_a_new_folder_is_made_and_marked_and_an_empty_one_too(tmp_path):
    from flexshaft.system.atomic import OUTPUT_MARKER, check_output_folder, prepare_output_folder

    new = tmp_path / "a" / "report"
    assert check_output_folder(new) == new and not (tmp_path / "a").exists()  # a check creates nothing
    assert prepare_output_folder(new, writer="flexshaft report") == new
    assert "flexshaft report" in (new / OUTPUT_MARKER).read_text()
    empty = tmp_path / "empty"
    empty.mkdir()
    prepare_output_folder(empty)
    assert [p.name for p in empty.iterdir()] == [OUTPUT_MARKER]
    # Marked: the folder is flexshaft's; the marker is kept as it is, the user's other files too.
    (new / OUTPUT_MARKER).write_text("written by an older flexshaft\n")
    (new / "notes.txt").write_text("mine")
    before = _tree(new)
    prepare_output_folder(new, files=("index.html",))
    assert _tree(new) == before


def test_a_folder_killed_while_being_marked_is_still_empty_and_a_marker_is_never_replaced(tmp_path):
    from flexshaft.system.atomic import OUTPUT_MARKER, prepare_output_folder

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()  # its pid is free: the writer of a temporary file with it in the name is gone
    d = tmp_path / "r"
    d.mkdir()
    (d / f".{OUTPUT_MARKER}.{dead.pid}.x1.tmp").write_text("written by flexsh")  # the kill's leftover
    assert prepare_output_folder(d, writer="flexshaft study", note='study: "/s.toml"') == d
    assert [p.name for p in d.iterdir()] == [OUTPUT_MARKER]  # the leftover went with the marking
    assert (d / OUTPUT_MARKER).read_text().splitlines()[1] == 'study: "/s.toml"'
    prepare_output_folder(d, writer="flexshaft report", note="other")  # marked: the first marker stands
    assert "other" not in (d / OUTPUT_MARKER).read_text()
    # a temporary file of a live writer is someone's marking in progress: not an empty folder
    live = tmp_path / "live"
    live.mkdir()
    (live / f".{OUTPUT_MARKER}.{os.getpid()}.x1.tmp").write_text("")
    with pytest.raises(fs.ModelError, match="is not empty"):
        prepare_output_folder(live)


def test_force_replaces_only_flexshafts_own_regular_files_in_a_marked_folder(tmp_path):
    from flexshaft.system.atomic import prepare_output_folder

    d = prepare_output_folder(tmp_path / "r")
    (d / "index.html").write_text("old")
    with pytest.raises(fs.ModelError, match="index.html'?: file exists; valid: .*--force"):
        prepare_output_folder(d, files=("index.html", "modes.json"))
    assert prepare_output_folder(d, force=True, files=("index.html", "modes.json")) == d
    (d / "index.html").unlink()
    (d / "index.html").symlink_to(tmp_path / "elsewhere.html")
    with pytest.raises(fs.ModelError, match="is not a regular file"):
        prepare_output_folder(d, force=True, files=("index.html",))


@pytest.mark.parametrize("force", [False, True])
def test_a_foreign_folder_a_link_or_a_file_is_refused_and_untouched(tmp_path, force):
    from flexshaft.system.atomic import prepare_output_folder

    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "index.html").write_text("the user's page")
    link = tmp_path / "link"
    link.symlink_to(foreign, target_is_directory=True)
    empty = tmp_path / "empty"
    empty.mkdir()
    link_to_empty = tmp_path / "link2"
    link_to_empty.symlink_to(empty, target_is_directory=True)
    dangling = tmp_path / "dangling"
    dangling.symlink_to(tmp_path / "nowhere")
    a_file = tmp_path / "a.txt"
    a_file.write_text("x")
    before = _tree(tmp_path)
    cases = {
        foreign: "not empty and flexshaft did not write it",
        link: "symbolic link",
        f"{link}/": "symbolic link",  # a trailing slash is the same link
        link_to_empty: "symbolic link",  # even an empty folder behind a link stays untouched
        dangling: "symbolic link",
        a_file: "is not a folder",
    }
    for path, says in cases.items():
        with pytest.raises(fs.ModelError, match=says) as err:
            prepare_output_folder(path, force=force, files=("index.html",), option="-o")
        assert str(err.value).startswith("-o = ") and "valid: " in str(err.value)
    assert _tree(tmp_path) == before


def test_root_home_folders_and_an_unexpanded_tilde_are_refused(tmp_path, monkeypatch):
    import pwd
    from pathlib import Path
    from types import SimpleNamespace

    from flexshaft.system.atomic import check_output_folder

    with pytest.raises(fs.ModelError, match="is the root folder"):
        check_output_folder("/", force=True)
    with pytest.raises(fs.ModelError, match="names no folder"):
        check_output_folder("", force=True)  # Path("") would be the current folder
    with pytest.raises(fs.ModelError, match="is a home folder"):
        check_output_folder(Path.home(), force=True)
    # Any home in the password database, an empty one too, and this user's $HOME.
    other = tmp_path / "other_user"
    other.mkdir()
    real = pwd.getpwall()
    monkeypatch.setattr(pwd, "getpwall", lambda: [*real, SimpleNamespace(pw_dir=str(other))])
    with pytest.raises(fs.ModelError, match="is a home folder"):
        check_output_folder(other)
    mine = tmp_path / "me"
    mine.mkdir()
    monkeypatch.setenv("HOME", str(mine))
    with pytest.raises(fs.ModelError, match="is a home folder"):
        check_output_folder(tmp_path / "x" / ".." / "me")  # the resolved path is compared
    assert check_output_folder(mine / "reports") == mine / "reports"  # a new folder inside a home is fine
    for tilde in ("~", "~/reports", "~root"):
        with pytest.raises(fs.ModelError, match="only the shell expands"):
            check_output_folder(tilde)
    assert not Path("~").exists()


def test_a_folder_holding_an_input_is_refused_even_when_marked(tmp_path):
    from flexshaft.system.atomic import prepare_output_folder

    d = prepare_output_folder(tmp_path / "r")
    (d / "deep").mkdir()
    model = d / "deep" / "m.toml"
    model.write_text("x")
    for given in (model, tmp_path / "r" / "deep" / ".." / "deep" / "m.toml"):
        with pytest.raises(fs.ModelError, match="holds the input file"):
            prepare_output_folder(d, force=True, inputs=[given])
    assert prepare_output_folder(d, force=True, inputs=[tmp_path / "m.toml"]) == d  # beside it: fine
    # Every file the command has read counts too (a model's STEP part or section table), named or not.
    from flexshaft.system.inputs import SECTIONS, read_bytes, recording

    with recording():
        read_bytes(model, SECTIONS)
        with pytest.raises(fs.ModelError, match="holds the input file"):
            prepare_output_folder(d, force=True)
