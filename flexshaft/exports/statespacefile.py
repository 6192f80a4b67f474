"""Linear-system files: a state space (A, B, C, D) as .npz, .mat or .json, a frequency response as .npz.

Each file carries its names and units: the inputs (torques, N·m), the outputs with their units, the
states, the modes kept and their frequencies (Hz). In an .npz or .mat file they are one JSON string
(``metadata``; ``flexshaft_metadata`` in .mat), so ``np.load(path)`` reads it all without pickles.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..system.atomic import atomic_write_bytes, atomic_write_text

__all__ = ["STATE_SPACE_SUFFIXES", "state_space_metadata", "write_state_space", "frf_npz"]

#: The suffixes :func:`write_state_space` writes (any case).
STATE_SPACE_SUFFIXES = (".npz", ".mat", ".json")


def state_space_metadata(ss, damping: str | None = None) -> dict:
    """The names and units of a :class:`~flexshaft.analysis.statespace.StateSpace` (time s, input N·m),
    and ``damping``, the damping it carries in words (:func:`flexshaft.model.describe.damping_line`)."""
    return {
        "format": "flexshaft-state-space",
        "units": {"input": "N·m", "time": "s"},
        "inputs": list(ss.inputs),
        "outputs": list(ss.outputs),
        "input_units": list(ss.input_units),
        "output_units": list(ss.output_units),
        "states": list(ss.states),
        "modes": ss.modes.tolist(),
        "frequencies_hz": ss.frequencies_hz.tolist(),
    } | ({} if damping is None else {"damping": damping})


def write_state_space(ss, path, *, overwrite: bool = False, damping: str | None = None) -> Path:
    """Write a state space to ``path``: its suffix picks .npz, .mat or .json.

    Parameters
    ----------
    ss : StateSpace
        A, B, C, D in SI (states: modal coordinates and their rates; inputs N·m).
    path : str or Path
        ``FILE.npz`` (arrays ``A``, ``B``, ``C``, ``D``, ``metadata``), ``FILE.mat`` (the same,
        ``flexshaft_metadata``) or ``FILE.json`` (the metadata with the matrices as lists).
    overwrite : bool
        Allow replacing an existing file.
    damping : str, optional
        The damping the system carries, in words, stored as the metadata's ``damping``.

    Returns
    -------
    Path
        The file written.
    """
    meta = state_space_metadata(ss, damping)
    out = str(path)
    if out.lower().endswith(".npz"):
        buf = io.BytesIO()
        np.savez(buf, A=ss.A, B=ss.B, C=ss.C, D=ss.D, metadata=np.array(json.dumps(meta, ensure_ascii=False)))
        return atomic_write_bytes(out, buf.getvalue(), overwrite=overwrite)
    if out.lower().endswith(".mat"):
        from scipy.io import savemat

        buf = io.BytesIO()
        savemat(
            buf,
            {
                "A": ss.A,
                "B": ss.B,
                "C": ss.C,
                "D": ss.D,
                "flexshaft_metadata": json.dumps(meta, ensure_ascii=False),
            },
        )
        return atomic_write_bytes(out, buf.getvalue(), overwrite=overwrite)
    if out.lower().endswith(".json"):
        doc = meta | {k: getattr(ss, k).tolist() for k in ("A", "B", "C", "D")}
        return atomic_write_text(out, json.dumps(doc, ensure_ascii=False), overwrite=overwrite)
    raise ModelError("unknown file type", field="path", value=out, valid="FILE.npz, FILE.mat or FILE.json")


def frf_npz(resp, doc: dict) -> bytes:
    """A frequency response as an .npz: ``frequency_hz`` (Hz), complex ``H`` [frequency, output, input],
    ``metadata``.

    ``metadata`` is a JSON string (as in a state-space .npz): the input and output names, their units
    (H is in output unit per input unit) and the peaks, from ``doc`` (the response's ``to_dict()``:
    its keys ``inputs``, ``outputs``, ``units``, ``peaks``).
    """
    meta = {
        "format": "flexshaft-frequency-response",
        "inputs": doc["inputs"],
        "outputs": doc["outputs"],
        "units": doc["units"] | {"H": "output unit per input unit, e.g. rad/s per N·m"},
        "shape": "H[frequency, output, input]",
        "peaks": doc["peaks"],
    }
    buf = io.BytesIO()
    np.savez(
        buf,
        frequency_hz=np.asarray(resp.frequencies_hz, dtype=float),
        H=np.asarray(resp.H, dtype=complex),
        metadata=np.array(json.dumps(meta, ensure_ascii=False)),
    )
    return buf.getvalue()
