"""An output the system refuses - a full disk, a quota, a file too large, a read-only folder - is one
line naming the file and the system's reason, exit 2, and nothing half-written (issue 33).

References: the kernel itself (a 64 KiB tmpfs filled to its last page gives ENOSPC, one mounted
read-only gives EROFS), ``errno``'s names for the codes, and what is left on the disk afterwards.
EDQUOT and EFBIG, which a test cannot provoke without a quota or a process-wide file-size limit, are
raised in place of the writer's ``fsync``.
"""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from flexshaft.cli import main
from flexshaft.system.atomic import OutputError, atomic_write_text
from tests.conftest import EXAMPLES

PAGE = 4096  # a tmpfs's block: files take whole pages of its size


def _mount(where: Path, options: str) -> None:
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    where.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)], capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"mount is not permitted here: {done.stderr.decode(errors='replace').strip()}")


def _fill(where: Path) -> None:
    """Fill the tmpfs at ``where`` to its last byte (``filler``): every write into it fails with ENOSPC."""
    fd = os.open(where / "filler", os.O_WRONLY | os.O_CREAT)
    try:
        while True:
            os.write(fd, b"\0" * PAGE)
    except OSError as err:
        assert err.errno == errno.ENOSPC
    finally:
        os.close(fd)


@pytest.fixture
def full(tmp_path):
    """A 64 KiB tmpfs, full."""
    where = tmp_path / "disk"
    _mount(where, "size=64k")
    _fill(where)
    yield where
    subprocess.run(["umount", "-l", str(where)], check=False)


@pytest.fixture
def read_only(tmp_path):
    where = tmp_path / "ro"
    _mount(where, "size=64k,ro")
    yield where
    subprocess.run(["umount", "-l", str(where)], check=False)


C1 = str(EXAMPLES / "customer1.toml")
COMMANDS = {
    "report": lambda d: ["report", C1, "-o", str(d / "rep")],
    "simulate": lambda d: [
        "simulate",
        C1,
        "--scenario",
        "step",
        "--measure",
        "speed:generator",
        "--duration",
        "1",
        "-o",
        str(d / "run.csv"),
    ],
    "reduce": lambda d: [
        "reduce",
        str(EXAMPLES / "customer1_flex.toml"),
        "--part",
        "part 1",
        "-o",
        str(d / "part1.npz"),
    ],
    "modes": lambda d: ["modes", C1, "-o", str(d / "modes.txt")],
    "study": lambda d: ["study", str(_study(d.parent)), "-o", str(d / "study")],
}


def _study(folder: Path, export: bool = True) -> Path:
    """A study of the flexible-body bench: its set-up, modes and one part exported (a file per stage)."""
    path = folder / "study.toml"
    text = f'[[setup]]\nname = "c1"\nmodel = "{EXAMPLES / "customer1_flex.toml"}"\n[views]\nsetups = []\n'
    path.write_text(text + ('[[export]]\npart = "part 1"\n' if export else ""))
    return path


def _one_line(capsys) -> str:
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert "unexpected" not in lines[0] and "defect" not in lines[0] and "Traceback" not in lines[0]
    return lines[0]


def _left(d: Path) -> set[str]:
    return {str(p.relative_to(d)) for p in d.rglob("*")}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_full_disk_is_one_line_naming_the_output_and_nothing_is_left(full, command, capsys):
    assert main(COMMANDS[command](full)) == 2
    line = _one_line(capsys)
    assert f"'{full}/" in line and "No space left on device (ENOSPC)" in line, line
    left = _left(full) - {"filler"}
    if command == "study":  # its folder (made and marked before the first stage): empty, no temporary
        assert left <= {"study"}, left
    else:
        assert not left, left  # no temporary file, no report folder without its page


@pytest.mark.parametrize("command", ["report", "simulate", "reduce", "study"])
def test_a_read_only_folder_is_one_line_naming_the_output(read_only, command, capsys):
    assert main(COMMANDS[command](read_only)) == 2
    line = _one_line(capsys)
    assert f"'{read_only}/" in line and "Read-only file system (EROFS)" in line, line


def test_stdout_to_a_full_disk_is_one_line_too(full):
    # `flexshaft modes --json > file` on a full disk: print() fails on its flush; one line, exit 2, and
    # no second complaint from the interpreter's own flush at exit
    with open(full / "modes.json", "w") as out:
        done = subprocess.run(
            [sys.executable, "-m", "flexshaft", "modes", C1, "--json"],
            stdout=out,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
        )
    assert done.returncode == 2, done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert line == (
        "flexshaft: error: output = '<standard output>': cannot be written: No space left on device "
        "(ENOSPC); valid: free space on that disk, or a path on another"
    )


@pytest.mark.parametrize(
    "code, reason", [(errno.EDQUOT, "Disk quota exceeded (EDQUOT)"), (errno.EFBIG, "File too large (EFBIG)")]
)
def test_a_quota_or_a_size_limit_keeps_the_previous_file(tmp_path, monkeypatch, code, reason):
    target = tmp_path / "out.txt"
    target.write_text("previous")

    def refuse(fd):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(os, "fsync", refuse)
    with pytest.raises(OutputError) as caught:
        atomic_write_text(target, "new", overwrite=True)
    assert str(caught.value).startswith(f"output = '{target}': cannot be written: {reason}")
    assert caught.value.located(file="model.toml") is caught.value  # the output is the place, not the model
    assert target.read_text() == "previous" and not list(tmp_path.glob(".*.tmp"))


def test_a_study_stage_meeting_a_full_disk_fails_by_name(tmp_path, capsys):
    # The case: the folder takes the study's files, but exports/ is on a disk that is full - the
    # export stage fails with the file and the reason (it was "unexpected OSError ... a flexshaft
    # defect"), the other stages run, and the study exits 2
    out = tmp_path / "study"
    assert main(["study", str(_study(tmp_path, export=False)), "-o", str(out)]) == 0  # the study's folder
    capsys.readouterr()
    _mount(out / "exports", "size=64k")
    try:
        _fill(out / "exports")
        assert main(["study", str(_study(tmp_path)), "-o", str(out)]) == 2
        line = _one_line(capsys)
        assert line.startswith("flexshaft: error: study stage export 'part 1' of 'c1': output = ")
        assert f"'{out}/exports/c1/part-1.npz'" in line and "No space left on device (ENOSPC)" in line, line
        assert (out / "index.html").is_file()  # the report of what ran, the failure in it
        assert not [p for p in (out / "exports").rglob("*") if p.is_file() and p.name != "filler"]
    finally:
        subprocess.run(["umount", "-l", str(out / "exports")], check=False)
