"""Export a :class:`fmus.cosim.system.System` to an SSP 1.0 package, and read one back.

The package (a zip) holds:

* ``SystemStructure.ssd``: one ``ssd:System`` with one ``ssd:Component`` per instance,
  typed connectors (``ssc:Real`` ...) of kind ``output`` (connected or recorded outputs),
  ``input`` (connected inputs only: an unconnected input keeps its FMU start value) and
  ``parameter`` (every parameter the system sets), the connections, and
  ``ssd:DefaultExperiment`` (start 0, stop ``system.stop_time``) with two annotations of
  the communication step: :data:`STEP_ANNOTATION` (SSP 1.0 has no attribute for it) and
  libcosim's :data:`OSP_ANNOTATION` (its fixed-step algorithm, without which libcosim's
  ``from_ssp_file`` cannot run the package);
* ``resources/<instance>.fmu``: each instance's own copy of its FMU with its parameters
  baked in as start values (``bake``, default; :func:`fmus.systemfmu.export.with_start_values`),
  so they hold in tools that ignore parameter bindings; or, with ``bake=False``,
  ``resources/<Model>.fmu`` once per model;
* ``resources/<instance>.ssv``: the component's parameters (Real, Integer, Boolean,
  String), bound by the component's ``ssd:ParameterBindings``.  Every file is a
  parameter set named :data:`PARAMETER_SET`, the name Ecos selects them by.

Parameter names in the ``.ssv`` files are the FMU's variable names (names in a
component's parameter binding are relative to the component).

Which system to export for a Jacobi master is :mod:`scenarios.packaging.chain`'s business (a
scene's control chain and its plant); exported component by component, a closed loop gets
a step of delay per connection there (docs/ssp.md).  :mod:`fmus.ssp.run` runs a package in fmpy or Ecos, :mod:`fmus.ssp.libcosim` in
libcosim.
"""
from __future__ import annotations

import contextlib
import math
import os
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

from fmus.export.archive import umask_mode
from fmus.cosim.system import System, split_signal

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
}
#: Name of the parameter set in every ``.ssv`` file (Ecos: ``init(parameter_set=...)``).
PARAMETER_SET = "parameters"
#: Annotation type of ``ssd:DefaultExperiment`` that carries the communication step.
STEP_ANNOTATION = "org.parcosim.communicationStep"
_PARCOSIM_NS = "urn:parcosim:ssp"
#: Namespace of the OSP annotations (libcosim matches the literal prefix ``osp:``).
OSP_NS = "http://opensimulationplatform.com/SSP/OSPAnnotations"
#: Annotation type of ``ssd:DefaultExperiment`` that libcosim reads.
OSP_ANNOTATION = "com.opensimulationplatform"
#: libcosim's time unit: durations and time points are integer nanoseconds.
#: libcosim steps the FMUs on the calling thread: Python FMUs hold the GIL anyway (one
#: worker thread is 5-8x slower, docs/ssp_tools.md), and an FMU error in initialisation
#: then fails the first step instead of aborting the importing process.
LIBCOSIM_WORKER_THREADS = 0
_TYPES = ("Real", "Integer", "Boolean", "String")
_INT32 = (-2**31, 2**31 - 1)

for _prefix, _uri in {**NS, "parcosim": _PARCOSIM_NS, "osp": OSP_NS}.items():
    ET.register_namespace(_prefix, _uri)


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


# --- export ---------------------------------------------------------------------------------

