"""flexshaft: drivetrain shafts from CAD to validated flexible-body dynamics.

The public API in one place. Names load lazily (PEP 562): ``import flexshaft``
imports no solver, and ``import geometry`` (the CAD side, which needs only
the section table and the error types) loads none either.

The package is laid out as its data flow, each stage importing only earlier
ones::

    errors, validation, system/   what every stage uses: errors, value checks, the OS-facing safety
    sections/    the section table (the seam with geometry), closed forms, CSV
    linalg/      the sparse assembler, solvers chosen by size, eigensolvers, the one MAC, the one
                 damped eigen-solver, damping matrices
    elements/    torsion, Timoshenko and 10-node tetrahedron matrices, materials, the tet mesh type
    parts/       1D and solid part models (K, M, masters, recovery), one constraint step
    reduction/   the one Craig–Bampton front end for 1D and solid parts, damping, selection, cb_check
    model/       components, the drivetrain and its one assembled model
    input/       model files through one schema layer, units, CAD parts, caches (runs no analysis)
    measurement/ recordings, spectra, peaks and damping, SSI-COV/FDD identification, pairing
    views/       plots, 3D pictures, the browser viewer, progress: they draw what they are given
    analysis/    modal (undamped and damped), twist test, state space, forced response, time
                 simulation, Campbell diagram, sensitivities, calibration, sweeps, identification
    exports/     flexible bodies and linear systems for other tools
    study/       the whole study in one command: its file, stages, cache, the one report
    cli/         the ``flexshaft`` command
"""

from __future__ import annotations

import importlib

from .version import __version__ as __version__

# public name -> module that defines it
_EXPORTS = {
    "ModelError": "errors",
    "Material": "elements.materials",
    "STEEL": "elements.materials",
    "SectionTable": "sections",
    "part_model": "parts.model",
    "PartModel": "parts.model",
    "FlexibleBody": "reduction",
    "ModalDamping": "reduction",
    "cb_check": "reduction",
    "craig_bampton": "reduction",
    "select_modes": "reduction",
    "Coupling": "model.components",
    "Gear": "model.components",
    "Drivetrain": "model.components",
    "Rayleigh": "model.components",
    "Reduce": "model.components",
    "Rigid": "model.components",
    "Shaft": "model.components",
    "AssembledModel": "model.assembly",
    "Station": "model.assembly",
    "assemble": "model.assembly",
    "modal_damping_matrix": "linalg.damping",
    "rayleigh_coefficients": "linalg.damping",
    "rayleigh_ratio": "linalg.damping",
    "ModalResult": "analysis.modal",
    "modal_analysis": "analysis.modal",
    "part_modes": "analysis.modal",
    "TwistResult": "analysis.twist",
    "twist_test": "analysis.twist",
    "stiffness_target": "analysis.twist",
    "StateSpace": "analysis.statespace",
    "FrequencyResponse": "analysis.statespace",
    "state_space": "analysis.statespace",
    "frequency_response": "analysis.statespace",
    "frequency_grid": "analysis.statespace",
    "signal_names": "analysis.statespace",
    "ForcedResponse": "analysis.forced",
    "forced_response": "analysis.forced",
    "Scenario": "analysis.scenario",
    "SpeedControl": "analysis.scenario",
    "SimulationResult": "analysis.simulate",
    "simulate": "analysis.simulate",
    "closed_loop_poles": "analysis.simulate",
    "CampbellDiagram": "analysis.campbell",
    "campbell": "analysis.campbell",
    "sensitivities": "analysis.sensitivity",
    "Sensitivities": "analysis.sensitivity",
    "parameters": "analysis.parameters",
    "with_parameters": "analysis.parameters",
    "calibrate": "analysis.calibrate",
    "Target": "analysis.calibrate",
    "Bound": "analysis.calibrate",
    "CalibrationResult": "analysis.calibrate",
    "sweep": "analysis.sweep",
    "SweepResult": "analysis.sweep",
    "read_targets": "study.tunedfile",
    "MeshConvergence": "analysis.convergence",
    "mesh_convergence": "analysis.convergence",
    "MeshChoice": "analysis.convergence",
    "mesh_for_range": "analysis.convergence",
    "spectrum": "measurement.spectrum",
    "Spectrum": "measurement.spectrum",
    "spectrogram": "measurement.spectrogram",
    "Spectrogram": "measurement.spectrogram",
    "find_peaks": "measurement.peaks",
    "Peak": "measurement.peaks",
    "half_power_damping": "measurement.peaks",
    "log_decrement": "measurement.decay",
    "decay_damping": "measurement.decay",
    "order_lines": "measurement.spectrogram",
    "ridge": "measurement.spectrogram",
    "read_signals": "measurement.signalfile",
    "write_signals": "measurement.signalfile",
    "SignalTable": "measurement.signalfile",
    "read_measured": "measurement.files",
    "write_measured": "measurement.files.write",
    "load_model": "input.modelfile",
    "loads_model": "input.modelfile",
    "BodyFile": "exports.bodies",
    "read_flexible_body": "exports.bodies",
    "write_flexible_body": "exports.bodies",
    "read_study": "study.studyfile",
    "Study": "study.studyfile",
    "run_study": "study",
    "system_damped": "analysis.systemdamping",
    "response_modes": "analysis.modal",
    "listing_modes": "analysis.modal",
    "analyse_signal": "measurement.analyse",
    "identify_modes": "measurement.identify",
    "identify": "analysis.identification",
    "ModelIdentification": "analysis.identification",
    "pair_modes": "measurement.pairing",
    "Pairing": "measurement.pairing",
    "Identification": "measurement.identified",
    "IdentifiedMode": "measurement.identified",
    "SignalAnalysis": "measurement.analyse",
    "calibrate_stages": "analysis.staged",
    "reduce_part": "model.reduce",
    "StudyRun": "study",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    try:
        module = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module 'flexshaft' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
