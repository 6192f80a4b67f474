"""Build the Customer 1 test bench in Python (the same chain as customer1.toml) and print its modes.

Run:  python examples/customer1_python.py
Units are SI: stiffness N·m/rad, inertia kg·m², damping ratios as fractions.
"""

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


def main() -> fs.ModalResult:
    result = fs.modal_analysis(build())
    dominant = result.dominant_components()
    for i, f in enumerate(result.frequencies_hz):
        xi = result.damping_ratios[i]
        print(f"mode {i}: {f:9.3f} Hz  damping {100 * xi:.4f} %  {dominant[i] or 'rigid body'}")
    # Ratios to the first elastic mode are what the measurement carries over (REFERENCE.md).
    f = result.frequencies_hz
    print(f"f2/f1 = {f[2] / f[1]:.2f}, f3/f1 = {f[3] / f[1]:.2f} (measured 8.22, 20.28)")
    return result


if __name__ == "__main__":
    main()