def export_ssp(system: System, path, fmu_dir=None, fmus: dict | None = None, bake: bool = True,
               instance_fmus: dict | None = None) -> Path:
    """Write ``system`` as an SSP 1.0 package to ``path`` and return its path.

    Parameters
    ----------
    system : System
        What to export; every component must be an FMU that :func:`fmus.export.build.ensure_built`
        finds or builds in ``fmu_dir``.
    path : str or Path
        The ``.ssp`` file to write (its parent directory is created); its stem names the
        system structure.
    fmu_dir : str or Path, optional
        Where the FMUs are (and are built when missing or stale); default
        :data:`fmus.export.build.DEFAULT_OUT`.
    fmus : dict, optional
        Model -> FMU file for models that are not in ``fmu_dir`` (e.g. the
        ``ControlChain`` built for one scene, :mod:`scenarios.packaging.chain`).
    bake : bool
        Each instance gets its own copy of its FMU, ``resources/<instance>.fmu``, whose
        parameters start at the instance's values (:func:`fmus.systemfmu.export.with_start_values`),
        so they hold in tools that ignore parameter bindings (fmpy's SSP runner).  False:
        one ``resources/<Model>.fmu`` per model, the values in the bindings only.
    instance_fmus : dict, optional
        Instance -> the FMU file its copy is made from, in place of its model's (with
        ``bake``): an FMU of the instance's model built for that instance (the native FMUs of
        ``export-ssp --per-component --native``, whose compiled defaults are its parameters).

    Raises
    ------
    ValueError
        For anything SSP 1.0 or the FMUs cannot express: multi-rate components
        (``substeps > 1``), a missing FMU, a variable the FMU lacks, a connection that is
        not output -> input of one type, a recorded input that is not connected, a
        parameter that is no parameter (or input) of its FMU, or a value of the wrong type.
    """
    path = Path(path)
    if path.suffix.lower() != ".ssp":
        raise ValueError(f"{path}: an SSP package must end in '.ssp'")
    for c in system.components:
        if c.substeps != 1:
            raise ValueError(f"component {c.name}: substeps = {c.substeps}; SSP 1.0 has no per-component "
                             "step, so multi-rate systems cannot be exported (set substeps=1)")
    instance_fmus = dict(instance_fmus or {})
    if instance_fmus and not bake:
        raise ValueError("instance_fmus: an instance's own FMU goes into the package only with bake=True")
    unknown = set(instance_fmus) - {c.name for c in system.components}
    if unknown:
        raise ValueError(f"instance_fmus: no instance {', '.join(sorted(unknown))} in the system")
    given = dict(fmus or {})
    fmus = _fmu_paths([c.model for c in system.components if c.model not in given], fmu_dir)
    fmus.update({model: Path(fmu) for model, fmu in given.items()})
    variables = {model: _read_variables(model, fmu) for model, fmu in fmus.items()}
    for instance, fmu in instance_fmus.items():
        model = system.component(instance).model
        if set(_read_variables(model, Path(fmu))) != set(variables[model]):
            raise ValueError(f"instance_fmus: {fmu} for {instance} has other variables than {fmus[model]} "
                             f"(model {model})")
    connectors, values = _plan(system, variables)
    sources = {c.name: f"resources/{c.name if bake else c.model}.fmu" for c in system.components}
    ssd = _ssd(system, path.stem, connectors, values, sources)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zf, \
                tempfile.TemporaryDirectory(prefix="parcosim_ssp_") as copies:
            zf.writestr("SystemStructure.ssd", _xml_bytes(ssd))
            if bake:
                from fmus.systemfmu.export import with_start_values

                for c in system.components:
                    start = {name: value for name, (_, value) in values[c.name].items()}
                    own = instance_fmus.get(c.name, fmus[c.model])
                    copy = with_start_values(own, start, Path(copies) / f"{c.name}.fmu")
                    zf.write(copy, sources[c.name], compress_type=zipfile.ZIP_STORED)
            else:
                for model, fmu in fmus.items():
                    # FMUs are zips already: store them as they are.
                    zf.write(fmu, f"resources/{model}.fmu", compress_type=zipfile.ZIP_STORED)
            for c in system.components:
                if values[c.name]:
                    zf.writestr(f"resources/{c.name}.ssv", _xml_bytes(_ssv(values[c.name])))
        os.chmod(tmp, umask_mode())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def _fmu_paths(models, fmu_dir) -> dict:
    from fmus.export.build import ensure_built

    models = list(dict.fromkeys(models))
    for model in models:
        if not model or any(ch in model for ch in '/\\:*?"<>|') or model in (".", ".."):
            raise ValueError(f"model name {model!r} cannot name a file resources/{model}.fmu")
    try:
        return ensure_built(models, fmu_dir)
    except (FileNotFoundError, ValueError) as exc:
        raise ValueError(f"cannot export: {exc}") from None


def _read_variables(model: str, fmu: Path) -> dict:
    from fmpy import read_model_description

    try:
        md = read_model_description(str(fmu), validate=False)
    except Exception as exc:  # noqa: BLE001 - any unreadable FMU is an export error
        raise ValueError(f"cannot read the model description of {fmu}: {exc}") from None
    if md.fmiVersion != "2.0" or md.coSimulation is None:
        raise ValueError(f"{fmu} is not an FMI 2.0 co-simulation FMU (fmiVersion {md.fmiVersion})")
    if md.coSimulation.modelIdentifier != model and md.modelName != model:
        raise ValueError(f"{fmu} holds model {md.modelName!r}, not {model!r}")
    return {v.name: v for v in md.modelVariables}


