"""Universal file format (UFF/UNV) exports for modal-test software (Simcenter Testlab, ME'scope, ...).

- :func:`write_modes_uff`: dataset 164 (units: SI), dataset 2411 (the model's stations as nodes on
  the shaft axis, x in m, double precision; SDynPy reads this one and skips the older 15) and one
  dataset 55 per mode (normal modes: frequency in Hz, modal mass 1 kg·m², the modal viscous damping
  ratio as a fraction; the mass-normalised shape at each node as its six DOFs, the torsion θx in the
  fourth - a torsion model has nothing in the others). Each mode's ID lines state the damping the
  results carry (line 3) and the frequency to the last bit (line 4: the record holds E13.5).
- :func:`write_body_uff`: the same datasets for a flexible body's free-free modes on the part's mesh
  nodes (what a free-free modal test of the part measures).
- :func:`write_frf_uff`: dataset 164 and one dataset 58 per output and input (function type 4,
  frequency response; complex double ordinates; abscissa Hz, uneven where the grid is), response and
  reference at their station's node in direction 4 (θx), each axis labelled with its unit.

The files are written by pyuff (the ``uff`` extra, imported here only), to a temporary folder and
then moved into place whole (:func:`~flexshaft.system.atomic.atomic_write_bytes`): nothing
half-written, nothing replaced without ``overwrite``.
"""

from __future__ import annotations

import gc
import tempfile
import warnings
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..measurement.files.uff import FREQUENCY_DATA_TYPE, FRF_FUNCTION  # the reader's codes: one place
from ..model.describe import damping_line
from ..system.atomic import atomic_write_bytes

__all__ = [
    "write_modes_uff",
    "write_body_uff",
    "write_frf_uff",
    "uff_module",
    "UFF_SUFFIXES",
    "TORSION_DIRECTION",
]

#: The suffixes a UFF file goes by.
UFF_SUFFIXES = (".uff", ".unv")
#: UFF's direction code of a rotation about x (the shaft's torsion).
TORSION_DIRECTION = 4
# UFF's specific data types (dataset 58): 8 displacement, 11 velocity, 13 excitation force, 1 general.
_DATA_TYPE = {"rad": 8, "rad/s": 11, "N·m": 1}


def uff_module():
    """pyuff, or the one-line error naming the extra that brings it."""
    try:
        import pyuff
    except ImportError:
        raise ModelError(
            "needs pyuff to write a universal file", field="uff", valid="pip install 'flexshaft[uff]'"
        ) from None
    return pyuff


def _units(pyuff) -> dict:
    """Dataset 164: SI (m, N, °C with its offset to K), as its units code 1 says."""
    return pyuff.prepare_164(
        units_code=1, units_description="SI", temp_mode=1, length=1.0, force=1.0, temp=1.0, temp_offset=273.15
    )


def _written(pyuff, sets: list, path, overwrite: bool) -> Path:
    """Write the datasets through pyuff into a temporary folder, then into place whole."""
    with tempfile.TemporaryDirectory(prefix="flexshaft-uff-") as tmp, warnings.catch_warnings():
        # pyuff leaves its file to the garbage collector: closed (and flushed) by the collection below
        warnings.simplefilter("ignore", ResourceWarning)
        scratch = Path(tmp) / "out.uff"
        uff = pyuff.UFF(str(scratch))
        uff.write_sets(sets, mode="overwrite")
        del uff
        gc.collect()
        data = scratch.read_bytes()
    return atomic_write_bytes(path, data, overwrite=overwrite)


def _check_suffix(path) -> None:
    if Path(path).suffix.lower() not in UFF_SUFFIXES:
        raise ModelError("unknown file type", field="uff", value=str(path), valid="FILE.uff or FILE.unv")


