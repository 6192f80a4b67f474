"""Inputs that never end, and outputs over inputs (issue 20): devices, FIFOs, sockets and directories
named as input files are refused by name before any read; sparse 2 GB files by their size against the
ceiling of their kind; a signal file of one endless line after 1 MB of it; and an output that is one of
the command's inputs - itself, through a symbolic link or a hard link - is refused, --force or not."""

from __future__ import annotations

import os
import socket
import threading
from pathlib import Path

from tests.conftest import EXAMPLES
from tests.flexshaft.catalogue import Case

C1 = EXAMPLES / "customer1.toml"  # 5 DOFs, solved in milliseconds
FLEX = EXAMPLES / "customer1_flex.toml"  # part 1 is a shaft given by segments: reducible
SIGNAL_HEADER = "time [s],torque [N·m]\n"
TARGETS = (
    '[[target]]\nmode = 1\nfrequency_hz = 11.5\n[[parameter]]\nname = "part 3.stiffness"\npercent = 10\n'
)
TWO_GB = 2 << 30  # the sizes the issue tried: above every default ceiling but the signal file's


def _cad_model(part: str, unit: str = "") -> str:
    """Customer 1 with part 1 read from the part file ``part`` (a STEP or mesh file beside the model)."""
    text = C1.read_text()
    old = 'name = "part 1"\ntype = "shaft"\nstiffness = 307933.18\ninertia = 0.44\n'
    assert old in text, "customer1.toml changed: update the catalogue's CAD model"
    new = f'name = "part 1"\ntype = "cad"\ngeometry = "{part}"\nmaterial = "steel"\n{unit}'
    return text.replace(old, new)


def _signals(n: int = 2000) -> str:
    """A decaying 12 Hz torque sampled at 1 kHz: a valid signal file."""
    import math

    rows = (f"{k / 1000!r},{math.sin(2 * math.pi * 12 * k / 1000) * math.exp(-k / 1000)!r}" for k in range(n))
    return SIGNAL_HEADER + "\n".join(rows) + "\n"


def _sparse(path: Path, size: int = TWO_GB) -> None:
    with open(path, "wb") as fh:
        fh.truncate(size)  # nothing of it on disk


def _socket(path: Path) -> None:
    """A UNIX socket file at ``path`` (the socket closed: the file stays).

    Bound from inside its folder: a socket's address is limited to 107 bytes, a test's temporary
    folder may be longer. The cwd comes back at once; the slow step runs cases in threads, but only
    this moment changes it, under a lock.
    """
    import os

    with _CWD:
        here = os.getcwd()
        os.chdir(path.parent)
        try:
            s = socket.socket(socket.AF_UNIX)
            try:
                s.bind(path.name)
            finally:
                s.close()
        finally:
            os.chdir(here)


_CWD = threading.Lock()


# --- what is not a regular file, as each kind of input --------------------------------------------


def _device(device: str):
    def setup(d: Path) -> list[str]:
        return ["modes", device]

    return setup


def _fifo_as(name: str, argv, before=None):
    """A FIFO named ``name``; ``before(d)`` writes the other files the command needs."""

    def setup(d: Path) -> list[str]:
        if before is not None:
            before(d)
        os.mkfifo(d / name)
        return list(argv)

    return setup


def _copy_c1(d: Path) -> None:
    (d / "m.toml").write_text(C1.read_text())


def _step_model(d: Path) -> None:
    (d / "m.toml").write_text(_cad_model("part.step"))


def _directory_as_model(d: Path) -> list[str]:
    (d / "m.toml").mkdir()
    return ["modes", "m.toml"]


def _socket_as_model(d: Path) -> list[str]:
    _socket(d / "m.toml")
    return ["modes", "m.toml"]


# --- sparse 2 GB files -----------------------------------------------------------------------------


def _sparse_model(d: Path) -> list[str]:
    _sparse(d / "m.toml")
    return ["modes", "m.toml"]


def _sparse_signals(size: int):
    def setup(d: Path) -> list[str]:
        _sparse(d / "s.csv", size)
        return ["spectrum", "s.csv", "--column", "torque"]

    return setup


def _sparse_step(d: Path) -> list[str]:
    _step_model(d)
    _sparse(d / "part.step")
    return ["modes", "m.toml"]


def _sparse_step_no_cache(d: Path) -> list[str]:
    _step_model(d)
    _sparse(d / "part.step")
    return ["modes", "m.toml", "--no-cache"]  # past the cache's hash: OCCT's reader is handed no such path


def _sparse_stl(d: Path) -> list[str]:
    (d / "m.toml").write_text(_cad_model("part.stl", 'unit = "mm"\n'))
    _sparse(d / "part.stl")
    return ["modes", "m.toml"]


def _sparse_stl_sections(d: Path) -> list[str]:
    _sparse(d / "part.stl")
    return ["sections", "part.stl", "--unit", "mm"]


