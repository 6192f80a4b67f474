"""What an export says of the damping its numbers carry (model.describe.damping_line)."""

import flexshaft as fs
from flexshaft.analysis.systemdamping import system_damped
from flexshaft.model.describe import damping_line
from tests.conftest import EXAMPLES


def test_per_part_and_rayleigh_damping_are_told_apart():
    model = fs.load_model(EXAMPLES / "customer1.toml")
    assert damping_line(model) == "damping: per part (each part's own damping and dampers)"
    system = system_damped(model)
    line = damping_line(system)
    assert line.startswith("damping: Rayleigh alpha ") and f"{system.rayleigh.beta:.6g} s" in line
    assert len(line) <= 80  # it fits a universal file's ID line