def write_modes_uff(result, path, *, modes=None, overwrite: bool = False) -> Path:
    """The modes as a universal file: units (164), the stations as nodes (2411), each mode (55).

    Parameters
    ----------
    result : ModalResult
        The modes (:func:`flexshaft.modal_analysis`); their damping ratios are the damped solve's
        where there is one.
    path : str or Path
        ``FILE.uff`` or ``FILE.unv``.
    modes : sequence of int, optional
        The modes written (default: every mode of ``result``, rigid-body ones included at 0 Hz).
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path
        The file written.
    """
    _check_suffix(path)
    pyuff = uff_module()
    model = result.model
    stations = list(model.stations)
    x = np.array([model.x[st.node] for st in stations], dtype=float)
    # mass-normalised shapes at the stations, every DOF of each station node (θx alone in torsion)
    full = model.dofs == "full"
    first = model.node_dof([st.node for st in stations], "θx") - (3 if full else 0)
    kept = np.arange(result.count) if modes is None else np.asarray(modes, dtype=int)
    shapes = result.node_shapes
    six = np.zeros((len(stations), 6, kept.size))
    if full:
        for j in range(6):
            six[:, j] = shapes[np.ix_(first + j, kept)]
    else:
        six[:, 3] = shapes[np.ix_(first, kept)]
    sets = _mode_sets(
        pyuff,
        f"flexshaft {model.drivetrain.name}",
        x,
        six,
        kept,
        result.frequencies_hz[kept],
        result.damping_ratios[kept],
        damping_line(model.drivetrain),  # the results' damping, stated in each mode's ID lines
    )
    return _written(pyuff, sets, path, overwrite)


def write_body_uff(reduction, path, *, overwrite: bool = False) -> Path:
    """A flexible body's free-free modes as a universal file: units (164), the part's mesh nodes (2411),
    each mode (55) - what a free-free modal test of the part (hung on soft springs, struck with a
    hammer) measures.

    Parameters
    ----------
    reduction : PartReduction
        The reduced part (:func:`flexshaft.reduce_part`): its body's free-free modes (mass-normalised
        in the body's coordinates, recovered on every mesh node through T), their frequencies and
        the damping ratio set on each; the part model's node positions (m).
    path : str or Path
        ``FILE.uff`` or ``FILE.unv``.
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path
        The file written.
    """
    _check_suffix(path)
    comp, body = reduction.component, reduction.body
    if comp.sections is None:
        raise ModelError(
            "a shaft given by numbers has no length: its mesh has no positions in metres",
            component=comp.name,
            field="path",
            value=str(path),
            valid="a part given by segments or CAD, or another format (npz, json, mat, op4, pch)",
        )
    pyuff = uff_module()
    d = 6 if body.dofs == "full" else 1
    x = np.asarray(reduction.part_model.x, dtype=float)
    recovered = np.asarray(body.T @ body.free_modes).reshape(x.size, d, -1)
    six = np.zeros((x.size, 6, recovered.shape[2]))
    if d == 6:
        six[:] = recovered
    else:
        six[:, 3] = recovered[:, 0]
    count = recovered.shape[2]
    return _written(
        pyuff,
        _mode_sets(
            pyuff,
            f"flexshaft body {body.name}",
            x,
            six,
            np.arange(count),
            body.free_hz,
            body.damping_ratios,
            "damping: the body's own, per free-free mode",
        ),
        path,
        overwrite,
    )


