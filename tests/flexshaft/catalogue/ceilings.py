"""Ceilings: every count, range and size an option or a model file asks for is checked against its
ceiling (:mod:`flexshaft.system.limits`) before the work starts - ``frf --points 1000000000`` reached 7.9 GB,
``campbell --speed 0:1e9`` ran 287 s, a polygon of 100 000 sides over 5 minutes, a chain of 10 000
components in ``sensitivity`` past 150 s, ``elements = 5000000`` 94 s and 4.5 GB. Each is refused fast,
naming the option or field and the ceiling; a value at the ceiling, where that is cheap to run, works.
"""

from __future__ import annotations

from pathlib import Path

from tests.conftest import EXAMPLES
from tests.flexshaft.catalogue import Case

C1 = str(EXAMPLES / "customer1.toml")
PTSS = str(EXAMPLES / "ptss_full.toml")
FRF = ["frf", C1, "--at", "motor", "--measure", "speed:generator"]
STEP = ["simulate", C1, "--scenario", "step", "--torque", "100"]
ENDS = '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n'
GEN = '\n[[chain]]\nname = "generator"\ntype = "rigid"\ninertia = 6.67\n'


def _run(*argv: str):
    return lambda d: list(argv)


def _model(chain: str, *argv: str, head: str = ""):
    """A case: m.toml holds the motor, ``chain`` and the generator; the command runs on it."""

    def setup(d: Path) -> list[str]:
        (d / "m.toml").write_text(head + ENDS + chain + GEN)
        return [argv[0], "m.toml", *argv[1:]]

    return setup


def _shaft(**keys) -> str:
    return '\n[[chain]]\nname = "s"\n' + "".join(f"{k} = {v}\n" for k, v in keys.items())


def _part(function: str, params: str) -> str:
    """A library part (no --allow-code needed) as a cad component."""
    return (
        f'\n[[chain]]\nname = "p"\ntype = "cad"\ngeometry = "geometry.parts:{function}"\n'
        f'params = {{{params}}}\nmaterial = "steel"\n'
    )


def _chain(n: int, *argv: str):
    """A case: a chain of ``n`` components, rigid inertias and shafts by turns."""

    def setup(d: Path) -> list[str]:
        parts = []
        for i in range(n):
            if i % 2 == 0:
                parts.append(f'[[chain]]\nname = "r{i}"\ntype = "rigid"\ninertia = 1.0\n')
            else:
                parts.append(f'[[chain]]\nname = "s{i}"\ntype = "shaft"\nstiffness = 1e5\ninertia = 0.1\n')
        (d / "chain.toml").write_text("\n".join(parts))
        return [argv[0], "chain.toml", *argv[1:]]

    return setup


def _signal(*argv: str):
    """A case: s.csv holds a 25 Hz and a 60 Hz sine, 2 s at 1 kHz; the command runs on it."""

    def setup(d: Path) -> list[str]:
        import math

        rows = ["time [s],torque [N·m]"]
        for k in range(2000):
            t = k / 1000
            rows.append(f"{t:.4f},{math.sin(50 * math.pi * t) + 0.5 * math.sin(120 * math.pi * t):.9f}")
        (d / "s.csv").write_text("\n".join(rows) + "\n")
        return ["spectrum", "s.csv", "--column", "torque", *argv]

    return setup


def _targets(options: str, *argv: str):
    def setup(d: Path) -> list[str]:
        (d / "t.toml").write_text(
            options + '[[target]]\nmode = 1\nfrequency_hz = 11.5\n[[parameter]]\nname = "part 3.stiffness"\n'
            "percent = 10\n"
        )
        return ["calibrate", C1, "--targets", "t.toml", *argv]

    return setup


def _segments(n: int) -> str:
    return "[" + ", ".join(f"{{length = 0.001, od = {0.1 if k % 2 else 0.12}}}" for k in range(n)) + "]"


ORDERS = ",".join(str(k) for k in range(1, 102))
SPLIT = "valid: at most"

