"""From the bench's recordings to a tuned model: the modes identified, their targets file, the calibration.

The one implementation behind ``flexshaft identify --parameters`` and a study's ``[[measurement]]``
entries. The runs are identified and paired with the set-up's modes
(:func:`flexshaft.analysis.identification.identify`); the targets file is written from what the
identification trusts (:meth:`~flexshaft.analysis.identification.ModelIdentification.targets_toml`: a
mode or a damping ratio it doubts is left out, a comment says why) with the parameters added as
``[[parameter]]`` tables; that text is read back as every targets file is
(:func:`~flexshaft.study.tunedfile.loads_targets`) and calibrated
(:func:`flexshaft.analysis.staged.calibrate_stages`). The file is the interface: nothing reaches the
calibration but what the targets file a user can open says.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import date
from pathlib import Path

from ..errors import ModelError
from .tunedfile import PARAMETER, dumps_toml, loads_targets, parameter_bound, write_tuned_model

__all__ = ["MeasuredTuning", "measured_targets", "tune_to_measured", "read_parameters", "checked_parameters"]


@dataclass(frozen=True)
class MeasuredTuning:
    """Recordings identified and, with parameters, a model calibrated to them.

    Attributes
    ----------
    identified : ModelIdentification
        The modes identified from the runs, paired with the model's.
    targets_text : str
        The targets file calibrated to (the trusted targets and the parameters), as written.
    calibration : StagedCalibration or None
        The calibration; None without parameters.
    """

    identified: object
    targets_text: str
    calibration: object = None

    def table(self, *, verbose: bool = False) -> str:
        """The identification's table, then the calibration's (``flexshaft identify --parameters``)."""
        text = self.identified.table(verbose=verbose)
        if self.calibration is not None:
            text += "\n\ncalibrated to the trusted targets:\n" + self.calibration.table().rstrip()
        return text

    def to_dict(self) -> dict:
        """The identification's document with the calibration's stages under ``calibration``."""
        doc = self.identified.to_dict()
        if self.calibration is not None:
            doc["calibration"] = self.calibration.to_dict()
        return doc

    def write_tuned(self, path, *, overwrite: bool = False) -> Path:
        """Write the tuned model file (the model file with the tuned values put in, as ``calibrate -o``)."""
        if self.calibration is None:
            raise ModelError("needs parameters to tune", field="tuned", valid="parameters with the runs")
        last, values = self.calibration.last, self.calibration.tuned_values()
        header = (
            f"{last.drivetrain.name}, tuned by flexshaft on {date.today().isoformat()} to the modes "
            f"identified from recordings\nfrom {last.model}; tuned values (SI): "
            + ", ".join(f"{k} = {v:.9g}" for k, v in values.items())
        )
        return write_tuned_model(
            path, last.model, last.drivetrain, values, header=header, overwrite=overwrite
        )


def checked_parameters(parameters, source: str) -> list[dict]:
    """Each ``[[parameter]]`` entry read by the targets file's schema (the first problem, one error)."""
    from ..input.schema import read

    if not isinstance(parameters, list | tuple):
        raise ModelError("must be a list of parameter tables", file=source, field="parameters")
    out = []
    for i, p in enumerate(parameters):
        where = f"parameters #{i + 1}"
        entry = read(p, PARAMETER, file=source, where=where, field="parameters")
        parameter_bound(entry, source, where)  # its values checked now, before any work
        out.append({k: list(v) if isinstance(v, tuple) else v for k, v in entry.items()})  # as TOML writes it
    return out


def measured_targets(identified, parameters=(), source: str = "<parameters>") -> str:
    """The targets file's text: the trusted targets of ``identified`` (a ModelIdentification with a
    model), then ``parameters`` (dicts as ``[[parameter]]`` tables: ``name`` and ``percent``,
    ``bounds`` or ``fixed``) - checked, so a mistake names its entry."""
    text = identified.targets_toml()
    entries = checked_parameters(list(parameters), source)
    if entries:
        text += "\n# What calibration may change:\n" + dumps_toml({"parameter": entries})
    return text


def read_parameters(path) -> list[dict]:
    """The ``[[parameter]]`` tables of a TOML file (``identify --parameters``): nothing else in it."""
    from ..input.schema import toml_file
    from ..system.inputs import TARGETS, read_text

    source = str(path)
    doc = toml_file(read_text(path, TARGETS), source, None)
    unknown = sorted(set(doc) - {"parameter"})
    if unknown or not doc.get("parameter"):
        raise ModelError(
            "is not a parameters file",
            file=source,
            field=unknown[0] if unknown else "parameter",
            valid="[[parameter]] tables only (name, and percent, bounds or fixed)",
        )
    return checked_parameters(doc["parameter"], source)


def tune_to_measured(identified, parameters, *, model, load, source: str, starts: int = 1) -> MeasuredTuning:
    """Calibrate ``model`` to what ``identified`` trusts, moving ``parameters``.

    Parameters
    ----------
    identified : ModelIdentification
        From :func:`flexshaft.analysis.identification.identify` with the model's modes.
    parameters : sequence of dict
        ``[[parameter]]`` tables (none: identification only, ``calibration`` None).
    model : str or Path
        The model file (the tuned file is written from it).
    load : callable
        ``load(path) -> Drivetrain``, the caller's way of loading it (trust, cache, mesh).
    source : str
        What the targets are called in errors and the result (``"measurement/c1-targets.toml"``).
    starts : int
        Starting points of the calibration.

    Returns
    -------
    MeasuredTuning

    Raises
    ------
    ModelError
        A parameter entry that is wrong; no trusted target (every mode unpaired or doubted); what
        calibration refuses.
    """
    from ..analysis.staged import calibrate_stages

    text = measured_targets(identified, parameters, source)
    if not parameters:
        return MeasuredTuning(identified, text)
    if not any(p.frequency_target for p in identified.pairing.pairs):
        raise ModelError(
            "no identified mode makes a target (each is unpaired or doubted: see the notes)",
            file=source,
            field="target",
            valid="runs in which at least one mode is identified without doubt and paired with the model's",
        )
    staged = calibrate_stages(loads_targets(text, source), load, model=model, starts=starts)
    return MeasuredTuning(identified, text, staged)