def _plan(system: System, variables: dict):
    """Connectors (instance -> {name: (kind, type)}) and parameter values (instance -> {name: (type, value)})."""
    connectors = {c.name: {} for c in system.components}
    values = {c.name: {} for c in system.components}

    def variable(signal, what):
        instance, name = split_signal(signal)
        model = system.component(instance).model
        v = variables[model].get(name)
        if v is None:
            raise ValueError(f"{what} {signal}: {model} has no variable {name!r}")
        if v.type not in _TYPES:
            raise ValueError(f"{what} {signal}: type {v.type} cannot be exported (only {', '.join(_TYPES)})")
        return instance, name, v

    def declare(instance, name, kind, type_):
        old = connectors[instance].get(name)
        if old is not None and old != (kind, type_):
            raise ValueError(f"{instance}.{name} would be both a {old[0]} and a {kind} connector")
        connectors[instance][name] = (kind, type_)

    for conn in system.connections:
        si, sn, sv = variable(conn.source, "connection source")
        ti, tn, tv = variable(conn.target, "connection target")
        if sv.causality != "output":
            raise ValueError(f"connection {conn.source} -> {conn.target}: the source is a {sv.causality}, "
                             "not an output")
        if tv.causality != "input":
            raise ValueError(f"connection {conn.source} -> {conn.target}: the target is a {tv.causality}, "
                             "not an input")
        if sv.type != tv.type:
            raise ValueError(f"connection {conn.source} -> {conn.target} joins a {sv.type} to a {tv.type}")
        declare(si, sn, "output", sv.type)
        declare(ti, tn, "input", tv.type)
    connected = {c.target for c in system.connections}
    for signal in system.record:
        instance, name, v = variable(signal, "recorded signal")
        if v.causality == "output":
            declare(instance, name, "output", v.type)
        elif not (v.causality == "input" and signal in connected):
            raise ValueError(f"recorded signal {signal} is a {v.causality}; only outputs and connected inputs "
                             "can be recorded (fmpy's SSP runner needs every declared input connected)")
    for c in system.components:
        for name, value in c.parameters.items():
            _, _, v = variable(f"{c.name}.{name}", "parameter")
            if v.causality not in ("parameter", "input"):
                raise ValueError(f"parameter {c.name}.{name}: {c.model}'s {name!r} is a {v.causality}, "
                                 "not a parameter or input")
            if v.variability == "constant":
                raise ValueError(f"parameter {c.name}.{name}: {c.model}'s {name!r} is a constant")
            values[c.name][name] = (v.type, _coerce(f"{c.name}.{name}", v.type, value))
            if (c.name + "." + name) not in connected:
                # An input set as a parameter is declared a parameter connector: an
                # unconnected input connector would stop fmpy's runner.
                declare(c.name, name, "parameter", v.type)
    return connectors, values


def _coerce(signal: str, type_: str, value):
    """The value as its FMI type, or a ValueError that names it."""
    bad = ValueError(f"parameter {signal} = {value!r} ({type(value).__name__}) is no {type_} value")
    if type_ == "Real":
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise bad
        value = float(value)
        if not math.isfinite(value):
            raise ValueError(f"parameter {signal} = {value!r} is not finite")
        return value
    if type_ == "Integer":
        if isinstance(value, bool):
            raise bad
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            value = int(value)
        if not isinstance(value, (int, np.integer)):
            raise bad
        value = int(value)
        if not _INT32[0] <= value <= _INT32[1]:
            raise ValueError(f"parameter {signal} = {value} does not fit a 32-bit FMI Integer")
        return value
    if type_ == "Boolean":
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        if isinstance(value, (int, np.integer)) and value in (0, 1):
            return bool(value)
        raise bad
    if type_ == "String":
        if not isinstance(value, str):
            raise bad
        if any(ord(ch) < 32 and ch not in "\t\n\r" for ch in value):
            raise ValueError(f"parameter {signal} = {value!r} holds control characters XML cannot carry")
        return value
    raise bad


def _format(type_: str, value) -> str:
    if type_ == "Real":
        return repr(float(value))  # shortest string that reads back to the same double
    if type_ == "Integer":
        return str(int(value))
    if type_ == "Boolean":
        return "true" if value else "false"
    return value


