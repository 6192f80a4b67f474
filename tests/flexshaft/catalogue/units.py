"""Units that are programs, numbers past floating point, warnings and numpy reprs (issue 20).

A unit string is one number and a unit expression read by a grammar (nothing evaluated): a power
tower, a unit without a number, an overlong string or a large exponent is one error line naming the
key. Section properties, materials, Rayleigh coefficients, frequencies and speeds beyond floating
point (or far beyond any drivetrain) are range errors naming the field, never an OverflowError "defect"
and never a RuntimeWarning next to the result; numbers in messages are numbers, not ``np.float64(...)``.
"""

from __future__ import annotations

from pathlib import Path

from tests.conftest import EXAMPLES
from tests.flexshaft.catalogue import Case

C1 = EXAMPLES / "customer1.toml"  # 5 DOFs, solved in milliseconds
TARGETS = (
    '[[target]]\nmode = 1\nfrequency_hz = 11.5\ntolerance = 0.02\n[[parameter]]\nname = "motor.inertia"\n'
    "percent = 10\n"
)
SEGMENTS = """[model]
name = "segments"

[[chain]]
name = "motor"
type = "rigid"
inertia = 58.1

[[chain]]
name = "p"
type = "shaft"
material = "steel"
segments = [{length = 0.3, od = 0.16, id = 0.04}]

[[chain]]
name = "gen"
type = "rigid"
inertia = 6.67
"""


def _c1(old: str, new: str) -> str:
    text = C1.read_text()
    assert old in text, "customer1.toml changed: update the units catalogue"
    return text.replace(old, new, 1)


def _model(text: str, *command: str):
    """A case: ``text`` written as m.toml (and a targets file t.toml), then ``command`` on it."""

    def setup(d: Path) -> list[str]:
        (d / "m.toml").write_text(text)
        (d / "t.toml").write_text(TARGETS)
        return [c if c != "MODEL" else "m.toml" for c in command]

    return setup


def _segment(old: str, new: str, *command: str):
    assert old in SEGMENTS
    return _model(SEGMENTS.replace(old, new), *(command or ("modes", "MODEL")))


def _rayleigh(spec: str, *command: str):
    text = _c1('inertia_model = "consistent"\n', f'inertia_model = "consistent"\nrayleigh = {{{spec}}}\n')
    return _model(text, *(command or ("modes", "MODEL")))


def _signals_going_back(d: Path) -> list[str]:
    # uniform_rate printed these times as np.float64(0.742) s: numpy 2's repr of its scalars
    rows = ["time [s],torque [N·m]", "0.0,1.0", "0.742,2.0", "0.5,3.0", "0.75,4.0"]
    (d / "s.csv").write_text("\n".join(rows) + "\n")
    return ["spectrum", "s.csv", "--column", "torque"]


FRF = ("frf", "MODEL", "--at", "motor", "--measure", "speed:generator")
GUIDE_UNITS = _c1("inertia = 58.10", 'inertia = "58.1 t*m^2"').replace(
    "stiffness = 307933.18", 'stiffness = "307.93318 kN*m/rad"'
)

