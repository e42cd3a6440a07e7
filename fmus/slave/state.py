"""The FMU state of a parcosim slave (FMI 2.0 ``fmi2GetFMUstate`` and its siblings).

pythonfmu 0.7's default state holds the registered variables only; a parcosim slave's
continuation also depends on its model objects (the plant's integrator state, the drive's
current controller, the filters, the controller's adaptive gain and table caches) and on
its refusal flag.  So a slave's state is every attribute of the slave object but those
that pythonfmu's framework owns (:data:`FRAMEWORK_ATTRIBUTES`), taken as a deep copy: a
:class:`Snapshot`, which setting later (any number of times) continues the run bit for bit.
An FMU that contains a system (``ClosedLoop``, ``ControlChain``) composes its state from its
inner slaves' snapshots and its stepper's values and time (:meth:`fmus.cosim.stepper.Stepper.state`).

Serialised (:func:`to_bytes`), a snapshot is data (:mod:`fmus.slave.state_format`): numbers,
strings, numeric arrays and the *names* of the classes and functions it holds.  Read back
(:func:`decode`), it is laid over the live instance's own state (:func:`apply`): every
object of the bytes must be, at the same place, an object of the same class in the
instance, every opaque value (code) the same code, every array of a non-plain dtype an
array of that dtype there; nothing is constructed from a name, imported or called.  A value
the instance's state does not hold as finite (a NaN, an infinity) is refused unless the
instance holds the same non-finite value at that place (the controller's table marks the
points outside the workspace with NaN).
"""
from __future__ import annotations

import copy
import functools
import hashlib
import math
import struct
import types
from dataclasses import dataclass

import numpy as np

from fmus.slave.state_format import (ArrayBytes, Header, ObjectRecord, Opaque, Ref, SharedRef, Writer, decode, dtype_key,
                              encode)

#: Attributes of a slave object that belong to pythonfmu's machinery, are derived from the
#: variable declarations or name the FMU: not part of the state.
FRAMEWORK_ATTRIBUTES = frozenset({
    "vars", "instance_name", "resources", "visible", "log_queue", "guid", "author", "license", "version",
    "copyright", "modelName", "description", "default_experiment", "fmu_guid",
})
#: The class tag of a nested :class:`Snapshot` (a system FMU's inner slaves) in the bytes.
SNAPSHOT_TAG = "parcosim:Snapshot"
#: The class tag of a numpy array of objects (python-control's coefficient arrays).
OBJECT_ARRAY_TAG = "numpy:ndarray[object]"


class StateMismatch(ValueError):
    """A serialised state does not fit this instance; the message names the place."""


@dataclass(frozen=True)
class Snapshot:
    """One ``fmi2FMUstate`` of a slave: its attributes (``values``, owned by the snapshot),
    the model, the FMU's GUID and the digest of the configuration it was taken in."""

    values: dict
    model: str
    guid: str
    config: bytes

    def __deepcopy__(self, memo):
        return Snapshot(copy.deepcopy(self.values, memo), self.model, self.guid, self.config)


@dataclass(frozen=True)
class Decoded:
    """A serialised state as read (:func:`decode`), not yet laid over an instance."""

    header: Header
    tree: object


def model_state(slave) -> dict:
    """The attributes of ``slave`` that make its state (live references, not copies)."""
    return {name: value for name, value in vars(slave).items()
            if name not in FRAMEWORK_ATTRIBUTES and "__" not in name}


def captured(state):
    """A deep copy of ``state``: what an importer holds while the slave runs on."""
    return copy.deepcopy(state)


# ---- configuration -----------------------------------------------------------------------

def parameter_values(slave) -> dict:
    """Name -> value of the slave's parameters (causality parameter), by name."""
    return {v.name: getattr(slave, v.name) for v in slave.vars.values()
            if v.causality is not None and v.causality.name == "parameter"}


def config_digest(model: str, parameters: dict) -> bytes:
    """SHA-256 of the model identifier and the parameters' names, types and values
    (docs/state.md, "Configuration digest")."""
    digest = hashlib.sha256(model.encode() + b"\0")
    for name in sorted(parameters):
        value = parameters[name]
        digest.update(name.encode() + b"\0")
        if isinstance(value, bool):
            digest.update(b"B" + struct.pack("<B", value))
        elif isinstance(value, int):
            digest.update(b"I" + struct.pack("<q", value))
        elif isinstance(value, float):
            digest.update(b"R" + struct.pack("<d", value))
        else:
            text = str(value).encode("utf-8", "surrogatepass")
            digest.update(b"S" + struct.pack("<I", len(text)) + text)
    return digest.digest()


