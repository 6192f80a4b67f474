"""
The test bench in Python
========================

The Customer 1 test bench - motor, PTSS parts 1 and 2, the coupling (part 3), part 4, the generator
- built in Python instead of read from its model file, and its torsional modes. It is the same chain
as :download:`customer1.toml <../../examples/customer1.toml>` (the tests check that both give the
same numbers to the bit).

Units are SI: stiffness N·m/rad, inertia kg·m², damping ratios as fractions. Run it with
``python examples/customer1_python.py``.
"""

# %%
# The chain
# ---------
# Each component is a frozen dataclass; the drivetrain is their chain from the motor to the
# generator. A shaft's damping ratio is its own modal damping (per part).

import flexshaft as fs


def build() -> fs.Drivetrain:
    """Motor - part 1 - part 2 - part 3 (coupling) - part 4 - generator, as published."""
    return fs.Drivetrain(
        name="Customer 1",
        components=[
            fs.Rigid("motor", inertia=58.10),
            fs.Shaft("part 1", stiffness=307933.18, inertia=0.44, damping_ratio=0.0053),
            fs.Shaft("part 2", stiffness=156591.02, inertia=0.75, damping_ratio=0.0053),
            fs.Coupling("part 3", stiffness=55120.04, inertia=0.06),
            fs.Shaft("part 4", stiffness=295285.92, inertia=0.03, damping_ratio=0.0053),
            fs.Rigid("generator", inertia=6.67),
        ],
    )


# %%
# Its modes
# ---------
# Mode 0 is the free chain's rigid spin (0 Hz); each elastic mode is named by the component that
# holds most of its strain energy.

result = fs.modal_analysis(build())
dominant = result.dominant_components()
for i, f in enumerate(result.frequencies_hz):
    xi = result.damping_ratios[i]
    print(f"mode {i}: {f:9.3f} Hz  damping {100 * xi:.4f} %  {dominant[i] or 'rigid body'}")

# %%
# The measurement carries the ratios of the frequencies to the first elastic mode's (the published
# values are normalised), so these are what to compare:

f = result.frequencies_hz
print(f"f2/f1 = {f[2] / f[1]:.2f}, f3/f1 = {f[3] / f[1]:.2f} (measured 8.22, 20.28)")

# %%
# The mode shapes
# ---------------
# Each elastic mode's twist along the chain, the components shaded. The results' ``.plot()``
# return a matplotlib Figure and never show it (``fig.savefig("modes.png")`` writes it).

# sphinx_gallery_thumbnail_number = 1
shapes = result.plot(modes=[1, 2, 3])

# %%
# Where each mode's strain energy is: the coupling in the first mode, the shafts beyond.

energy = result.plot("strain")
