"""The linear drivetrain as a Functional Mock-up Unit (FMI 2.0 or 3.0) for Simulink, Modelica tools and FMPy.

An FMU is a zip: ``modelDescription.xml`` (the variables, their units, both interfaces) and C
sources, compiled here for the running platform with the system's C compiler when one is found.
One FMU offers both interfaces:

- **co-simulation**: each communication step is one exact zero-order-hold step of the modal state
  space, [[Ad, Bd], [0, I]] = exp([[A, B], [0, 0]]·h), for any step the importer takes (the matrix
  exponential is computed in the FMU, again only when the step changes). Inputs held over each
  step, as flexshaft's own ``simulate`` holds them, so the two agree to round-off;
- **model exchange**: the continuous state space ẋ = A·x + B·u, y = C·x + D·u for the importer's
  integrator.

The state is the drivetrain's modal coordinates and their rates (mass-normalised modes, as
``flexshaft statespace`` writes them). Inputs are torques at named stations (N·m), outputs
``angle:STATION`` (rad), ``speed:STATION`` (rad/s, shown in rpm) and ``torque:COMPONENT`` (N·m).
Parameters, fixed once the FMU is initialised:

- ``initial_speed`` (rad/s at the driving station): the line starts turning rigidly at that speed;
- ``damping_variant``: 1 ``parts`` (each part's own damping, dampers as given) or 2 ``system``
  (Rayleigh damping fitted to the system damping ratio on the first two elastic modes); both
  damping matrices are in the FMU;
- ``damping_scale``: multiplies the chosen variant's modal damping.

Nonlinear elements (slip, backlash, torque curves) are linearised about zero, as every linear
analysis takes them; the FMU's description says so.

Without a compiler (or on a platform other than Linux and macOS) the FMU carries its sources only,
which FMPy (``fmpy.build.build_platform_binary`` on the unpacked FMU) or a user's ``cc -shared``
builds; :attr:`FmuBuild.note` says why.
"""

from __future__ import annotations

import hashlib
import io
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
import uuid
import zipfile
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..system.atomic import atomic_write_bytes
from .fmudescription import VARIANT_ITEMS, description_xml, value_references, variables

__all__ = ["FmuSystem", "FmuBuild", "fmu_system", "write_fmu", "FMI_VERSIONS"]

#: The FMI versions :func:`write_fmu` writes.
FMI_VERSIONS = (2, 3)
#: Seconds a compile may take before it is given up (a model of thousands of states compiles in ~30 s).
COMPILE_TIMEOUT_S = 600
_HEADERS = {
    2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
    3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"),
}


@dataclass(frozen=True)
class FmuSystem:
    """What an FMU carries: the drivetrain's modal state space under each damping variant (SI).

    Attributes
    ----------
    variants : tuple of StateSpace
        The same modes under each damping variant, in :data:`VARIANT_ITEMS` order: A's damping
        block and the torque outputs' damper rows are what differ.
    spin : ndarray or None
        The state per rad/s of speed at the driving station, the line turning rigidly; None: the
        line cannot spin (no rigid-body mode), and the FMU has no ``initial_speed``.
    drive : str
        The driving station, where ``initial_speed`` is read.
    system_ratio : float
        The system variant's damping ratio (fraction).
    name, description : str
        The model's name, and what the FMU is (its damping and linearisation stated).
    """

    variants: tuple
    spin: np.ndarray | None
    drive: str
    system_ratio: float
    name: str
    description: str

    @property
    def ss(self):
        """The system under per-part damping (variant 1): its modes, inputs, outputs and B, D."""
        return self.variants[0]

    @property
    def step(self) -> float:
        """The default communication step, s: a tenth of the period of the highest mode kept."""
        f = float(self.ss.frequencies_hz.max())
        return 0.1 / f if f > 0 else 1e-3


