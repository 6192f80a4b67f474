"""What the geometry tests share: exact volumes of solids, and the test-bench parts and their
section tables, each built or sliced once a session, when first asked for.

The fixtures import build123d only when used, so a test module that skips without it
(``pytest.importorskip("build123d")``) still collects.
"""

from __future__ import annotations

import pytest

# OCCT integrates volumes of planes, cylinders, cones and tori to round-off; 1e-9 leaves headroom.
EXACT = 1e-9

#: The test-bench parts (functions of geometry.parts.testbench), from the motor to the generator.
BENCH = [
    "motor_shaft_end",
    "coupling_hub",
    "ptss_part1",
    "torque_flange",
    "ptss_part2",
    "ptss_part4",
    "generator_shaft_end",
]


def vol_m3(shape) -> float:
    """Volume in m³ of a build123d shape (mm³), integrated adaptively to 1e-12 relative.

    build123d's ``.volume`` uses a fixed Gauss rule, which is off by ~4e-6 on faces
    trimmed by B-spline edges (a round-ended keyway meets the shaft along a
    cylinder/cylinder intersection, approximated by OCCT as a B-spline).
    """
    from OCP.BRepGProp import BRepGProp  # ships with build123d
    from OCP.GProp import GProp_GProps

    from geometry.units import volume_from_cad

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape.wrapped, props, 1e-12, False)
    return volume_from_cad(props.Mass())


def one_valid_solid(part) -> bool:
    import build123d as bd

    # build123d 0.13: ``is_valid`` is a property, not a method.
    return isinstance(part, bd.Part) and len(part.solids()) == 1 and part.is_valid


class _OnFirstUse(dict):
    """A dict that makes a missing entry with ``make(key)`` and keeps it."""

    def __init__(self, make) -> None:
        super().__init__()
        self._make = make

    def __missing__(self, key):
        self[key] = value = self._make(key)
        return value


@pytest.fixture(scope="session")
def bench_parts():
    """The test-bench parts with their default dimensions, by function name, each built once.

    Read them only: a test that changes a part (``write_stl`` clears and replaces its
    triangulation) builds its own.
    """
    from geometry.parts import testbench

    return _OnFirstUse(lambda name: getattr(testbench, name)())


@pytest.fixture(scope="session")
def testbench_tables():
    """The test-bench parts' section tables, each sliced once (from its own fresh build), when first
    asked for (so the slow STL round trip, run alone by `pytest -m slow`, slices only the part it needs)."""
    from geometry.parts import testbench
    from geometry.slicing import sections

    return _OnFirstUse(lambda name: sections(getattr(testbench, name)(), name=name))