def _endless_first_line(d: Path) -> list[str]:
    """A signal file whose first line is 64 MB without a line feed (written, not sparse)."""
    with open(d / "s.csv", "wb") as fh:
        fh.write(b"time [s],torque [N\xc2\xb7m]")
        fh.write(b",0" * (32 << 20))
    return ["spectrum", "s.csv", "--column", "torque"]


# --- outputs over inputs -----------------------------------------------------------------------------


def _over_the_model(target: str, link: str | None = None, force: bool = True):
    """``modes m.txt -o TARGET``: the model file itself, or a symbolic or hard link to it (a model file
    may have any name; .txt is a name -o accepts for the table)."""

    def setup(d: Path) -> list[str]:
        (d / "m.txt").write_text(C1.read_text())
        if link == "symbolic":
            (d / target).symlink_to("m.txt")
        elif link == "hard":
            os.link(d / "m.txt", d / target)
        return ["modes", "m.txt", "-o", target] + (["--force"] if force else [])

    return setup


def _modes_over_toml(d: Path) -> list[str]:
    """The issue's command (refused, whichever check comes first: -o's suffix or the input)."""
    _copy_c1(d)
    return ["modes", "m.toml", "-o", "m.toml", "--force"]


def _spectrum_over(name: str):
    def setup(d: Path) -> list[str]:
        (d / name).write_text(_signals())
        return ["spectrum", name, "--column", "torque", "-o", name, "--force"]

    return setup


def _calibrate_over_targets(d: Path) -> list[str]:
    (d / "t.toml").write_text(TARGETS)
    return ["calibrate", str(C1), "--targets", "t.toml", "-o", "t.toml", "--force"]


def _calibrate_over_model(d: Path) -> list[str]:
    _copy_c1(d)
    (d / "t.toml").write_text(TARGETS)
    return ["calibrate", "m.toml", "--targets", "t.toml", "-o", "m.toml", "--force"]


def _simulate_over_series(d: Path) -> list[str]:
    _copy_c1(d)
    (d / "s.csv").write_text(_signals())
    return [
        "simulate", "m.toml", "--scenario", "csv", "--series", "s.csv", "--column", "torque",
        "--measure", "speed:motor", "-o", "s.csv", "--force",
    ]  # fmt: skip


def _reduce_over_model(d: Path) -> list[str]:
    (d / "m.json").write_text(FLEX.read_text())  # a model file named as a JSON body export
    return ["reduce", "m.json", "--part", "part 1", "-o", "m.json", "--force"]


def _reduce_sidecar_over_model(d: Path) -> list[str]:
    (d / "b.pch.json").write_text(FLEX.read_text())  # the punch's sidecar would be the model
    return ["reduce", "b.pch.json", "--part", "part 1", "-o", "b.pch", "--force"]


NEVER_REPLACES = "an output never replaces an input"

