"""
The test bench in Exudyn, from flexshaft's flexible bodies
==========================================================

Customer 1 with shaft parts 1, 2 and 4 as Craig–Bampton flexible bodies
(:download:`customer1_flex.toml <../../examples/customer1_flex.toml>`) built in the multibody code
Exudyn: each part enters as Exudyn's reduced-order floating-frame body (``ObjectFFRFreducedOrder``:
mesh nodes, mode basis, modal mass, stiffness and damping), the motor and the generator as rigid
bodies joined to the parts' interface markers, the coupling as a two-node body carrying its spring
and its inertia. Exudyn's eigenfrequencies and a motor-torque step response are then set against
flexshaft's own answers for the same drivetrain.

Exudyn is the ``multibody`` extra (``pip install 'flexshaft[multibody]'``). Run it with
``python examples/customer1_exudyn.py`` (about 10 s: Exudyn integrates 10 000 steps).
"""

import time
from pathlib import Path

import exudyn as exu
import exudyn.itemInterface as items
import numpy as np
from matplotlib.figure import Figure

import flexshaft as fs
from flexshaft.exports.exudynbody import chain_to_exudyn, simulate_exudyn

# The model files beside this script (the gallery and notebooks run it without __file__, in its folder).
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()

# %%
# The bench in Exudyn
# -------------------
# :func:`~flexshaft.exports.exudynbody.chain_to_exudyn` reduces each shaft as the model file says
# (:func:`flexshaft.reduce_part`), places each body with
# :func:`~flexshaft.exports.exudynbody.to_exudyn` (each mesh node a ring of four points turning with
# it) and joins the components at their interfaces: the motor on a revolute joint about x, every
# other joint rigid. A torque step of 1 kN·m acts on the motor from t = 0.

drivetrain = fs.load_model(HERE / "customer1_flex.toml")
system = exu.SystemContainer()
mbs = system.AddSystem()
chain = chain_to_exudyn(drivetrain, mbs)
for part in chain.components:
    kind = "rigid body" if not hasattr(part, "interfaces") else f"{len(part.interfaces)} interfaces"
    print(f"{part.name:>9}: {kind}")

TORQUE = 1000.0  # N·m on the motor
motor, generator, coupling = (chain.component(n) for n in ("motor", "generator", "part 3"))
mbs.AddLoad(items.LoadTorqueVector(markerNumber=motor.marker, loadVector=[TORQUE, 0.0, 0.0]))


def sensor(node, output):
    """A sensor on ``node`` keeping its ``output`` (an exu.OutputVariableType) in memory."""
    return mbs.AddSensor(items.SensorNode(nodeNumber=node, storeInternal=True, outputVariableType=output))


speed, coordinates = exu.OutputVariableType.AngularVelocity, exu.OutputVariableType.Coordinates
sensors = {
    "speed:motor": sensor(motor.node, speed),
    "speed:generator": sensor(generator.node, speed),
    # the coupling body's one flexible coordinate: its twist, θ_out − θ_in
    "torque:part 3": sensor(coupling.modal_node, coordinates),
}
mbs.Assemble()

# %%
# Eigenfrequencies
# ----------------
# Exudyn's own eigen-solver on the constrained system (projected on its constraints' null space)
# against :func:`flexshaft.modal_analysis` of the same file: every mode the bodies carry, rigid spin
# (0 Hz) left out.

reference = fs.modal_analysis(drivetrain)
eigenvalues, _ = mbs.ComputeODE2Eigenvalues()
f_exudyn = np.sqrt(np.abs(eigenvalues)) / (2 * np.pi)
f_flexshaft = reference.frequencies_hz
elastic = ~reference.rigid
deviation = np.abs(f_exudyn[elastic] / f_flexshaft[elastic] - 1.0)
print(f"{'mode':>4} {'flexshaft, Hz':>14} {'Exudyn, Hz':>14} {'deviation':>10}")
for i in np.flatnonzero(elastic)[:8]:
    print(f"{i:4d} {f_flexshaft[i]:14.4f} {f_exudyn[i]:14.4f} {abs(f_exudyn[i] / f_flexshaft[i] - 1):10.1e}")
print(f"all {elastic.sum()} elastic modes: largest deviation {deviation.max():.1e} (asked: 1e-3)")

# %%
# The step response
# -----------------
# Exudyn integrates with the trapezoidal rule (no numerical damping) at 50 µs; flexshaft's
# :func:`flexshaft.simulate` gives the exact response at each 1 ms sample (every mode kept). Both carry
# the parts' 0.53 % modal damping (each body's own damping matrix). The deviation is Exudyn's
# integration error, a fraction of a thousandth of each output's range.

DURATION, STEP, RATE = 0.5, 5e-5, 1000.0
start = time.perf_counter()
simulate_exudyn(mbs, DURATION, STEP, sample_period=1.0 / RATE)
elapsed = time.perf_counter() - start
stored = {name: mbs.GetSensorStoredData(s) for name, s in sensors.items()}
t = stored["speed:motor"][:, 0]
exudyn_out = {
    "speed:motor": stored["speed:motor"][:, 1],
    "speed:generator": stored["speed:generator"][:, 1],
    "torque:part 3": chain.coupling_torque("part 3", stored["torque:part 3"][:, 1]),
}
run = fs.simulate(
    reference, fs.Scenario.step(TORQUE), list(exudyn_out), rate=RATE, duration=DURATION, max_hz=np.inf
)
print(f"Exudyn: {t.size - 1} samples of {DURATION:g} s in {elapsed:.1f} s ({round(DURATION / STEP)} steps)")
for name, y in exudyn_out.items():
    y_ref = run.outputs[name]
    span = np.ptp(y_ref)
    worst = np.max(np.abs(y - y_ref)) / span
    print(f"{name:>16}: range {span:10.4g} {run.units[name]:<6} largest deviation {worst:.1e} of it")

# %%
# Both responses
# --------------
# The coupling torque and the two speeds: Exudyn's lines lie on flexshaft's.

# sphinx_gallery_thumbnail_number = 1
fig = Figure(figsize=(8, 6), layout="constrained")
axes = fig.subplots(2, 1, sharex=True)
axes[0].plot(run.time, run.outputs["torque:part 3"], lw=3, alpha=0.4, label="flexshaft")
axes[0].plot(t, exudyn_out["torque:part 3"], "k", lw=0.8, label="Exudyn")
axes[0].set_ylabel("coupling torque, N·m")
axes[0].legend()
for name in ("speed:motor", "speed:generator"):
    axes[1].plot(run.time, run.outputs[name], lw=3, alpha=0.4, label=f"{name} flexshaft")
    axes[1].plot(t, exudyn_out[name], "k", lw=0.8)
axes[1].set_ylabel("speed, rad/s")
axes[1].set_xlabel("time, s")
axes[1].legend()
