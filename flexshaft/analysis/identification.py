"""From measured runs to calibration targets: the modes identified, paired with a model's.

:func:`identify` is ``flexshaft identify`` as a function: it reads the runs (any format
:func:`~flexshaft.measurement.signalfile.read_signals` reads: CSV, TDMS, MDF 3/4, HDF5, MATLAB), identifies
their modes (:func:`~flexshaft.measurement.identify.identify_modes`: covariance-driven stochastic subspace
identification with a stabilisation diagram, checked by frequency-domain decomposition) and, given a
model, pairs each with the model mode it measures (:func:`~flexshaft.measurement.pairing.pair_modes`),
so that :meth:`ModelIdentification.write_targets` writes the targets file ``flexshaft calibrate``
reads.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

from ..errors import ModelError
from ..measurement.identified import Identification
from ..measurement.pairing import Pairing, pair_modes, targets_toml
from ..system.threads import follows_policy
from .modal import ModalResult, modal_analysis

__all__ = ["ModelIdentification", "identify", "default_max_hz"]

#: Without ``max_hz``: the model's highest elastic mode times this (a model before calibration may be
#: off by half as much again), or without a model this fraction of the Nyquist frequency.
MODEL_MARGIN = 1.5
NYQUIST_WITH_MODEL = 0.8
NYQUIST_ALONE = 0.4


@dataclass(frozen=True)
class ModelIdentification:
    """The modes identified from measured runs and, given a model, their pairing with its modes.

    Attributes
    ----------
    identification : Identification
        The modes with their spread, the stabilisation diagrams, the method and the notes.
    pairing : Pairing or None
        Each mode's model mode (numbered as ``flexshaft modes`` numbers them), MAC and target
        tolerances; None without a model.
    """

    identification: Identification
    pairing: Pairing | None = None

    @property
    def modes(self) -> tuple:
        """The identified modes (:class:`~flexshaft.measurement.identified.IdentifiedMode`), by frequency."""
        return self.identification.modes

    def targets_toml(self) -> str:
        """The targets file's text (``[[target]]`` per paired mode; the user adds ``[[parameter]]``)."""
        if self.pairing is None:
            raise ModelError(
                "a targets file numbers modes as the model does",
                field="model",
                valid="identify(..., model=MODEL) before writing targets",
                has_value=False,
            )
        return targets_toml(self.pairing, self.identification) + "\n"

    def write_targets(self, path: str | PathLike, *, overwrite: bool = False) -> Path:
        """Write :meth:`targets_toml` to ``path`` atomically (an existing file only with ``overwrite``)."""
        from ..system.atomic import atomic_write_text

        return atomic_write_text(path, self.targets_toml(), overwrite=overwrite)

    def to_dict(self, *, diagrams: bool = False) -> dict:
        """A JSON-ready document: the identification (without the stabilisation diagrams unless asked)
        and the pairing."""
        doc = self.identification.to_dict(diagrams=diagrams)
        if self.pairing is not None:
            doc["pairing"] = self.pairing.to_dict()
        return doc

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), ensure_ascii=False)

    def table(self, *, verbose: bool = False) -> str:
        """The ``flexshaft identify`` table: the band searched and why, then each mode's frequency,
        damping, their spread, and the model mode paired (with a model); ``verbose`` puts the method
        paragraph first."""
        found, pairing = self.identification, self.pairing
        rows = ([found.method, ""] if verbose else []) + [found.band, ""]
        head = f"{'frequency Hz':>12}  {'± Hz':>8}  {'damping %':>9}  {'± %':>6}  {'runs':>4}  {'MPC':>5}"
        if pairing is not None:
            head += f"  {'mode':>4}  {'model Hz':>9}  {'MAC':>5}"
        rows.append(head)
        pairs = pairing.pairs if pairing is not None else [None] * len(found.modes)
        notes = list(found.notes)
        for m, p in zip(found.modes, pairs):
            f_std = m.frequency_std_hz
            if f_std != f_std:  # NaN: found in one run, the spread over its segments
                f_std = m.segment_frequency_std_hz
            z_std = m.damping_std if m.damping_std == m.damping_std else m.segment_damping_std
            # no spread from one estimate (one run of one segment): "-", as --json says null
            f_spread = f"{f_std:8.4f}" if f_std == f_std else f"{'-':>8}"
            z_spread = f"{100 * z_std:6.3f}" if z_std == z_std else f"{'-':>6}"
            row = (
                f"{m.frequency_hz:12.4f}  {f_spread}  {100 * m.damping_ratio:9.4f}  {z_spread}"
                f"  {m.found_in_runs:4d}  {m.mpc:5.3f}"
            )
            if p is not None:
                if p.mode is None:
                    row += f"  {'-':>4}  {'-':>9}  {'-':>5}"
                    notes.append(f"{m.frequency_hz:.4g} Hz unpaired: {p.reason}")
                else:
                    mac = f"{p.mac:5.3f}" if p.mac == p.mac else "    -"
                    row += f"  {p.mode:4d}  {p.model_frequency_hz:9.4f}  {mac}"
            rows.append(row)
            if m.frequency_doubt:
                notes.append(f"{m.frequency_hz:.4g} Hz is doubtful, no target: {m.frequency_doubt}")
            elif m.damping_doubt:
                notes.append(
                    f"{m.frequency_hz:.4g} Hz: its damping is doubtful, no damping target: {m.damping_doubt}"
                )
        rows.append("")
        rows.append("± : one standard deviation across runs (one run: across its segments; - : one estimate)")
        if notes:
            rows += ["", "notes:"] + [f"  {n}" for n in notes]
        return "\n".join(rows)

    def plot(self, run: int = 0):
        """The stabilisation diagram of run ``run`` (its poles over the model orders, the modes marked),
        a matplotlib Figure (never shown)."""
        from ..views.stabilisation import stabilisation_figure

        return stabilisation_figure(self.identification, run=run)