CASES = {
    # devices and FIFOs, refused by name before any read (they never end, or block forever)
    "/dev/zero as model file": Case(
        _device("/dev/zero"), says=("/dev/zero", "character device"), budget_s=15
    ),
    "/dev/urandom as model file": Case(
        _device("/dev/urandom"), says=("/dev/urandom", "character device"), budget_s=15
    ),
    "FIFO as model file": Case(_fifo_as("m.toml", ["modes", "m.toml"]), says=("m.toml", "FIFO"), budget_s=15),
    "FIFO as signal CSV for spectrum": Case(
        _fifo_as("s.csv", ["spectrum", "s.csv", "--column", "torque"]), says=("s.csv", "FIFO"), budget_s=15
    ),
    "FIFO as --targets for calibrate": Case(
        _fifo_as("t.toml", ["calibrate", str(C1), "--targets", "t.toml"]),
        says=("t.toml", "FIFO"),
        budget_s=15,
    ),
    "FIFO as --series for simulate --scenario csv": Case(
        _fifo_as(
            "s.csv",
            [
                "simulate",
                "m.toml",
                "--scenario",
                "csv",
                "--series",
                "s.csv",
                "--column",
                "torque",
                "--measure",
                "speed:motor",
            ],
            _copy_c1,
        ),  # fmt: skip
        says=("s.csv", "FIFO"),
        budget_s=30,
    ),
    "FIFO as --model for spectrum": Case(
        _fifo_as(
            "m.toml",
            ["spectrum", "s.csv", "--column", "torque", "--model", "m.toml"],
            lambda d: (d / "s.csv").write_text(_signals()),
        ),
        says=("m.toml", "FIFO"),
        budget_s=15,
    ),
    "FIFO as a stage's model in a targets file": Case(
        _fifo_as(
            "stage.toml",
            ["calibrate", str(C1), "--targets", "t.toml"],
            lambda d: (d / "t.toml").write_text(
                '[[stage]]\nname = "one"\nmodel = "stage.toml"\n'
                + TARGETS.replace("[[target]]", "[[stage.target]]").replace(
                    "[[parameter]]", "[[stage.parameter]]"
                )
            ),
        ),
        says=("stage.toml", "FIFO"),
        budget_s=15,
    ),
    "FIFO as a STEP part named by a model": Case(
        _fifo_as("part.step", ["modes", "m.toml"], _step_model), says=("part.step", "FIFO"), budget_s=30
    ),
    "FIFO as a STEP part named by a model, no cache": Case(
        _fifo_as("part.step", ["modes", "m.toml", "--no-cache"], _step_model),
        says=("part.step", "FIFO"),
        budget_s=60,
    ),
    "FIFO as sections source (a part file)": Case(
        _fifo_as("part.step", ["sections", "part.step"]), says=("part.step", "FIFO"), budget_s=30
    ),
    "FIFO as sections source (a model file)": Case(
        _fifo_as("m.toml", ["sections", "m.toml"]), says=("m.toml", "FIFO"), budget_s=15
    ),
    "a directory as model file": Case(_directory_as_model, says=("m.toml", "is a directory"), budget_s=15),
    "a socket as model file": Case(_socket_as_model, says=("m.toml", "is a socket"), budget_s=15),
    # sparse 2 GB files: refused by their size against the ceiling of their kind
    "sparse 2 GB model file": Case(
        _sparse_model, says=("m.toml", "2048 MB", "8 MB ceiling", "FLEXSHAFT_MAX_FILE_MB"), budget_s=15
    ),
    "sparse 2 GB signal CSV (at the 2048 MB ceiling: one endless line of NULs)": Case(
        _sparse_signals(TWO_GB), says=("s.csv", "line 1 is longer than 1 MB"), budget_s=15
    ),
    "sparse signal CSV one byte above the 2048 MB ceiling": Case(
        _sparse_signals(TWO_GB + 1), says=("s.csv", "2048 MB ceiling", "FLEXSHAFT_MAX_FILE_MB"), budget_s=15
    ),
    "sparse 2 GB STEP part": Case(
        _sparse_step, says=("part.step", "2048 MB", "128 MB ceiling", "FLEXSHAFT_MAX_FILE_MB"), budget_s=30
    ),
    "sparse 2 GB STEP part, no cache": Case(
        _sparse_step_no_cache, says=("part.step", "2048 MB", "128 MB ceiling"), budget_s=60
    ),
    "sparse 2 GB STL part": Case(
        _sparse_stl, says=("part.stl", "2048 MB", "128 MB ceiling", "FLEXSHAFT_MAX_FILE_MB"), budget_s=30
    ),
    "sparse 2 GB STL as sections source": Case(
        _sparse_stl_sections, says=("part.stl", "2048 MB", "128 MB ceiling"), budget_s=30
    ),
    "signal CSV whose first line is 64 MB without a line feed": Case(
        _endless_first_line, says=("s.csv", "line 1 is longer than 1 MB"), budget_s=15
    ),
    # outputs over inputs: exit 2 with or without --force, the input unchanged
    "modes m.toml -o m.toml --force": Case(_modes_over_toml, says=("m.toml",), budget_s=15),
    "modes m.txt -o m.txt --force (the model itself)": Case(
        _over_the_model("m.txt"), says=("'m.txt'", NEVER_REPLACES, "--force"), budget_s=15
    ),
    "modes m.txt -o m.txt (no --force)": Case(
        _over_the_model("m.txt", force=False), says=("'m.txt'", NEVER_REPLACES), budget_s=15
    ),
    "modes -o through a symbolic link to the model": Case(
        _over_the_model("link.txt", "symbolic"), says=("link.txt", "'m.txt'", NEVER_REPLACES), budget_s=15
    ),
    "modes -o through a hard link to the model": Case(
        _over_the_model("hard.txt", "hard"), says=("hard.txt", "'m.txt'", NEVER_REPLACES), budget_s=15
    ),
    "spectrum s.csv -o s.csv --force": Case(_spectrum_over("s.csv"), says=("s.csv",), budget_s=15),
    "spectrum s.txt -o s.txt --force (a signal file named as a table)": Case(
        _spectrum_over("s.txt"), says=("'s.txt'", NEVER_REPLACES), budget_s=15
    ),
    "calibrate --targets t.toml -o t.toml --force": Case(
        _calibrate_over_targets, says=("'t.toml'", NEVER_REPLACES), budget_s=30
    ),
    "calibrate m.toml -o m.toml --force": Case(
        _calibrate_over_model, says=("'m.toml'", NEVER_REPLACES), budget_s=30
    ),
    "simulate --scenario csv --series s.csv -o s.csv --force": Case(
        _simulate_over_series, says=("'s.csv'", NEVER_REPLACES), budget_s=30
    ),
    "reduce m.json -o m.json --force (over the model)": Case(
        _reduce_over_model, says=("'m.json'", NEVER_REPLACES), budget_s=30
    ),
    "reduce -o b.pch --force, its sidecar b.pch.json the model": Case(
        _reduce_sidecar_over_model, says=("'b.pch.json'", NEVER_REPLACES), budget_s=30
    ),
}
