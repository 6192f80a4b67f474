"""The model description of a drivetrain FMU (``modelDescription.xml``), FMI 2.0 or 3.0.

One list of variables (:func:`variables`) is written in either standard's form. Their value
references are the ones the C sources switch on (``model_data.h``): the inputs from 1, then the
outputs, the states, their derivatives, and the parameters. Units are SI, each defined from the SI
base units; a speed shows in rpm where the importer offers display units.
"""

from __future__ import annotations

from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

__all__ = ["Variable", "variables", "value_references", "description_xml", "UNITS"]

#: FMI unit name -> its SI base-unit exponents, and display units (name, factor: display = factor·value).
UNITS = {
    "N.m": ({"kg": 1, "m": 2, "s": -2}, ()),
    "rad": ({"rad": 1}, (("deg", 57.29577951308232),)),
    "rad/s": ({"rad": 1, "s": -1}, (("rpm", 9.549296585513721),)),
    "s": ({"s": 1}, ()),
}
_UNIT_OF = {"N·m": "N.m", "rad": "rad", "rad/s": "rad/s"}
#: The damping variants an FMU carries, in the order of the ``damping_variant`` parameter (1, 2).
VARIANT_ITEMS = (
    ("parts", "per-part damping: each part's own damping on its own modes, dampers as given"),
    ("system", "system damping: Rayleigh damping fitted so the first two elastic modes carry the ratio"),
)


@dataclass(frozen=True)
class Variable:
    """One FMU variable.

    Attributes
    ----------
    name, description : str
    vr : int
        Value reference.
    kind : {"input", "output", "state", "derivative", "parameter", "variant"}
    unit : str or None
        The FMI unit name (``"N.m"``, ``"rad"``, ``"rad/s"``).
    start : float or int or None
        The start value (inputs and parameters).
    state : int or None
        A derivative's state: its index among the variables, 1-based.
    """

    name: str
    description: str
    vr: int
    kind: str
    unit: str | None = None
    start: float | int | None = None
    state: int | None = None


def value_references(n_inputs: int, n_outputs: int, n_states: int) -> dict[str, int]:
    """The first value reference of each group, and the parameters' (the C sources use the same)."""
    first = {"input": 1, "output": 1 + n_inputs}
    first["state"] = first["output"] + n_outputs
    first["derivative"] = first["state"] + n_states
    first["initial_speed"] = first["derivative"] + n_states
    first["damping_scale"] = first["initial_speed"] + 1
    first["damping_variant"] = first["damping_scale"] + 1
    return first


def variables(system, *, default_variant: int) -> list[Variable]:
    """Every variable of the FMU of ``system`` (an :class:`~flexshaft.exports.fmu.FmuSystem`)."""
    ss = system.ss
    n = ss.A.shape[0]
    vr = value_references(len(ss.inputs), len(ss.outputs), n)
    out = [
        Variable(name, f"torque applied at station {name}, N·m", vr["input"] + k, "input", "N.m", 0.0)
        for k, name in enumerate(ss.inputs)
    ]
    out += [
        Variable(name, _output_description(name, unit), vr["output"] + k, "output", _UNIT_OF[unit])
        for k, (name, unit) in enumerate(zip(ss.outputs, ss.output_units))
    ]
    first_state = len(out) + 1
    out += [
        Variable(name, f"modal coordinate {name} (mass-normalised)", vr["state"] + k, "state")
        for k, name in enumerate(ss.states)
    ]
    out += [
        Variable(
            f"der({name})",
            f"time derivative of {name}",
            vr["derivative"] + k,
            "derivative",
            state=first_state + k,
        )
        for k, name in enumerate(ss.states)
    ]
    if system.spin is not None:
        out.append(
            Variable(
                "initial_speed",
                f"speed of station {system.drive} at the start, the whole line turning rigidly, rad/s",
                vr["initial_speed"],
                "parameter",
                "rad/s",
                0.0,
            )
        )
    out.append(
        Variable(
            "damping_scale",
            "multiplies the modal damping of the chosen variant (1: as computed)",
            vr["damping_scale"],
            "parameter",
            None,
            1.0,
        )
    )
    out.append(
        Variable(
            "damping_variant",
            "1 parts: each part's own damping; 2 system: Rayleigh damping fitted to "
            f"{100 * system.system_ratio:g} % on the first two elastic modes",
            vr["damping_variant"],
            "variant",
            None,
            default_variant,
        )
    )
    return out