CASES = {
    # --- a unit string is not a program -----------------------------------------------------------
    "power tower in an inertia": Case(
        _model(_c1("inertia = 58.10", 'inertia = "9**9**9 kg*m**2"'), "modes", "MODEL"),
        says=("inertia = '9**9**9 kg*m**2'", "nothing is computed", "valid"),
        budget_s=15,
    ),
    "power tower in a segment length": Case(
        _segment("length = 0.3", 'length = "9**9**9 mm"'),
        says=("segments[0].length = '9**9**9 mm'", "valid"),
        budget_s=15,
    ),
    "power tower in a stiffness": Case(
        _model(_c1("stiffness = 307933.18", 'stiffness = "9**9**9 N*m/rad"'), "modes", "MODEL"),
        says=("stiffness = '9**9**9 N*m/rad'", "valid"),
        budget_s=15,
    ),
    "unit without a number": Case(
        _model(_c1("inertia = 58.10", 'inertia = "kg*m^2"'), "modes", "MODEL"),
        says=("inertia = 'kg*m^2'", "no number in front", "valid"),
        budget_s=15,
    ),
    "overlong unit string": Case(
        _model(_c1("inertia = 58.10", 'inertia = "1 ' + "kg*" * 400 + 'm**2"'), "modes", "MODEL"),
        says=("inertia = ", "characters long, more than 200", "valid"),
        budget_s=15,
    ),
    "exponent too large": Case(
        _segment("od = 0.16", 'od = "1 m**99"'),
        says=("segments[0].od = '1 m**99'", "the exponent 99 is beyond ±4", "valid"),
        budget_s=15,
    ),
    "units of the model-file guide read as before": Case(
        _model(GUIDE_UNITS, "modes", "MODEL"), exit=0, budget_s=15
    ),
    # --- overflow in section properties is a range error naming the field -------------------------
    "od 1e100 in modes": Case(
        _segment("od = 0.16", "od = 1e100"),
        says=("segments[0].od = 1e+100 m", "<= 1000", "valid"),
        budget_s=15,
    ),
    "od 1e100 in calibrate": Case(
        _segment("od = 0.16", "od = 1e100", "calibrate", "MODEL", "--targets", "t.toml"),
        says=("segments[0].od = 1e+100 m", "valid"),
        budget_s=15,
    ),
    "segment length that overflows": Case(
        _segment("length = 0.3", "length = 1e300", "calibrate", "MODEL", "--targets", "t.toml"),
        says=("segments[0].length = 1e+300 m", "valid"),
        budget_s=15,
    ),
    "Young's modulus 1e308 in a 6-DOF model": Case(
        _model(
            SEGMENTS.replace('name = "segments"', 'name = "s"\ndofs = "full"').replace('"steel"', '"m"')
            + "\n[materials.m]\nE = 1e308\nnu = 0.29\nrho = 7850\n",
            "modes",
            "MODEL",
        ),
        says=("[materials.m]: E = 1e+308 Pa", "valid"),
        budget_s=15,
    ),
    # --- no RuntimeWarning beside a result or before the error line -------------------------------
    "huge Rayleigh coefficients in modes": Case(
        _rayleigh("alpha = 1e300, beta = 1e300"), says=("rayleigh.alpha = 1e+300 1/s", "valid"), budget_s=15
    ),
    "huge Rayleigh coefficients in frf": Case(
        _rayleigh("beta = 1e308", *FRF), says=("rayleigh.beta = 1e+308 s", "valid"), budget_s=15
    ),
    "Rayleigh targets at 1e300 Hz": Case(
        _rayleigh("frequencies_hz = [1e200, 1e300], damping_ratios = [0.01, 0.02]"),
        says=("rayleigh.frequencies_hz[0] = 1e+200 Hz", "valid"),
        budget_s=15,
    ),
    "frf to 1e308 Hz": Case(
        _model(C1.read_text(), *FRF, "--to", "1e308"), says=("--to", "valid"), budget_s=15
    ),
    "frf at 1e308 rpm": Case(
        _model(C1.read_text(), *FRF, "--speed", "1e308"), says=("--speed", "valid"), budget_s=15
    ),
    "modes up to inf Hz": Case(
        _model(C1.read_text(), "modes", "MODEL", "--max-hz", "inf"), says=("--max-hz", "valid")
    ),
    "reduce below 1e300 Hz": Case(
        _model(C1.read_text(), "reduce", "MODEL", "--part", "part 1", "--max-hz", "1e300", "-o", "b.npz"),
        says=("--max-hz", "valid"),
    ),
    "twist of stiffnesses summing past 1e308": Case(
        _model(
            C1.read_text()
            .replace("stiffness = 307933.18", "stiffness = 1e308")
            .replace("stiffness = 156591.02", "stiffness = 1e308"),
            "twist",
            "MODEL",
        ),
        says=("stiffness", "overflows double precision", "valid"),
    ),
    "sensitivity to an inertia of 1e-308": Case(
        _model(_c1("inertia = 58.10", "inertia = 1e-308"), "sensitivity", "MODEL"),
        says=("the derivatives leave double precision", "valid"),
    ),
    "calibrate an inertia of 1e308": Case(
        _model(_c1("inertia = 58.10", "inertia = 1e308"), "calibrate", "MODEL", "--targets", "t.toml"),
        says=("double precision", "valid"),
    ),
    # --- numbers in messages are numbers ----------------------------------------------------------
    "times printed as numbers": Case(_signals_going_back, says=("(0.742 s then 0.5 s)", "valid")),
    # a spread past 1e308 is said in orders of magnitude (it printed "spans inf")
    "stiffness over inertia spread past double precision": Case(
        _model(
            '[[chain]]\nname = "m"\ntype = "rigid"\ninertia = 1e-7\n'
            '[[chain]]\nname = "p"\ntype = "shaft"\nstiffness = 1e300\ninertia = 0.0\n'
            '[[chain]]\nname = "g"\ntype = "rigid"\ninertia = 1e305\n',
            "modes",
            "MODEL",
        ),
        says=("spans 1e312", "valid"),
    ),
}