def _ssd(system: System, name: str, connectors: dict, values: dict, sources: dict) -> ET.Element:
    root = ET.Element(_q("ssd", "SystemStructureDescription"),
                      {"version": "1.0", "name": name, "generationTool": "parcosim (fmus.ssp.export.export_ssp)"})
    sys_el = ET.SubElement(root, _q("ssd", "System"), {
        "name": name, "description": f"parcosim system, {len(system.components)} components, "
                                     f"communication step {system.step!r} s"})
    elements = ET.SubElement(sys_el, _q("ssd", "Elements"))
    for c in system.components:
        comp = ET.SubElement(elements, _q("ssd", "Component"), {
            "name": c.name, "type": "application/x-fmu-sharedlibrary",
            "source": sources[c.name], "implementation": "CoSimulation"})
        if connectors[c.name]:
            conns = ET.SubElement(comp, _q("ssd", "Connectors"))
            for cname, (kind, type_) in connectors[c.name].items():
                el = ET.SubElement(conns, _q("ssd", "Connector"), {"name": cname, "kind": kind})
                ET.SubElement(el, _q("ssc", type_))
        if values[c.name]:
            bindings = ET.SubElement(comp, _q("ssd", "ParameterBindings"))
            ET.SubElement(bindings, _q("ssd", "ParameterBinding"), {
                "type": "application/x-ssp-parameter-set", "source": f"resources/{c.name}.ssv"})
    if system.connections:
        conns = ET.SubElement(sys_el, _q("ssd", "Connections"))
        for conn in system.connections:
            si, sn = split_signal(conn.source)
            ti, tn = split_signal(conn.target)
            ET.SubElement(conns, _q("ssd", "Connection"), {
                "startElement": si, "startConnector": sn, "endElement": ti, "endConnector": tn})
    experiment = ET.SubElement(root, _q("ssd", "DefaultExperiment"),
                               {"startTime": "0.0", "stopTime": repr(float(system.stop_time))})
    annotations = ET.SubElement(experiment, _q("ssd", "Annotations"))
    annotation = ET.SubElement(annotations, _q("ssc", "Annotation"), {"type": STEP_ANNOTATION})
    ET.SubElement(annotation, f"{{{_PARCOSIM_NS}}}CommunicationStep", {"value": repr(float(system.step))})
    annotations.append(libcosim_annotation(system.step, LIBCOSIM_WORKER_THREADS))
    return root


def _ssv(values: dict) -> ET.Element:
    root = ET.Element(_q("ssv", "ParameterSet"), {"version": "1.0", "name": PARAMETER_SET})
    params = ET.SubElement(root, _q("ssv", "Parameters"))
    for name, (type_, value) in values.items():
        p = ET.SubElement(params, _q("ssv", "Parameter"), {"name": name})
        ET.SubElement(p, _q("ssv", type_), {"value": _format(type_, value)})
    return root


def _xml_bytes(root: ET.Element) -> bytes:
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"


# --- libcosim's annotation ------------------------------------------------------------------

def _step_text(step) -> str:
    step = float(step)
    if not (step > 0 and np.isfinite(step)):
        raise ValueError(f"step = {step!r} must be a finite number > 0")
    return repr(step)


def _threads_text(worker_threads) -> str | None:
    if worker_threads is None:
        return None
    if isinstance(worker_threads, bool) or int(worker_threads) != worker_threads or worker_threads < 0:
        raise ValueError(f"worker_threads = {worker_threads!r} must be an integer >= 0")
    return str(int(worker_threads))


def libcosim_annotation(step: float, worker_threads: int | None = None) -> ET.Element:
    """The ``ssc:Annotation`` element to append to ``ssd:DefaultExperiment/ssd:Annotations``
    so that libcosim takes its fixed-step algorithm and communication step (``step``, s)
    from the package, and ``CosimExecution.from_ssp_file(path)`` needs no ``step_size``.

    ``worker_threads`` sets ``numWorkerThreads`` (0: libcosim steps the FMUs on the
    calling thread; absent: ``hardware_concurrency - 1`` worker threads).

    libcosim matches the prefixes literally (``ssd:``, ``ssc:``, ``osp:``); this module
    registers ``osp`` for :data:`OSP_NS` with ElementTree, so serialising the whole
    document writes ``xmlns:osp="..."`` on the root and ``osp:`` on these elements.
    """
    annotation = ET.Element(f"{{{NS['ssc']}}}Annotation", {"type": OSP_ANNOTATION})
    algorithm = ET.SubElement(annotation, f"{{{OSP_NS}}}Algorithm")
    attrs = {"baseStepSize": _step_text(step)}
    threads = _threads_text(worker_threads)
    if threads is not None:
        attrs["numWorkerThreads"] = threads
    ET.SubElement(algorithm, f"{{{OSP_NS}}}FixedStepAlgorithm", attrs)
    return annotation