def _output_description(name: str, unit: str) -> str:
    kind, _, what = name.partition(":")
    return {
        "angle": f"rotation of station {what}",
        "speed": f"speed of station {what}",
        "torque": f"torque transmitted by {what} (positive when a positive motor torque drives it)",
    }[kind] + f", {unit}"


def description_xml(
    system, vars_: list[Variable], *, fmi: int, identifier: str, guid: str, stamp: str
) -> str:
    """``modelDescription.xml`` for FMI ``fmi`` (2 or 3): both interfaces, model exchange and
    co-simulation, in one FMU."""
    from ..version import __version__

    head = (
        f"modelName={quoteattr(system.name)} description={quoteattr(system.description)} "
        f'generationTool="flexshaft {__version__}" generationDateAndTime="{stamp}" '
        'variableNamingConvention="flat"'
    )
    units = "".join(_unit_xml(name, fmi) for name in UNITS)
    step = f'<DefaultExperiment startTime="0" stopTime="1" stepSize="{system.step:.17g}"/>'
    if fmi == 2:
        return _fmi2(system, vars_, head, units, step, identifier, guid)
    return _fmi3(system, vars_, head, units, step, identifier, guid)


def _unit_xml(name: str, fmi: int) -> str:
    base, display = UNITS[name]
    powers = " ".join(f'{k}="{v}"' for k, v in base.items())
    shown = "".join(f'<DisplayUnit name="{d}" factor="{f:.17g}"/>' for d, f in display)
    return f'<Unit name="{name}"><BaseUnit {powers}/>{shown}</Unit>'


def _attr(v: Variable, key: str, value) -> str:
    return "" if value is None else f" {key}={quoteattr(str(value))}"


_CAUSALITY = {
    "input": ("input", "continuous", None),
    "output": ("output", "continuous", "calculated"),
    "state": ("local", "continuous", "calculated"),
    "derivative": ("local", "continuous", "calculated"),
    "parameter": ("parameter", "fixed", "exact"),
    "variant": ("parameter", "fixed", "exact"),
}


def _variable_attrs(v: Variable) -> str:
    """What both standards write of a variable: name, value reference, description, causality,
    variability and initial."""
    causality, variability, initial = _CAUSALITY[v.kind]
    return (
        f'name={quoteattr(v.name)} valueReference="{v.vr}" description={quoteattr(v.description)} '
        f'causality="{causality}" variability="{variability}"' + _attr(v, "initial", initial)
    )


def _real_attrs(v: Variable, derivative_of) -> str:
    """A real variable's unit (a speed parameter shown in rpm), the state it is the derivative of
    (``derivative_of``: as the standard names it) and its start value."""
    extra = _attr(v, "unit", v.unit) + _attr(v, "derivative", derivative_of)
    if v.unit == "rad/s" and v.kind == "parameter":
        extra += ' displayUnit="rpm"'
    return extra + _attr(v, "start", None if v.start is None else repr(float(v.start)))