def differing_parameter(state_values, parameters: dict) -> str:
    """'parameter T = 0.002 in the state, 0.001 in this instance' for the first parameter
    whose value in ``state_values`` (a state's attributes) differs; '' if none can be named."""
    if not isinstance(state_values, dict):
        return ""
    for name in sorted(parameters):
        value = state_values.get(name, parameters[name])
        if type(value) is not type(parameters[name]) or value != parameters[name]:
            return f"parameter {name} = {value!r} in the state, {parameters[name]!r} in this instance"
    return ""


# ---- writing -----------------------------------------------------------------------------

def to_bytes(snapshot: Snapshot, layout: int) -> bytes:
    """``snapshot`` serialised (:mod:`fmus.slave.state_format`); :func:`decode` reads it back.

    Raises
    ------
    TypeError
        The state holds a value the format cannot carry (named).
    """
    header = Header(snapshot.model, snapshot.guid, snapshot.config, layout)
    return encode(header, _TreeBuilder().node(snapshot.values, snapshot.model))


def class_tag(cls) -> str:
    """``module.qualname`` of a class, without a build's private package prefix
    (``parcosim_<hash>.``), so that a state names classes as the sources do."""
    module = cls.__module__ or ""
    head, dot, rest = module.partition(".")
    if dot and head.startswith("parcosim_"):
        module = rest
    return f"{module}.{cls.__qualname__}"


def opaque_tag(value) -> str | None:
    """The tag of a value that is code, not data (None for data).  An object whose class sets
    ``FMU_STATE_OPAQUE = True`` (a kernel binding that holds configuration derived from the
    parameters and scratch, no run state) counts as code: its class is written, never its
    buffers, and a restored state keeps the instance's own."""
    if getattr(type(value), "FMU_STATE_OPAQUE", False):
        return f"kernel:{class_tag(type(value))}"
    if isinstance(value, type):
        return f"class:{class_tag(value)}"
    if isinstance(value, types.ModuleType):
        return f"module:{value.__name__}"
    if isinstance(value, (types.FunctionType, types.BuiltinFunctionType, types.MethodType,
                          types.BuiltinMethodType, functools.partial, np.ufunc)):
        function = getattr(value, "func", value)
        owner = getattr(function, "__self__", None)
        name = getattr(function, "__qualname__", getattr(function, "__name__", "?"))
        where = getattr(function, "__module__", None) or (class_tag(type(owner)) if owner is not None else "")
        return f"function:{where}.{name}"
    return None


class _TreeBuilder:
    """A live state as the tree :func:`fmus.slave.state_format.encode` writes."""

    def __init__(self, skip=None):
        self.skip = skip or (lambda tag, field: False)   # (class tag, field) -> leave the field out
        self.seen = {}   # id(live value) -> its tree node, for shared values
        self.keep = []   # the field dicts made here: alive while ids in ``seen`` may name them

    def node(self, v, path: str):
        if v is None or type(v) in (bool, int, float, complex, str, bytes):
            if type(v) is int and not -2 ** 63 <= v < 2 ** 63:
                raise TypeError(f"{path}: the int {v} does not fit the state format's 64 bits")
            return v
        if isinstance(v, np.generic):
            return v
        shared = self.seen.get(id(v))
        if shared is not None:
            return SharedRef(shared)
        if type(v) is tuple:
            return tuple(self.node(item, f"{path}[{k}]") for k, item in enumerate(v))
        if type(v) is list:
            result = self.seen[id(v)] = []
            result.extend(self.node(item, f"{path}[{k}]") for k, item in enumerate(v))
            return result
        if type(v) is dict:
            result = self.seen[id(v)] = {}
            for key, item in v.items():
                result[self.node(key, f"{path} key")] = self.node(item, f"{path}[{key!r}]")
            return result
        if isinstance(v, np.ndarray):
            if v.dtype.hasobject:
                return self.record(v, OBJECT_ARRAY_TAG, {"shape": v.shape, "items": list(v.flat)}, path)
            self.seen[id(v)] = v
            return v
        if isinstance(v, Snapshot):
            return self.record(v, SNAPSHOT_TAG, {"values": v.values, "config": v.config}, path)
        tag = opaque_tag(v)
        if tag is not None:
            return Opaque(tag)
        fields = object_fields(v)
        if fields is None:
            raise TypeError(f"{path}: a {class_tag(type(v))} cannot be written into an FMU state")
        return self.record(v, class_tag(type(v)), fields, path)

    def record(self, live, tag: str, fields: dict, path: str) -> ObjectRecord:
        record = self.seen[id(live)] = ObjectRecord(tag, {})
        self.keep.append(fields)
        for name, value in fields.items():
            if not self.skip(tag, name):
                record.fields[name] = self.node(value, f"{path}.{name}")
        return record


