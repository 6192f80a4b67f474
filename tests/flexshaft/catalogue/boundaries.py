"""Boundaries: every mode number, ratio reference, bound and range checked against the model before any
solve - a target's mode = 99 was an IndexError ("a flexshaft defect"), bounds = [-1, 70000] on a
stiffness was accepted, and sensitivity/sweep --modes 99 quietly clamped where modes --count (now
modes --modes) refused."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import EXAMPLES
from tests.flexshaft.catalogue import Case

C1 = str(EXAMPLES / "customer1.toml")  # 5 DOFs: mode 0 rigid-body, modes 1 … 4 elastic
GOOD_TARGET = "[[target]]\nmode = 1\nfrequency_hz = 11.5\n"
GOOD_PARAMETER = '[[parameter]]\nname = "part 3.stiffness"\npercent = 10\n'


def _calibrate(targets: str = GOOD_TARGET, parameters: str = GOOD_PARAMETER):
    """A case: calibrate Customer 1 against a targets file of these entries."""

    def setup(d: Path) -> list[str]:
        (d / "t.toml").write_text(targets + parameters)
        return ["calibrate", C1, "--targets", "t.toml"]

    return setup


def _target(**keys) -> str:
    return "[[target]]\n" + "".join(f"{k} = {v}\n" for k, v in keys.items())


def _staged(d: Path) -> list[str]:
    """Two stages; the second one's mode 99 is refused before the first is solved."""
    (d / "without_dut.toml").write_text((EXAMPLES / "without_dut.toml").read_text())
    (d / "t.toml").write_text(
        '[[stage]]\nname = "shared"\nmodel = "without_dut.toml"\n'
        "[[stage.target]]\nmode = 2\nratio_to = 1\nratio = 2.9\n"
        '[[stage.parameter]]\nname = "part 1.stiffness"\npercent = 10\n'
        '[[stage]]\nname = "Customer 1"\n'
        "[[stage.target]]\nmode = 99\nratio_to = 1\nratio = 8.22\n"
        '[[stage.parameter]]\nname = "part 3.stiffness"\npercent = 10\n'
    )
    return ["calibrate", C1, "--targets", "t.toml"]


def _run(*argv: str):
    return lambda d: list(argv)


TARGET = ("t.toml", "[[target]] #1", "valid: an elastic mode of the model, 1 … 4")
SWEEP = ["sweep", C1, "--param"]