def _mode_sets(pyuff, title: str, x, six, numbers, frequencies_hz, damping, stated: str) -> list:
    """The datasets of a modes file: units (164), nodes 1, 2, ... at ``x`` on the axis (2411) and one
    dataset 55 per mode (``six``: each node's six DOFs per mode, shape (nodes, 6, modes))."""
    nodes = np.arange(1, x.size + 1)
    zero = np.zeros(x.size)
    sets = [
        _units(pyuff),
        pyuff.prepare_2411(
            node_nums=[int(n) for n in nodes],
            def_cs=[0] * x.size,  # global coordinates (pyuff wants lists of ints here)
            disp_cs=[0] * x.size,
            color=[1] * x.size,
            x=x,
            y=zero,
            z=zero,
        ),
    ]
    for i, k in enumerate(numbers):
        sets.append(
            pyuff.prepare_55(
                id1=f"{title}: mode {k}"[:80],
                id2="normal mode, mass-normalised (modal mass 1 kg*m^2), SI units",
                id3=stated[:80],  # ID lines are 80 characters
                # the frequency to the last bit (the record's E13.5 holds six digits), for any reader
                id4=f"frequency {float(frequencies_hz[i])!r} Hz",
                id5="NONE",
                model_type=1,
                analysis_type=2,
                data_ch=3,
                spec_data_type=8,
                data_type=2,
                n_data_per_node=6,
                node_nums=nodes,
                load_case=1,
                mode_n=int(k) + 1,
                freq=float(frequencies_hz[i]),
                modal_m=1.0,
                modal_damp_vis=float(damping[i]) if np.isfinite(damping[i]) else 0.0,
                modal_damp_his=0.0,
                **{f"r{j + 1}": np.asarray(six[:, j, i], dtype=float) for j in range(6)},
            )
        )
    return sets


def write_frf_uff(resp, model, path, *, overwrite: bool = False) -> Path:
    """A frequency response as a universal file: units (164) and one FRF (58) per output and input.

    Parameters
    ----------
    resp : FrequencyResponse
        The response (:func:`flexshaft.analysis.statespace.frequency_response`).
    model : AssembledModel
        Its model: the stations give the nodes (numbered as :func:`write_modes_uff` numbers them).
    path : str or Path
        ``FILE.uff`` or ``FILE.unv``.
    overwrite : bool
        Replace an existing file.
    """
    _check_suffix(path)
    pyuff = uff_module()
    names = [st.name for st in model.stations]
    f = np.asarray(resp.frequencies_hz, dtype=float)
    even = f.size > 1 and np.allclose(np.diff(f), f[1] - f[0], rtol=1e-12, atol=0.0)

    def node_of(signal: str) -> int:
        what = signal.partition(":")[2] or signal
        if what in names:
            return names.index(what) + 1
        comp = [c.name for c in model.drivetrain.components]
        if what in comp:  # a component's torque: at its first station
            start = int(model.start_node[comp.index(what)])
            return next(i + 1 for i, st in enumerate(model.stations) if st.node >= start)
        return 0

    stated = damping_line(model.drivetrain)
    sets = [_units(pyuff)]
    for i, (out, unit) in enumerate(zip(resp.outputs, resp.output_units)):
        for j, (inp, iunit) in enumerate(zip(resp.inputs, resp.input_units)):
            sets.append(
                pyuff.prepare_58(
                    binary=1,  # 58b: the ordinates and abscissae as doubles, to the last bit
                    id1=f"flexshaft FRF {out} / {inp}",
                    id2=f"{unit} per {iunit}",
                    id3=stated[:80],
                    id4="NONE",
                    id5="NONE",
                    func_type=FRF_FUNCTION,
                    ver_num=1,
                    load_case_id=0,
                    rsp_ent_name="flexshaft",
                    rsp_node=node_of(out),
                    rsp_dir=TORSION_DIRECTION,
                    ref_ent_name="flexshaft",
                    ref_node=node_of(inp),
                    ref_dir=TORSION_DIRECTION,
                    ord_data_type=6,
                    num_pts=f.size,
                    abscissa_spacing=1 if even else 0,
                    abscissa_min=float(f[0]),
                    abscissa_inc=float(f[1] - f[0]) if even else 0.0,
                    abscissa_spec_data_type=FREQUENCY_DATA_TYPE,
                    abscissa_axis_units_lab="Hz",
                    ordinate_spec_data_type=_DATA_TYPE.get(unit, 1),
                    ordinate_axis_units_lab=unit,
                    orddenom_spec_data_type=13,
                    orddenom_axis_units_lab=iunit,
                    data=np.asarray(resp.H[:, i, j], dtype=complex),
                    x=f,
                )
            )
    return _written(pyuff, sets, path, overwrite)
