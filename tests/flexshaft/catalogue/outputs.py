"""Outputs: a report folder is new, empty or flexshaft's own - never a link, /, a home folder or a
foreign folder - and every -o, --plot and --view has a suffix that says what it gets."""

from __future__ import annotations

from pathlib import Path

from flexshaft.cli import REPORT_FILES
from flexshaft.errors import ModelError
from flexshaft.system.atomic import check_output_folder, prepare_output_folder
from tests.conftest import EXAMPLES
from tests.flexshaft.catalogue import Case

C1 = str(EXAMPLES / "customer1.toml")
FRF = ["frf", C1, "--at", "motor", "--measure", "torque:part 3"]


def _refused_before_the_case(path: str) -> None:
    """The case never runs unless the folder check refuses ``path``: a broken check must not let a
    report be written into / or a home folder (the CLI checks before loading the model, and
    write_report again before drawing)."""
    try:
        check_output_folder(path, force=True, files=REPORT_FILES, option="-o")
    except ModelError:
        return
    raise AssertionError(f"{path} is not refused by check_output_folder: the case is not run")


def _linked_folder(d: Path) -> None:
    """d/real holds a user's file; d/link points at it."""
    (d / "real").mkdir()
    (d / "real" / "keep.txt").write_text("the user's file\n")
    (d / "link").symlink_to(d / "real", target_is_directory=True)


def _foreign(d: Path) -> None:
    """A folder of the user's: not empty, no marker."""
    (d / "results").mkdir()
    (d / "results" / "index.html").write_text("<p>the user's own page</p>\n")


def report_through_link(d: Path) -> list[str]:
    _linked_folder(d)
    return ["report", C1, "-o", "link", "--force"]


def demo_through_link(d: Path) -> list[str]:
    _linked_folder(d)
    return ["demo", "-o", "link/", "--force"]


def report_into_root(d: Path) -> list[str]:
    _refused_before_the_case("/")
    return ["report", C1, "-o", "/", "--force"]


def demo_into_root(d: Path) -> list[str]:
    _refused_before_the_case("/")
    return ["demo", "-o", "/"]


def report_into_home(d: Path) -> list[str]:
    home = str(Path.home())  # what the shell makes of ~
    _refused_before_the_case(home)
    return ["report", C1, "-o", home, "--force"]


def report_into_foreign(d: Path) -> list[str]:
    _foreign(d)
    return ["report", C1, "-o", "results", "--force"]


def demo_into_foreign(d: Path) -> list[str]:
    _foreign(d)
    return ["demo", "-o", "results/", "--force"]


def report_into_folder_with_model(d: Path) -> list[str]:
    # flexshaft's own folder, but the model lives in it: the output folder never holds an input
    prepare_output_folder(d / "r", writer="flexshaft report")
    (d / "r" / "m.toml").write_bytes(Path(C1).read_bytes())
    return ["report", "r/m.toml", "-o", "r", "--force"]


def report_again_without_force(d: Path) -> list[str]:
    prepare_output_folder(d / "r", writer="flexshaft report")
    (d / "r" / "index.html").write_text("<p>the previous report</p>\n")
    return ["report", C1, "-o", "r"]


def report_again_with_force(d: Path) -> list[str]:
    # A folder as a report leaves it (marker), with a note of the user's beside: --force writes the report
    # and leaves the note (and the marker) as they were. (Replacing an earlier report's files is
    # tests/flexshaft/views/test_report.py's: a changed file is what this catalogue forbids.)
    prepare_output_folder(d / "r", writer="flexshaft report")
    (d / "r" / "notes.txt").write_text("seen on the test bench\n")
    return ["report", C1, "-o", "r", "--force"]


def _signals(d: Path) -> str:
    rows = ["time [s],torque [N·m]"] + [f"{k / 1000:.3f},{(k % 7) - 3}" for k in range(256)]
    (d / "s.csv").write_text("\n".join(rows) + "\n")
    return "s.csv"


def _plot_case(argv) -> Case:
    return Case(lambda d: [*argv(d), "--plot", "y.txt"], says=("--plot", "'y.txt'", ".png", ".svg", ".pdf"))


CASES = {
    "report -o LINK --force (a link to a folder)": Case(report_through_link, says=("-o", "'link'", "link")),
    "demo -o LINK/ --force": Case(demo_through_link, says=("-o", "'link/'", "link")),
    "report -o / --force": Case(report_into_root, says=("-o", "'/'", "root folder")),
    "demo -o /": Case(demo_into_root, says=("-o", "'/'", "root folder")),
    "report -o HOME --force": Case(report_into_home, says=("-o", "home folder")),
    "report -o '~' (not expanded)": Case(lambda d: ["report", C1, "-o", "~", "--force"], says=("-o", "'~'")),
    "report --force into a foreign folder": Case(report_into_foreign, says=("-o", ".flexshaft-output")),
    "demo -o DIR/ --force into a foreign folder": Case(demo_into_foreign, says=("-o", ".flexshaft-output")),
    "report into its folder holding the model": Case(report_into_folder_with_model, says=("-o", "input")),
    "report into its own folder without --force": Case(report_again_without_force, says=("-o", "--force")),
    "report into its own folder with --force": Case(report_again_with_force, exit=0, budget_s=60.0),
    "report -o r.html": Case(lambda d: ["report", C1, "-o", "r.html"], says=("-o", "'r.html'", "index.html")),
    "frf -o y.npz (a real npz)": Case(lambda d: [*FRF, "-o", "y.npz"], exit=0),
    "frf -o y.dat": Case(lambda d: [*FRF, "-o", "y.dat"], says=("-o", "'y.dat'", ".npz", ".csv")),
    "frf --plot y.txt": _plot_case(lambda d: FRF),
    "twist --plot y.txt": _plot_case(lambda d: ["twist", C1]),
    "simulate --plot y.txt": _plot_case(
        lambda d: ["simulate", C1, "--scenario", "step", "--measure", "speed:motor"]
    ),
    "campbell --plot y.txt": _plot_case(lambda d: ["campbell", C1]),
    "spectrum --plot y.txt": _plot_case(lambda d: ["spectrum", _signals(d), "--column", "torque"]),
    "sensitivity --plot y.txt": _plot_case(lambda d: ["sensitivity", C1]),
    "twist --view y.svg (3D: PNG only)": Case(
        lambda d: ["twist", C1, "--view", "y.svg"], says=("--view", ".png")
    ),
    "view -o x.txt": Case(
        lambda d: ["view", C1, "--mode", "2", "-o", "x.txt"], says=("-o", "'x.txt'", ".gif")
    ),
    "modes -o m.npz (a table)": Case(lambda d: ["modes", C1, "-o", "m.npz"], says=("-o", "'m.npz'", ".txt")),
    "spectrum -o y.csv (a table)": Case(
        lambda d: ["spectrum", _signals(d), "--column", "torque", "-o", "y.csv"], says=("-o", ".json")
    ),
    "campbell -o Y.PNG (a table)": Case(lambda d: ["campbell", C1, "-o", "Y.PNG"], says=("-o", ".txt")),
    "simulate -o y.json (samples are CSV)": Case(
        lambda d: ["simulate", C1, "--scenario", "step", "--measure", "speed:motor", "-o", "y.json"],
        says=("-o", ".csv"),
    ),
}