def _fmi2(system, vars_, head, units, step, identifier, guid) -> str:
    rows = []
    for v in vars_:
        if v.kind == "variant":
            body = f'<Enumeration declaredType="DampingVariant" start="{v.start}"/>'
        else:
            body = f"<Real{_real_attrs(v, v.state)}/>"  # FMI 2 names a state by its index
        rows.append(f"    <ScalarVariable {_variable_attrs(v)}>{body}</ScalarVariable>")
    index = {v.vr: k + 1 for k, v in enumerate(vars_)}
    outputs = [index[v.vr] for v in vars_ if v.kind == "output"]
    derivatives = [index[v.vr] for v in vars_ if v.kind == "derivative"]
    initial = sorted(outputs + derivatives + [index[v.vr] for v in vars_ if v.kind == "state"])
    items = "".join(
        f'<Item name="{n}" value="{k + 1}" description={quoteattr(d)}/>'
        for k, (n, d) in enumerate(VARIANT_ITEMS)
    )
    files = "".join(f'<File name="{n}"/>' for n in ("model_data.c", "drivetrain.c", "fmi2.c"))
    sources = f"<SourceFiles>{files}</SourceFiles>"
    return "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<fmiModelDescription fmiVersion="2.0" {head} guid="{guid}" numberOfEventIndicators="0">',
            f'  <ModelExchange modelIdentifier="{identifier}" canNotUseMemoryManagementFunctions="true">'
            f"{sources}</ModelExchange>",
            f'  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="true" '
            f'canNotUseMemoryManagementFunctions="true">{sources}</CoSimulation>',
            f"  <UnitDefinitions>{units}</UnitDefinitions>",
            f'  <TypeDefinitions><SimpleType name="DampingVariant"><Enumeration>{items}</Enumeration>'
            "</SimpleType></TypeDefinitions>",
            f"  {step}",
            "  <ModelVariables>",
            *rows,
            "  </ModelVariables>",
            "  <ModelStructure>",
            "    <Outputs>" + "".join(f'<Unknown index="{i}"/>' for i in outputs) + "</Outputs>",
            "    <Derivatives>" + "".join(f'<Unknown index="{i}"/>' for i in derivatives) + "</Derivatives>",
            "    <InitialUnknowns>"
            + "".join(f'<Unknown index="{i}"/>' for i in initial)
            + "</InitialUnknowns>",
            "  </ModelStructure>",
            "</fmiModelDescription>",
            "",
        ]
    )


def _fmi3(system, vars_, head, units, step, identifier, guid) -> str:
    rows = [
        '    <Float64 name="time" valueReference="0" causality="independent" variability="continuous" '
        'unit="s" description="simulation time, s"/>'
    ]
    vr_of = {k + 1: v.vr for k, v in enumerate(vars_)}  # FMI 3 names a state by its value reference
    for v in vars_:
        if v.kind == "variant":
            rows.append(
                f'    <Enumeration {_variable_attrs(v)} declaredType="DampingVariant" start="{v.start}"/>'
            )
        else:
            rows.append(f"    <Float64 {_variable_attrs(v)}{_real_attrs(v, vr_of.get(v.state))}/>")
    outputs = [v.vr for v in vars_ if v.kind == "output"]
    derivatives = [v.vr for v in vars_ if v.kind == "derivative"]
    initial = outputs + derivatives + [v.vr for v in vars_ if v.kind == "state"]
    items = "".join(
        f'<Item name="{n}" value="{k + 1}" description={quoteattr(d)}/>'
        for k, (n, d) in enumerate(VARIANT_ITEMS)
    )
    caps = 'canHandleVariableCommunicationStepSize="true" '
    return "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<fmiModelDescription fmiVersion="3.0" {head} instantiationToken="{guid}">',
            f'  <ModelExchange modelIdentifier="{identifier}"/>',
            f'  <CoSimulation modelIdentifier="{identifier}" {caps}/>',
            f"  <UnitDefinitions>{units}</UnitDefinitions>",
            f'  <TypeDefinitions><EnumerationType name="DampingVariant">{items}</EnumerationType>'
            "</TypeDefinitions>",
            f"  {step}",
            "  <ModelVariables>",
            *rows,
            "  </ModelVariables>",
            "  <ModelStructure>",
            *(f'    <Output valueReference="{r}"/>' for r in outputs),
            *(f'    <ContinuousStateDerivative valueReference="{r}"/>' for r in derivatives),
            *(f'    <InitialUnknown valueReference="{r}"/>' for r in initial),
            "  </ModelStructure>",
            "</fmiModelDescription>",
            "",
        ]
    )