@dataclass(frozen=True)
class FmuBuild:
    """An FMU written by :func:`write_fmu`.

    Attributes
    ----------
    path : Path
    fmi : int
        The FMI version, 2 or 3.
    identifier : str
        The model identifier (the binary's and the C functions' name).
    platform : str or None
        The platform the binary is built for (``linux64``, ``x86_64-linux``, ...); None: sources only.
    compiler : str or None
        The compiler used.
    note : str or None
        Why the FMU carries sources only, when it does.
    size_bytes : int
    build_seconds : float
        Generating, compiling and zipping, s.
    states : int
    inputs, outputs : tuple of str
        The FMU's input and output variables (as ``statespace`` names them).
    damping_variant : str
        The ``damping_variant`` parameter's start value, ``"parts"`` or ``"system"``.
    """

    path: Path
    fmi: int
    identifier: str
    platform: str | None
    compiler: str | None
    note: str | None
    size_bytes: int
    build_seconds: float
    states: int
    inputs: tuple
    outputs: tuple
    damping_variant: str

    def table(self) -> str:
        """The ``flexshaft fmu`` summary."""
        what = (
            f"binary for {self.platform} ({self.compiler}) and sources" if self.platform else "sources only"
        )
        lines = [
            f"FMU (FMI {self.fmi}.0, model exchange and co-simulation): {self.path}",
            f"  {_count(self.states, 'state')}, {_count(len(self.inputs), 'input')}, "
            f"{_count(len(self.outputs), 'output')}; {what}",
            f"  {self.size_bytes / 1024:.0f} KiB, built in {self.build_seconds:.1f} s",
        ]
        if self.note:
            lines.append(f"  note: {self.note}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """The ``--json`` document (size in bytes, time in s)."""
        return {
            "path": str(self.path),
            "fmi_version": f"{self.fmi}.0",
            "model_identifier": self.identifier,
            "platform": self.platform,
            "compiler": self.compiler,
            "note": self.note,
            "size_bytes": self.size_bytes,
            "build_seconds": self.build_seconds,
            "states": self.states,
            "inputs": list(self.inputs),
            "outputs": list(self.outputs),
            "damping_variant": self.damping_variant,
            "units": {"input": "N·m", "time": "s", "size": "bytes"},
        }


def _count(n: int, what: str) -> str:
    return f"{n} {what}{'' if n == 1 else 's'}"


def fmu_system(drivetrain, inputs=None, outputs=None, *, max_hz=None, system_ratio=None) -> FmuSystem:
    """The drivetrain's modal state space under both damping variants, for :func:`write_fmu`.

    Parameters
    ----------
    drivetrain : Drivetrain
    inputs : sequence of str, optional
        Stations driven by a torque (N·m); default the driving end and the far end.
    outputs : sequence of str, optional
        ``angle:``, ``speed:`` or ``torque:`` signals; default the speeds of both ends.
    max_hz : float, optional
        Keep only the modes up to this frequency, Hz (the rigid-body modes always).
    system_ratio : float, optional
        The system damping variant's ratio on the first two elastic modes, a fraction; default the
        bench's measured 0.53 %.
    """
    from ..analysis.modal import response_modes
    from ..analysis.statespace import state_space
    from ..analysis.systemdamping import SYSTEM_DAMPING_RATIO, system_damped
    from ..model.assembly import assemble
    from ..model.describe import linearised_line
    from ..validation import FRACTION_VALID, check_real

    ratio = SYSTEM_DAMPING_RATIO if system_ratio is None else system_ratio
    try:
        ratio = check_real(ratio, "system_ratio", "", lo=0.0, hi=1.0, hi_open=True)
    except ModelError as err:
        raise ModelError(err.message, field="system_ratio", value=ratio, valid=FRACTION_VALID) from None
    model = assemble(drivetrain)
    ends = [model.stations[0].name, model.stations[-1].name]
    inputs = list(inputs or dict.fromkeys(ends))
    outputs = list(outputs or [f"speed:{s}" for s in dict.fromkeys(ends)])
    result = response_modes(model)
    ss = state_space(result, inputs, outputs, max_hz=max_hz)
    damped = assemble(system_damped(drivetrain, ratio))
    # The system variant keeps the stiffness and inertia, so the same modes diagonalise it; only its
    # damping block (and the dampers in its torque outputs) differ.
    if (damped.K != model.K).nnz or (damped.M != model.M).nnz:
        raise ModelError("system damping changed the stiffness or inertia", field="system_ratio", value=ratio)
    system = state_space(replace(result, model=damped, damped=None), inputs, outputs, max_hz=max_hz)
    spin = _spin(result, ss, inputs, model.stations[0].name, max_hz)
    linear = linearised_line(drivetrain)
    description = (
        f"{drivetrain.name}: linear torsional drivetrain from flexshaft, {len(ss.modes)} modes "
        f"(state: modal coordinates and rates), damping per parameter damping_variant"
        + ("" if linear is None else "; " + linear)
    )
    return FmuSystem(
        variants=(ss, system),
        spin=spin,
        drive=model.stations[0].name,
        system_ratio=float(ratio),
        name=drivetrain.name,
        description=description,
    )


def _spin(result, ss, inputs, drive: str, max_hz) -> np.ndarray | None:
    """The state per rad/s at ``drive``, the line turning rigidly (the rigid-body mode the drive's
    speed reads most, as ``simulate`` starts a spinning line); None without a rigid-body mode."""
    from ..analysis.statespace import state_space

    m = ss.A.shape[0] // 2
    row = state_space(result, inputs, [f"speed:{drive}"], max_hz=max_hz).C[0, m:]
    rigid = np.flatnonzero(result.rigid[ss.modes])
    if rigid.size == 0:
        return None
    k = rigid[np.argmax(np.abs(row[rigid]))]
    if row[k] == 0:
        return None
    spin = np.zeros(2 * m)
    spin[m + k] = 1.0 / row[k]
    return spin


def write_fmu(
    system: FmuSystem,
    path,
    *,
    fmi: int = 2,
    compile: bool = True,
    default_variant: str = "parts",
    overwrite: bool = False,
    say=None,
) -> FmuBuild:
    """Write ``system`` as an FMU, compiled for this platform when a C compiler is found.

    Parameters
    ----------
    system : FmuSystem
        From :func:`fmu_system`.
    path : str or Path
        ``FILE.fmu``; its stem (made a C identifier) is the model identifier.
    fmi : {2, 3}
        The FMI version.
    compile : bool
        Build the binary (False: sources only).
    default_variant : {"parts", "system"}
        The ``damping_variant`` parameter's start value.
    overwrite : bool
        Allow replacing an existing file.
    say : callable, optional
        ``say(text)``: a line on what is being done (the compile takes seconds).

    Returns
    -------
    FmuBuild
    """
    t0 = time.perf_counter()
    out = Path(path)
    if out.suffix.lower() != ".fmu":
        raise ModelError("unknown file type", field="path", value=str(path), valid="FILE.fmu")
    if fmi not in FMI_VERSIONS:
        raise ModelError("unknown FMI version", field="fmi", value=fmi, valid="2 or 3")
    names = [n for n, _ in VARIANT_ITEMS]
    if default_variant not in names:
        raise ModelError(
            "unknown damping variant", field="damping", value=default_variant, valid=" or ".join(names)
        )
    identifier = _identifier(out.stem)
    vars_ = variables(system, default_variant=names.index(default_variant) + 1)
    data_c, data_h = model_sources(system)
    guid = "{" + str(uuid.UUID(hashlib.sha256(data_c.encode()).hexdigest()[:32])) + "}"
    data_h = data_h.replace("@GUID@", guid)
    stamp = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    files = {
        "modelDescription.xml": description_xml(
            system, vars_, fmi=fmi, identifier=identifier, guid=guid, stamp=stamp
        )
    }
    sources = {"model_data.c": data_c, "model_data.h": data_h} | _fixed_sources(fmi)
    files |= {f"sources/{k}": v for k, v in sources.items()}
    if fmi == 3:
        files["sources/buildDescription.xml"] = _build_description(identifier)
    files["documentation/licenses/FMI-LICENSE.txt"] = _resource("vendor/LICENSE.txt")
    target, compiler, note, binary = None, None, None, None
    if compile:
        target, compiler, note, binary = _compile(sources, identifier, fmi, say)
    else:
        note = "sources only, as asked (no compile)"
    blob = _zip(files, {} if binary is None else {f"binaries/{target}/{identifier}{_suffix()}": binary})
    written = atomic_write_bytes(str(out), blob, overwrite=overwrite)
    ss = system.ss
    return FmuBuild(
        path=written,
        fmi=fmi,
        identifier=identifier,
        platform=target if binary is not None else None,
        compiler=compiler if binary is not None else None,
        note=note,
        size_bytes=len(blob),
        build_seconds=time.perf_counter() - t0,
        states=ss.A.shape[0],
        inputs=tuple(ss.inputs),
        outputs=tuple(ss.outputs),
        damping_variant=default_variant,
    )


def _identifier(stem: str) -> str:
    """A C identifier from a file name: other characters become ``_``, a leading digit gets one."""
    ident = re.sub(r"[^A-Za-z0-9_]", "_", stem) or "drivetrain"
    return "_" + ident if ident[0].isdigit() else ident


def _c_array(name: str, values) -> str:
    """A C array of doubles; %.17g keeps every double exactly (round trip)."""
    flat = np.asarray(values, dtype=float).ravel()
    if flat.size == 0:
        flat = np.zeros(1)  # C has no empty arrays; the sizes say none is read
    body = ",\n".join(", ".join(f"{v:.17g}" for v in flat[k : k + 4]) for k in range(0, flat.size, 4))
    return f"const double {name}[{flat.size}] = {{\n{body}\n}};\n"


def model_sources(system: FmuSystem) -> tuple[str, str]:
    """``model_data.c`` (the matrices) and ``model_data.h`` (the sizes and value references; its
    GUID left as ``@GUID@``)."""
    ss = system.ss
    n, nu, ny = ss.A.shape[0], len(ss.inputs), len(ss.outputs)
    m = n // 2
    for v in system.variants:
        if not (np.all(np.isfinite(v.A)) and np.all(np.isfinite(v.C))):
            raise ModelError("the state space is not finite", field="state space")
    omega2 = -np.diag(ss.A[m:, :m])
    damping = np.stack([-v.A[m:, m:] for v in system.variants])
    spin = np.zeros(n) if system.spin is None else system.spin
    data_c = (
        "/* Generated by flexshaft: the drivetrain's modal state space (SI). Row-major. */\n"
        '#include "model_data.h"\n\n'
        + _c_array("fs_omega2", omega2)
        + _c_array("fs_damping", damping)
        + _c_array("fs_Bq", ss.B[m:])
        + _c_array("fs_C", np.stack([v.C for v in system.variants]))
        + _c_array("fs_D", ss.D)
        + _c_array("fs_spin", spin)
    )
    vr = value_references(nu, ny, n)
    speed = vr["initial_speed"] if system.spin is not None else 0xFFFFFFFF  # none: no reference reaches it
    data_h = "\n".join(
        [
            "/* Generated by flexshaft: sizes, value references and GUID of this FMU. */",
            "#ifndef FLEXSHAFT_MODEL_DATA_H",
            "#define FLEXSHAFT_MODEL_DATA_H",
            f"#define FS_NM {m}",
            f"#define FS_NX {n}",
            f"#define FS_NU {nu}",
            f"#define FS_NY {ny}",
            f"#define FS_NVARIANTS {len(system.variants)}",
            '#define FS_GUID "@GUID@"',
            *(f"#define FS_VR_{k.upper()} {vr[k]}u" for k in ("input", "output", "state", "derivative")),
            f"#define FS_VR_SPEED {speed}u",
            f"#define FS_VR_SCALE {vr['damping_scale']}u",
            f"#define FS_VR_VARIANT {vr['damping_variant']}u",
            "extern const double fs_omega2[], fs_damping[], fs_Bq[], fs_C[], fs_D[], fs_spin[];",
            "#endif",
            "",
        ]
    )
    return data_c, data_h


def _resource(name: str) -> str:
    return resources.files("flexshaft.exports").joinpath("fmi", name).read_text(encoding="utf-8")


def _fixed_sources(fmi: int) -> dict[str, str]:
    """The C runtime, the FMI functions and the standard's headers (vendored, BSD-2-Clause)."""
    out = {name: _resource(name) for name in ("drivetrain.c", "drivetrain.h", f"fmi{fmi}.c")}
    return out | {name: _resource(f"vendor/{name}") for name in _HEADERS[fmi]}


def _build_description(identifier: str) -> str:
    files = "".join(f'<SourceFile name="{n}"/>' for n in ("model_data.c", "drivetrain.c", "fmi3.c"))
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<fmiBuildDescription fmiVersion="3.0">\n'
        f'  <BuildConfiguration modelIdentifier="{identifier}"><SourceFileSet language="C99">{files}'
        "</SourceFileSet></BuildConfiguration>\n</fmiBuildDescription>\n"
    )