def object_fields(obj) -> dict | None:
    """An object's fields (its ``__dict__`` and slots), or None if it has neither."""
    fields = dict(vars(obj)) if hasattr(obj, "__dict__") else {}
    slots = [s for cls in type(obj).__mro__ for s in getattr(cls, "__slots__", ()) if s not in ("__dict__", "__weakref__")]
    for name in slots:
        if hasattr(obj, name):
            fields[name] = getattr(obj, name)
    if not fields and not hasattr(obj, "__dict__") and not slots:
        return None
    return fields


# ---- reading -----------------------------------------------------------------------------

def read(data: bytes) -> Decoded:
    """The bytes of :func:`to_bytes`, read (:func:`fmus.slave.state_format.decode`)."""
    header, tree = decode(data)
    return Decoded(header, tree)


def apply(template: dict, tree) -> dict:
    """The state ``tree`` (read from bytes) laid over ``template`` (a captured state of the
    live instance, consumed): the template's objects with the tree's values.

    Raises
    ------
    StateMismatch
        The tree does not fit the template; the message names the place and what differs.
    """
    if not isinstance(tree, dict) or not all(type(k) is str for k in tree):
        raise StateMismatch("the state is not a set of named attributes")
    missing, extra = set(template) - set(tree), set(tree) - set(template)
    if missing or extra:
        raise StateMismatch(f"the state's attributes differ from this instance's: "
                            f"{'missing ' + ', '.join(sorted(missing)) if missing else ''}"
                            f"{'; ' if missing and extra else ''}{'unknown ' + ', '.join(sorted(extra)) if extra else ''}")
    return _Applier().dict_into(template, tree, "")


_LEAVES = (bool, int, float, complex, str, bytes)


def _is_leaf(value) -> bool:
    return value is None or type(value) in _LEAVES or isinstance(value, np.generic)


def _leaf_kind(value) -> str:
    """What a leaf is, Python's and numpy's scalars alike (a variable may hold either)."""
    if isinstance(value, (bool, np.bool_)):
        return "bool"
    if isinstance(value, (int, np.integer)):
        return "int"
    if isinstance(value, (float, np.floating)):
        return "real"
    if isinstance(value, (complex, np.complexfloating)):
        return "complex"
    return type(value).__name__


def _finite_or_as_template(value, template) -> bool:
    """A non-finite number is taken only where the template holds the same one."""
    kind = _leaf_kind(value)
    if kind not in ("real", "complex") or np.isfinite(value):
        return True
    return _leaf_kind(template) == kind and bool(value == template or (np.isnan(value) and np.isnan(template)))