CASES = {
    # command-line counts, refused while the options are read
    "frf --points 1000000000": Case(
        _run(*FRF, "--points", "1000000000"), says=("--points = 1000000000", "100000 frequencies", SPLIT)
    ),
    "view --frames 100000": Case(
        _run("view", C1, "--mode", "1", "--frames", "100000", "-o", "v.gif"), says=("--frames", "240 frames")
    ),
    "sweep --lhs 2000000": Case(
        _run("sweep", C1, "--param", "part 3.stiffness=4e4:7e4", "--lhs", "2000000"),
        says=("--lhs", "1000000 points", SPLIT),
    ),
    "calibrate --starts 1000000": Case(_targets("", "--starts", "1000000"), says=("--starts", "1000 starts")),
    "spectrum --peaks 1000000": Case(_signal("--peaks", "1000000"), says=("--peaks", "1000 peaks", SPLIT)),
    # ranges and lists, refused before the model is read
    "campbell ptss_full --speed 0:1e9": Case(
        _run("campbell", PTSS, "--speed", "0:1e9"), says=("--speed = '0:1e9' rpm", "1000000 rpm", SPLIT)
    ),
    "campbell 101 orders": Case(_run("campbell", C1, "--orders", ORDERS), says=("--orders", "100 orders")),
    "sweep 1000000 values of one parameter": Case(
        _run("sweep", C1, "--param", "part 3.stiffness=4e4:7e4:1000000"),
        says=("--param", "100000 values per parameter"),
    ),
    "sweep grid of 1001 × 1000": Case(
        _run(
            "sweep",
            C1,
            "--param",
            "part 3.stiffness=4e4:7e4:1001",
            "--param",
            "part 1.stiffness=1e5:4e5:1000",
        ),
        says=("--param = '1001 × 1000'", "1000000 points", "--lhs"),
    ),
    "calibrate starts = 100000 in the targets file": Case(
        _targets("[options]\nstarts = 100000\n"), says=("t.toml", "starts = 100000", "1000 starts")
    ),
    "simulate --duration 1e9": Case(
        _run(*STEP, "--measure", "speed:generator", "--duration", "1e9"),
        says=("--duration = 1000000000.0 s", "10000000 samples", "--rate"),
    ),
    "simulate 30 outputs of 10 million samples": Case(
        _run(*STEP, *["--measure", "speed:generator"] * 30, "--duration", "9999"),
        says=("--measure = 30 outputs", "MB", SPLIT),
    ),
    # model files: counted before anything is built
    "sensitivity on a chain of 10 000 components": Case(
        _chain(10_000, "sensitivity"), says=("chain.toml", "chain = 10000", "500 components")
    ),
    "elements = 5000000": Case(
        _model(_shaft(type='"shaft"', stiffness=3e5, inertia=0.44, elements=5_000_000), "modes"),
        says=("m.toml", "'s'", "elements = 5000000", "1000000 elements per part"),
    ),
    "three shafts of a million elements (memory)": Case(
        _model(
            "".join(
                _shaft(type='"shaft"', stiffness=3e5, inertia=0.44, elements=1_000_000).replace(
                    '"s"', f'"s{k}"'
                )
                for k in range(3)
            ),
            "modes",
        ),
        says=("m.toml", "'s0'", "elements = 1000000", "MB", "FLEXSHAFT_MAX_MEMORY_MB"),
    ),
    "max_element_length = 1e-9 m": Case(
        _model(
            _shaft(
                type='"shaft"',
                material='"steel"',
                segments="[{length = 1.0, od = 0.1}]",
                max_element_length=1e-9,
            ),
            "modes",
        ),
        says=("m.toml", "max_element_length = 1e-09 m", "elements per part", "FLEXSHAFT_MAX_ELEMENTS"),
    ),
    "6-DOF shaft of 200 000 elements": Case(
        _model(
            _shaft(
                type='"shaft"',
                material='"steel"',
                segments="[{length = 2.0, od = 0.2}]",
                max_element_length=1e-5,
            ),
            "modes",
            head='[model]\ndofs = "full"\n',
        ),
        says=("m.toml", "max_element_length = 1e-05 m", SPLIT),
    ),
    "a shaft of 10 000 segments": Case(
        _model(_shaft(type='"shaft"', material='"steel"', segments=_segments(10_000)), "modes"),
        says=("m.toml", "segments = 10000", "1000 segments per shaft"),
    ),
    "modes --modes 4000 of 10 000 DOFs (a dense solve)": Case(
        _model(
            _shaft(type='"shaft"', stiffness=3e5, inertia=0.44, elements=9999), "modes", "--modes", "4000"
        ),
        says=("--modes = 4000", "dense eigen-solve", "MB", "3333 modes"),
    ),
    # the part library (no --allow-code needed): counts checked before the solid is built
    "polygon_shaft of 100 000 sides": Case(
        _model(_part("polygon_shaft", "length = 0.5, sides = 100000, across_flats = 0.1"), "modes"),
        says=("m.toml", "sides = 100000", "100 sides"),
        budget_s=60,
    ),
    "spline_shaft of 10 000 teeth": Case(
        _model(_part("spline_shaft", "length = 0.5, root_d = 0.1, tip_d = 0.11, teeth = 10000"), "modes"),
        says=("m.toml", "teeth = 10000", "200 teeth"),
        budget_s=60,
    ),
    "flange of 10 000 bolt holes": Case(
        _model(
            _part(
                "flange", "od = 1.0, thickness = 0.05, bolt_count = 10000, bolt_hole_d = 1e-4, pitch_d = 0.8"
            ),
            "modes",
        ),
        says=("m.toml", "bolt_count = 10000", "200 holes per circle"),
        budget_s=60,
    ),
    "stepped_shaft of 1000 segments": Case(
        _model(_part("stepped_shaft", f"segments = {_segments(1000)}"), "modes"),
        says=("m.toml", "segments = 1000", "100 segments per part"),
        budget_s=60,
    ),
    # work estimated from two sizes at once: refused after the modes, before the long part
    "campbell ptss_full --speed 0:20000 (whirl tracking)": Case(
        _run("campbell", PTSS, "--speed", "0:20000"),
        says=("--speed = 20000.0 rpm", "dense solves of order 1000", SPLIT),
        budget_s=90,
        slow=True,  # the modes of ptss_full first: 8-11 s
    ),
    # at the ceiling, where that is cheap: it runs
    "frf --points 100000 (at the ceiling)": Case(_run(*FRF, "--points", "100000"), exit=0),
    "campbell --speed 0:1000000 (at the ceiling)": Case(_run("campbell", C1, "--speed", "0:1000000"), exit=0),
    "campbell 100 orders (at the ceiling)": Case(
        _run("campbell", C1, "--orders", ",".join(str(k) for k in range(1, 101))), exit=0
    ),
    "modes of a chain of 500 components (at the ceiling)": Case(_chain(500, "modes"), exit=0),
    "a shaft of 1000 segments (at the ceiling)": Case(
        _model(_shaft(type='"shaft"', material='"steel"', segments=_segments(1000)), "modes"), exit=0
    ),
    "elements = 1000000 (at the ceiling)": Case(
        _model(_shaft(type='"shaft"', stiffness=3e5, inertia=0.44, elements=1_000_000), "modes"),
        exit=0,
        slow=True,  # a million elements assembled and solved: 6-7 s
    ),
    "spectrum --peaks 1000 (at the ceiling)": Case(_signal("--peaks", "1000"), exit=0),
    "polygon_shaft of 100 sides (at the ceiling)": Case(
        _model(
            _part("polygon_shaft", "length = 0.5, sides = 100, across_flats = 0.1"), "modes", "--no-cache"
        ),
        exit=0,
        budget_s=60,
    ),
}