CASES = {
    # targets: mode numbers and ratio references against the model's modes
    "calibrate target mode 99": Case(
        _calibrate(_target(mode=99, frequency_hz=100.0)), says=(*TARGET, "target.mode = 99")
    ),
    "calibrate ratio_to 99": Case(
        _calibrate(_target(mode=2, ratio_to=99, ratio=8.0)), says=(*TARGET, "target.ratio_to = 99")
    ),
    "calibrate mode 0 (rigid-body)": Case(
        _calibrate(_target(mode=0, frequency_hz=1.0)), says=(*TARGET, "mode 0 is rigid-body")
    ),
    "calibrate ratio to the rigid-body mode": Case(
        _calibrate(_target(mode=2, ratio_to=0, ratio=8.0)), says=(*TARGET, "target.ratio_to = 0")
    ),
    "calibrate negative mode": Case(
        _calibrate(_target(mode=-3, frequency_hz=1.0)), says=(*TARGET, "target.mode = -3")
    ),
    "calibrate mode 2.5": Case(
        _calibrate(_target(mode=2.5, frequency_hz=91.0)),
        says=("t.toml", "target.mode = 2.5", "valid: a whole"),
    ),
    "calibrate mode 2**70": Case(
        _calibrate(_target(mode=2**70, frequency_hz=91.0)), says=(*TARGET, f"target.mode = {2**70}")
    ),
    "calibrate ratio_to itself": Case(
        _calibrate(_target(mode=2, ratio_to=2, ratio=1.0)), says=("t.toml", "target.ratio_to = 2", "valid")
    ),
    "calibrate duplicated target": Case(
        _calibrate(GOOD_TARGET + _target(mode=1, frequency_hz=12.0)),
        says=("t.toml", "[[target]] #2", "[[target]] #1 targets already", "valid"),
    ),
    "calibrate ratio and its inverse": Case(
        _calibrate(_target(mode=2, ratio_to=1, ratio=8.0) + _target(mode=1, ratio_to=2, ratio=0.125)),
        says=("t.toml", "[[target]] #2", "already", "valid"),
    ),
    "calibrate shape of the wrong length": Case(
        _calibrate(_target(mode=2, frequency_hz=91.0, shape="[1.0, -0.5]")),
        says=(*TARGET[:2], "target.shape = 2", "5 stations", "valid: θx at each station"),
    ),
    "calibrate stage 2 mode 99": Case(
        _staged, says=("t.toml", "[[stage]] #2 [[target]] #1", "mode = 99", "1 … 4")
    ),
    # parameters: bounds inside the parameter's domain, around its value
    "calibrate bounds [-1, 70000] on a stiffness": Case(
        _calibrate(parameters='[[parameter]]\nname = "part 3.stiffness"\nbounds = [-1, 70000]\n'),
        says=("t.toml", "[[parameter]] #1", "part 3.stiffness.bounds = [-1.0, 70000.0]", "valid", "> 0"),
    ),
    "calibrate damping-ratio bound of 1": Case(
        _calibrate(parameters='[[parameter]]\nname = "part 1.damping_ratio"\nbounds = [0.001, 1.0]\n'),
        says=("t.toml", "part 1.damping_ratio.bounds", "upper bound", "< 1"),
    ),
    "calibrate bounds [nan, 1]": Case(
        _calibrate(parameters='[[parameter]]\nname = "part 3.stiffness"\nbounds = [nan, 70000]\n'),
        says=("t.toml", "part 3.stiffness.bounds = nan", "valid: a finite number"),
    ),
    "calibrate bounds not around the model's value": Case(
        _calibrate(parameters='[[parameter]]\nname = "part 3.stiffness"\nbounds = [60000, 70000]\n'),
        says=("t.toml", "[[parameter]] #1", "part 3.stiffness.bounds", "55120.04", "valid"),
    ),
    "calibrate a parameter tuned and fixed": Case(
        _calibrate(parameters=GOOD_PARAMETER + '[[parameter]]\nname = "part 3.stiffness"\nfixed = 50000.0\n'),
        says=("t.toml", "[[parameter]] #2", "listed twice", "valid"),
    ),
    "calibrate fixed value out of domain": Case(
        _calibrate(parameters=GOOD_PARAMETER + '[[parameter]]\nname = "motor.inertia"\nfixed = -58.1\n'),
        says=("t.toml", "[[parameter]] #2", "motor.inertia.fixed = -58.1", "> 0"),
    ),
    "calibrate unknown parameter": Case(
        _calibrate(parameters='[[parameter]]\nname = "part 9.stiffness"\npercent = 10\n'),
        says=("t.toml", "[[parameter]] #1", "'part 9.stiffness'", "valid: motor.inertia"),
    ),
    "calibrate a valid problem": Case(_calibrate(), exit=0),
    # how many modes: the three commands refuse alike
    "sensitivity --modes 99": Case(
        _run("sensitivity", C1, "--modes", "99"),
        says=("--modes = 99", "5 modes, 4 of them elastic", "at most 4"),
    ),
    "sweep --modes 99": Case(
        _run(*SWEEP, "part 3.stiffness=4e4:7e4:3", "--modes", "99"),
        says=("--modes = 99", "5 modes, 4 of them elastic", "at most 4"),
    ),
    "modes --modes 99": Case(
        _run("modes", C1, "--modes", "99"), says=("--modes = 99", "5 modes", "at most 5")
    ),
    "sensitivity --modes 4": Case(
        _run("sensitivity", C1, "--modes", "4", "--param", "part 3.stiffness"), exit=0
    ),
    # sweep ranges: inside the parameter's domain, LO <= HI
    "sweep negative stiffness": Case(
        _run(*SWEEP, "part 3.stiffness=-1:7e4:3"),
        says=("--param = 'part 3.stiffness=-1:7e4:3'", "valid", "> 0"),
    ),
    "sweep damping ratio 1": Case(
        _run(*SWEEP, "part 1.damping_ratio=0,0.5,1"), says=("--param", "damping_ratio = 1", "< 1")
    ),
    "sweep zero rigid inertia": Case(
        _run(*SWEEP, "motor.inertia=0:60:3"), says=("--param", "motor.inertia", "> 0")
    ),
    "sweep LO above HI": Case(_run(*SWEEP, "part 3.stiffness=7e4:4e4:3"), says=("--param", "LO <= HI")),
    "sweep unknown parameter": Case(
        _run(*SWEEP, "part 9.stiffness=1:2:2"), says=("--param", "valid: motor.inertia")
    ),
    "sweep inf": Case(_run(*SWEEP, "part 3.stiffness=1:inf:2"), says=("--param", "valid")),
}