class _Applier:
    def __init__(self):
        self.rebuilt = []   # the values of the tree's lists, dicts, objects and arrays, in order

    def value(self, template, data, path: str):
        if isinstance(data, Ref):
            return self.reference(template, data, path)
        if _is_leaf(data):
            return self.leaf(template, data, path)
        if isinstance(data, Opaque):
            if opaque_tag(template) != data.tag:
                raise StateMismatch(f"{path}: the state refers to {data.tag}, this instance {_describe(template)}")
            return template
        if isinstance(data, (np.ndarray, ArrayBytes)):
            return self.array(template, data, path)
        if type(data) is tuple:
            items = template if type(template) is tuple else ()
            return tuple(self.value(items[k] if k < len(items) else None, item, f"{path}[{k}]")
                         for k, item in enumerate(data))
        if type(data) is list:
            return self.list_into(template, data, path)
        if type(data) is dict:
            return self.dict_into(template, data, path)
        if isinstance(data, ObjectRecord):
            return self.record(template, data, path)
        raise StateMismatch(f"{path}: a {type(data).__name__} in the state")

    def leaf(self, template, data, path):
        if data is None:
            return None   # taken before this place was built (before initialisation)
        if template is not None and not (_is_leaf(template) and _leaf_kind(template) == _leaf_kind(data)):
            raise StateMismatch(f"{path}: the state holds the {type(data).__name__} {data!r}, this instance "
                                f"{_describe(template)}")
        if not _finite_or_as_template(data, template):
            raise StateMismatch(f"{path}: the state holds {data!r}, not a finite number")
        return data

    def reference(self, template, data: Ref, path):
        target = self.rebuilt[data.index]
        if template is not None and not _is_leaf(template) and type(template) is not type(target):
            raise StateMismatch(f"{path}: the state shares a {type(target).__name__} here, this instance "
                                f"{_describe(template)}")
        if template is None or _is_leaf(template):
            if not isinstance(target, (list, dict, np.ndarray)) or _holds_objects(target):
                raise StateMismatch(f"{path}: the state shares a {type(target).__name__} where this instance "
                                    f"{_describe(template)}")
        return target

    def array(self, template, data, path):
        slot = len(self.rebuilt)
        self.rebuilt.append(None)
        fits = isinstance(template, np.ndarray) and not template.dtype.hasobject
        if isinstance(data, ArrayBytes):
            if not (fits and dtype_key(template.dtype) == data.dtype_key):
                raise StateMismatch(f"{path}: an array of dtype {data.dtype_key} in the state, this instance "
                                    f"{_describe(template)}")
            if math.prod(data.shape) * template.dtype.itemsize != len(data.data):
                raise StateMismatch(f"{path}: {len(data.data)} bytes for an array of shape {data.shape}")
            data = np.frombuffer(data.data, dtype=template.dtype).reshape(data.shape).copy()
        elif template is not None and not _is_leaf(template) and not (fits and template.dtype == data.dtype):
            raise StateMismatch(f"{path}: an array of dtype {data.dtype} in the state, this instance "
                                f"{_describe(template)}")
        if fits and template.shape != data.shape:
            raise StateMismatch(f"{path}: an array of shape {data.shape} in the state, this instance "
                                f"{_describe(template)}")
        _check_array_finite(data, template if fits else None, path)
        if fits and template.flags.writeable:
            np.copyto(template, data)
            data = template
        self.rebuilt[slot] = data
        return data

    def list_into(self, template, data: list, path):
        result = template if type(template) is list else self.new_container(template, [], path)
        self.rebuilt.append(result)
        items = [self.value(result[k] if k < len(result) else None, item, f"{path}[{k}]")
                 for k, item in enumerate(data)]
        result[:] = items
        return result

    def dict_into(self, template, data: dict, path):
        result = template if type(template) is dict else self.new_container(template, {}, path)
        self.rebuilt.append(result)
        items = {key: self.value(result.get(key), item, f"{path}[{key!r}]" if path else key)
                 for key, item in data.items()}
        result.clear()
        result.update(items)
        return result

    @staticmethod
    def new_container(template, empty, path):
        if template is not None and not _is_leaf(template):
            raise StateMismatch(f"{path}: the state holds a {type(empty).__name__}, this instance "
                                f"{_describe(template)}")
        return empty

    def record(self, template, data: ObjectRecord, path):
        if data.tag == SNAPSHOT_TAG:
            return self.snapshot(template, data, path)
        if data.tag == OBJECT_ARRAY_TAG:
            return self.object_array(template, data, path)
        if template is None or _is_leaf(template) or opaque_tag(template) is not None or \
                class_tag(type(template)) != data.tag:
            raise StateMismatch(f"{path}: the state holds a {data.tag}, this instance {_describe(template)}")
        self.rebuilt.append(template)
        configuration = _canonical(template) if _is_frozen(template) else None
        configured = _configuration_words(template)
        fields = object_fields(template) or {}
        for name, item in data.fields.items():
            if name not in fields and (not name.isidentifier() or hasattr(type(template), name)):
                raise StateMismatch(f"{path}: {data.tag} has no field {name!r}")
            _set_field(template, name, self.value(fields.get(name), item, f"{path}.{name}"))
        for name, (mask, before) in configured.items():
            first = _first_changed(getattr(template, name, None), mask, before)
            if first is not None:
                raise StateMismatch(f"{path}.{name}[{first}]: the state changes a configuration word of the kernel "
                                    "buffer (sizes, indices, modes, coefficients: fixed by the parameters), not "
                                    "run state")
        if configuration is not None and _canonical(template) != configuration:
            raise StateMismatch(f"{path}: the state's {data.tag} differs from this instance's; it is configuration "
                                "(frozen: fixed by the parameters), not run state")
        return template

    def snapshot(self, template, data: ObjectRecord, path):
        if not isinstance(template, Snapshot) or set(data.fields) != {"values", "config"}:
            raise StateMismatch(f"{path}: the state holds an inner FMU state, this instance {_describe(template)}")
        self.rebuilt.append(template)
        if data.fields["config"] != template.config:
            raise StateMismatch(f"{path}: the inner state's configuration differs from this instance's: "
                                f"{differing_parameter(data.fields['values'], _parameters_of(template.values))}")
        values = self.value(template.values, data.fields["values"], f"{path}.values")
        return Snapshot(values, template.model, template.guid, template.config)

    def object_array(self, template, data: ObjectRecord, path):
        if not (isinstance(template, np.ndarray) and template.dtype.hasobject) or \
                data.fields.get("shape") != template.shape or set(data.fields) != {"shape", "items"}:
            raise StateMismatch(f"{path}: the state holds an array of objects, this instance {_describe(template)}")
        self.rebuilt.append(template)
        items = self.value(list(template.flat), data.fields["items"], f"{path}.items")
        if len(items) != template.size:
            raise StateMismatch(f"{path}: {len(items)} items for an array of shape {template.shape}")
        for k, item in enumerate(items):
            template.flat[k] = item
        return template