def default_max_hz(rate_hz: float, result: ModalResult | None = None) -> float:
    """The highest frequency identified when none is given, Hz.

    With a model: :data:`MODEL_MARGIN` times its highest elastic mode, at most
    :data:`NYQUIST_WITH_MODEL` of the Nyquist frequency; without: :data:`NYQUIST_ALONE` of it.
    ``rate_hz`` is the slowest run's sampling rate.
    """
    nyquist = rate_hz / 2
    elastic = [] if result is None else [f for f, r in zip(result.frequencies_hz, result.rigid) if not r]
    if elastic:
        return min(MODEL_MARGIN * max(elastic), NYQUIST_WITH_MODEL * nyquist)
    return NYQUIST_ALONE * nyquist


def _modal(model) -> ModalResult | None:
    if model is None or isinstance(model, ModalResult):
        return model
    from ..model.components import Drivetrain

    if isinstance(model, str | PathLike):
        from ..input.modelfile import load_model
        from .convergence import meshed_for_own_range

        model = meshed_for_own_range(load_model(model))  # as every command works on it
    if not isinstance(model, Drivetrain):
        raise ModelError(
            "is not a model",
            field="model",
            valid="a Drivetrain, its ModalResult or a model file's path",
            has_value=False,
        )
    return modal_analysis(model)


@follows_policy
def identify(
    runs,
    channels=None,
    *,
    model=None,
    stations: dict | None = None,
    max_hz: float | None = None,
    min_hz: float | None = None,
    orders=None,
    references=None,
    segments: int | None = None,
    units: dict | None = None,
    time_column: str | None = None,
    group: str | None = None,
    rate: float | None = None,
) -> ModelIdentification:
    """Identify the modes of measured runs and pair them with a model's (``flexshaft identify``).

    Parameters
    ----------
    runs : path, or sequence of paths, Run, SignalTable or (time, columns, units)
        One or more runs. A path is read by :func:`~flexshaft.measurement.signalfile.read_signals` (its suffix
        says the format) with ``channels``, ``units``, ``time_column``, ``group`` and ``rate``.
    channels : sequence of str, optional
        The channels to use (default: every channel of the first run).
    model : Drivetrain, ModalResult or path, optional
        The model to pair with. A model file is loaded without trusting code (use
        :func:`flexshaft.load_model` with ``allow_code`` and pass the model for one that has some).
    stations : dict of str to str, optional
        Channel -> model station, for channels measuring a station's rotation (speed or angle): the
        pairing then also needs a MAC >= :data:`~flexshaft.measurement.pairing.MIN_MAC`, and where every
        station is measured the targets carry the shape. Only with ``model``.
    max_hz : float, optional
        The highest frequency of interest, Hz (default :func:`default_max_hz`).
    min_hz : float, optional
        The lowest frequency of interest, Hz (default: half the model's first elastic mode; without a
        model what the record resolves: :func:`~flexshaft.measurement.identify.default_min_hz`).
    orders, references, segments
        As :func:`~flexshaft.measurement.identify.identify_modes`.
    units, time_column, group, rate
        How paths are read (:func:`~flexshaft.measurement.signalfile.read_signals`).

    Returns
    -------
    ModelIdentification

    Raises
    ------
    ModelError
        An unreadable run, a channel or station that does not exist, ``stations`` without a model,
        and everything :func:`~flexshaft.measurement.identify.identify_modes` refuses.
    """
    from ..measurement.signalfile import read_signals

    if stations and model is None:
        raise ModelError(
            "pairs channels with a model's stations", field="stations", valid="stations with a model"
        )
    if isinstance(runs, str | PathLike):
        runs = [runs]
    if isinstance(runs, list | tuple) and any(isinstance(r, str | PathLike) for r in runs):
        columns = None if channels is None else list(channels)
        runs = [
            read_signals(r, columns=columns, units=units, time_column=time_column, group=group, rate=rate)
            if isinstance(r, str | PathLike)
            else r
            for r in runs
        ]
    from ..measurement.identify import identify_modes, run_rates

    result = _modal(model)
    if max_hz is None:
        max_hz = default_max_hz(min(run_rates(runs)), result)
    elastic = [] if result is None else [f for f, r in zip(result.frequencies_hz, result.rigid) if not r]
    found = identify_modes(
        runs,
        channels=None if channels is None else list(channels),
        max_hz=max_hz,
        min_hz=min_hz,
        lowest_mode_hz=min(elastic) if elastic else None,
        orders=orders,
        references=references,
        segments=segments,
    )
    if result is None:
        return ModelIdentification(found)
    pairing = pair_modes(found, result, stations)
    return ModelIdentification(_model_notes(found, pairing, result), pairing)


def _model_notes(found: Identification, pairing: Pairing, result: ModalResult) -> Identification:
    """The notes with what the model says: a lightly damped mode the model has is no harmonic."""
    from dataclasses import replace

    from ..measurement.identify import harmonic_note

    notes = list(found.notes)
    for p in pairing.pairs:
        note = harmonic_note(p.identified)
        if p.mode is not None and note in notes:
            model_zeta = result.damping_ratios[p.mode]
            notes[notes.index(note)] = (
                f"the mode at {p.identified.frequency_hz:.6g} Hz has a damping ratio of "
                f"{100 * p.identified.damping_ratio:.2g} %, less than a drivetrain's usual 0.1 to 5 %; the "
                f"model has mode {p.mode} there ({p.model_frequency_hz:.6g} Hz, "
                f"{100 * model_zeta:.2g} % damping)"
            )
    return replace(found, notes=tuple(notes))