def _platform(fmi: int) -> str | None:
    """The binaries folder for this platform (FMI 2: ``linux64``; FMI 3: ``x86_64-linux``)."""
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "x86_64": "x86_64", "arm64": "aarch64", "aarch64": "aarch64"}.get(machine)
    os_name = {"linux": "linux", "darwin": "darwin"}.get(sys.platform)
    if arch is None or os_name is None:
        return None
    if fmi == 3:
        return f"{arch}-{os_name}"
    return {"linux": "linux64", "darwin": "darwin64"}[os_name] if arch == "x86_64" else None


def _suffix() -> str:
    return ".dylib" if sys.platform == "darwin" else ".so"


def _compiler() -> list[str] | None:
    """The C compiler: ``CC`` if set, else ``cc``, ``gcc`` or ``clang`` on the PATH."""
    if os.environ.get("CC"):
        cmd = shlex.split(os.environ["CC"])
        return cmd if cmd and shutil.which(cmd[0]) else None
    for name in ("cc", "gcc", "clang"):
        if shutil.which(name):
            return [shutil.which(name)]
    return None


def _compile(sources: dict, identifier: str, fmi: int, say):
    """Compile ``sources`` to a shared library: (platform, compiler, note, bytes or None)."""
    target = _platform(fmi)
    if target is None:
        return None, None, f"sources only: no binary is built on {sys.platform} {platform.machine()}", None
    cc = _compiler()
    if cc is None:
        return target, None, "sources only: no C compiler found (set CC, or install gcc or clang)", None
    if say:
        say(f"compiling {identifier} with {Path(cc[0]).name}")
    with tempfile.TemporaryDirectory(prefix="flexshaft-fmu-") as tmp:
        for name, text in sources.items():
            Path(tmp, name).write_text(text, encoding="utf-8")
        lib = Path(tmp, identifier + _suffix())
        c_files = [str(Path(tmp, n)) for n in sources if n.endswith(".c")]
        cmd = [*cc, "-shared", "-fPIC", "-O2", "-std=c99", "-I", tmp, *c_files, "-o", str(lib), "-lm"]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True, timeout=COMPILE_TIMEOUT_S)
        except (OSError, subprocess.TimeoutExpired) as err:
            return target, cc[0], f"sources only: the compiler failed ({err})", None
        if run.returncode != 0 or not lib.is_file():
            first = (run.stderr.strip().splitlines() or ["no message"])[0]
            return target, cc[0], f"sources only: the compiler failed: {first}", None
        return target, Path(cc[0]).name, None, lib.read_bytes()


def _zip(files: dict[str, str], binaries: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in files.items():
            z.writestr(name, text.encode("utf-8"))
        for name, data in binaries.items():
            z.writestr(name, data)
    return buf.getvalue()