def libcosim_annotation_xml(step: float, worker_threads: int | None = None) -> str:
    """:func:`libcosim_annotation` as text; for ``step = 1e-3``::

        <ssc:Annotation type="com.opensimulationplatform">
          <osp:Algorithm>
            <osp:FixedStepAlgorithm baseStepSize="0.001"/>
          </osp:Algorithm>
        </ssc:Annotation>

    It goes into ``ssd:DefaultExperiment/ssd:Annotations``; an enclosing element (the
    root) must declare ``xmlns:osp="http://opensimulationplatform.com/SSP/OSPAnnotations"``
    and ``xmlns:ssc`` with exactly these prefixes.
    """
    threads = _threads_text(worker_threads)
    attrs = f' numWorkerThreads="{threads}"' if threads is not None else ""
    return (f'<ssc:Annotation type="{OSP_ANNOTATION}">\n'
            f'  <osp:Algorithm>\n'
            f'    <osp:FixedStepAlgorithm baseStepSize="{_step_text(step)}"{attrs}/>\n'
            f'  </osp:Algorithm>\n'
            f'</ssc:Annotation>')


# --- reading back ---------------------------------------------------------------------------

def _parse(zf: zipfile.ZipFile, member: str) -> ET.Element:
    try:
        return ET.fromstring(zf.read(member))
    except KeyError:
        raise ValueError(f"{zf.filename}: no {member}") from None
    except ET.ParseError as exc:
        raise ValueError(f"{zf.filename}: {member} is not well-formed XML: {exc}") from None


def read_ssp_parameters(path) -> dict:
    """The parameters bound to the components of an SSP package:
    ``"instance.variable" -> value`` (float, int, bool or str).

    Reads each component's ``ssd:ParameterBindings`` (``.ssv`` files in the package or
    inline ``ssd:ParameterValues``), which is what fmpy's runner ignores.
    """
    result = {}
    with zipfile.ZipFile(path) as zf:
        ssd = _parse(zf, "SystemStructure.ssd")
        for comp in ssd.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
            instance = comp.get("name")
            for binding in comp.iterfind("ssd:ParameterBindings/ssd:ParameterBinding", NS):
                prefix = binding.get("prefix", "")
                if binding.get("source"):
                    sets = [_parse(zf, binding.get("source"))]
                else:
                    sets = binding.findall("ssd:ParameterValues/ssv:ParameterSet", NS)
                for pset in sets:
                    for p in pset.iterfind("ssv:Parameters/ssv:Parameter", NS):
                        name = p.get("name")
                        if prefix and name.startswith(prefix):
                            name = name[len(prefix):]
                        result[f"{instance}.{name}"] = _parameter_value(p)
    return result


def _parameter_value(p: ET.Element):
    for type_ in _TYPES:
        el = p.find(f"ssv:{type_}", NS)
        if el is not None:
            text = el.get("value")
            if type_ == "Real":
                return float(text)
            if type_ == "Integer":
                return int(text)
            if type_ == "Boolean":
                return text.strip() in ("true", "1")
            return text
    raise ValueError(f"parameter {p.get('name')!r}: no Real, Integer, Boolean or String value")


def read_ssp_experiment(path) -> tuple:
    """``(start_time, stop_time, step)`` of an SSP package's default experiment
    (``None`` where it gives none)."""
    with zipfile.ZipFile(path) as zf:
        ssd = _parse(zf, "SystemStructure.ssd")
    experiment = ssd.find("ssd:DefaultExperiment", NS)
    if experiment is None:
        return None, None, None
    start = experiment.get("startTime")
    stop = experiment.get("stopTime")
    step = None
    for annotation in experiment.iterfind("ssd:Annotations/ssc:Annotation", NS):
        if annotation.get("type") == STEP_ANNOTATION:
            el = annotation.find(f"{{{_PARCOSIM_NS}}}CommunicationStep")
            if el is not None:
                step = float(el.get("value"))
        elif annotation.get("type") == OSP_ANNOTATION and step is None:
            el = annotation.find(f"{{{OSP_NS}}}Algorithm/{{{OSP_NS}}}FixedStepAlgorithm")
            if el is not None and el.get("baseStepSize") is not None:
                step = float(el.get("baseStepSize"))
    return (float(start) if start is not None else None, float(stop) if stop is not None else None, step)