def _configuration_words(obj) -> dict:
    """Field -> (mask of its configuration words, their bytes now) of the kernel buffers
    ``obj``'s class names in ``KERNEL_BUFFERS`` (field -> the function giving the words a run
    changes): the sizes, indices, modes and coefficients a kernel runs with (docs/state.md)."""
    result = {}
    for name, run_state in (getattr(type(obj), "KERNEL_BUFFERS", None) or {}).items():
        buffer = getattr(obj, name, None)
        if isinstance(buffer, np.ndarray) and not buffer.dtype.hasobject:
            mask = np.ones(buffer.size, dtype=bool)
            mask[list(run_state(buffer))] = False
            result[name] = (mask, buffer.ravel()[mask].tobytes())
    return result


def _first_changed(buffer, mask, before: bytes):
    """The first index of ``buffer`` under ``mask`` whose value is not the one in ``before``
    (NaN equals NaN), 0 if the buffer is gone or resized, None if none changed."""
    if not isinstance(buffer, np.ndarray) or buffer.size != mask.size:
        return 0
    now = buffer.ravel()[mask]
    was = np.frombuffer(before, dtype=now.dtype)
    changed = ~((now == was) | (np.isnan(now) & np.isnan(was)))
    if not changed.any():
        return None
    return int(np.flatnonzero(mask)[np.flatnonzero(changed)[0]])


def _is_frozen(obj) -> bool:
    """A frozen dataclass: parameters, settings and designs, fixed once built."""
    params = getattr(type(obj), "__dataclass_params__", None)
    return params is not None and params.frozen


def _canonical(obj) -> bytes:
    """``obj`` written in the state format: equal bytes, equal values (NaN included).
    python-control's system names (``sys[12]``, from a process-wide counter) are left out:
    they say nothing of the dynamics."""
    out = bytearray()
    Writer(out).value(_TreeBuilder(skip=_control_name).node(obj, ""), 0)
    return bytes(out)


def _control_name(tag: str, field: str) -> bool:
    return field == "name" and tag.startswith("control.")


def _parameters_of(values) -> dict:
    return values if isinstance(values, dict) else {}


def _holds_objects(value) -> bool:
    """Whether ``value`` (read from a state) holds anything but plain data."""
    if _is_leaf(value):
        return False
    if isinstance(value, np.ndarray):
        return value.dtype.hasobject
    if isinstance(value, dict):
        return any(_holds_objects(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return any(_holds_objects(v) for v in value)
    return True


def _check_array_finite(data: np.ndarray, template, path: str) -> None:
    names = data.dtype.names or (None,)
    for name in names:
        values = data if name is None else data[name]
        if values.dtype.kind not in "fc":
            continue
        bad = ~np.isfinite(values)
        if template is not None and bad.any():
            same = template if name is None else template[name]
            bad &= ~((np.isnan(values) & np.isnan(same)) | (values == same))
        if bad.any():
            where = tuple(int(i) for i in np.argwhere(bad)[0])
            field = f"[{name!r}]" if name else ""
            raise StateMismatch(f"{path}{field}{list(where)}: the state holds {values[where]!r}, not a finite number")


def _set_field(obj, name: str, value) -> None:
    """Set a field without running a property or ``__setattr__`` of the class."""
    if hasattr(obj, "__dict__") and not isinstance(getattr(type(obj), name, None), types.MemberDescriptorType):
        obj.__dict__[name] = value
    else:
        object.__setattr__(obj, name, value)


def _describe(value) -> str:
    if value is None:
        return "holds None"
    tag = opaque_tag(value)
    if tag is not None:
        return f"has {tag}"
    if isinstance(value, np.ndarray):
        return f"has an array of dtype {value.dtype} and shape {value.shape}"
    return f"holds a {class_tag(type(value))}"
