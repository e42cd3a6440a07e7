"""The FMU state of a parcosim slave (FMI 2.0 ``fmi2GetFMUstate`` and its siblings).

pythonfmu 0.7's default state holds the registered variables only; a parcosim slave's
continuation also depends on its model objects (the plant's integrator state, the drive's
current controller, the filters, the controller's adaptive gain and table caches) and on
its refusal flag.  So a slave's state is every attribute of the slave object but those
that pythonfmu's framework owns (:data:`FRAMEWORK_ATTRIBUTES`): the variables' values,
the parameters, the model objects and the flags, taken as a deep copy, so that setting
it later (any number of times) continues the run bit for bit.  An FMU that contains a
system (``ClosedLoop``, ``ControlChain``) composes its state from its inner slaves' states
and its stepper's values and time (:meth:`fmus.stepper.Stepper.state`).

Serialised, a state is a header naming the model and a pickle.  Deserialising accepts
only classes of the modules a parcosim state is made of (:data:`ALLOWED_MODULES`): bytes
from elsewhere cannot make it import or call anything else.
"""
from __future__ import annotations

import copy
import io
import pickle

#: Attributes of a slave object that belong to pythonfmu's machinery or are derived from
#: the variable declarations: not part of the state.
FRAMEWORK_ATTRIBUTES = frozenset({
    "vars", "instance_name", "resources", "visible", "log_queue", "guid", "author", "license", "version",
    "copyright", "modelName", "description", "default_experiment",
})
#: First bytes of a serialised parcosim state, then the model name, a newline, the pickle.
MAGIC = b"parcosim-fmu-state-1\n"
#: Top-level modules whose classes a serialised state may name.
ALLOWED_MODULES = frozenset({"numpy", "collections", "copyreg", "plant", "motor", "controller", "fmus", "control",
                             "_codecs", "scipy"})
#: Built-ins a serialised state may name (containers and numbers).
ALLOWED_BUILTINS = frozenset({"complex", "set", "frozenset", "slice", "range", "bytearray", "object",
                              "tuple", "list", "dict", "float", "int", "bool", "str", "bytes"})


def model_state(slave) -> dict:
    """The attributes of ``slave`` that make its state (live references, not copies)."""
    return {name: value for name, value in vars(slave).items()
            if name not in FRAMEWORK_ATTRIBUTES and "__" not in name}


def captured(state: dict) -> dict:
    """A deep copy of ``state``: what an importer holds while the slave runs on."""
    return copy.deepcopy(state)


def to_bytes(model: str, state: dict) -> bytes:
    """``state`` of a slave of ``model`` serialised (:func:`from_bytes` reads it back)."""
    return MAGIC + model.encode() + b"\n" + pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)


def from_bytes(model: str, data: bytes) -> dict:
    """The state serialised by :func:`to_bytes`.

    Raises
    ------
    ValueError
        ``data`` is not a parcosim state, or is the state of another model than ``model``.
    pickle.UnpicklingError
        It names a class outside :data:`ALLOWED_MODULES`.
    """
    data = bytes(data)
    if not data.startswith(MAGIC):
        raise ValueError(f"not a serialised parcosim FMU state (it starts with {data[:24]!r})")
    name, _, payload = data[len(MAGIC):].partition(b"\n")
    if name.decode(errors="replace") != model:
        raise ValueError(f"a serialised state of {name.decode(errors='replace')!r} cannot be set in {model!r}")
    return _RestrictedUnpickler(io.BytesIO(payload)).load()


class _RestrictedUnpickler(pickle.Unpickler):
    def find_class(self, module, name):
        top = module.split(".", 1)[0]
        allowed = (module == "builtins" and name in ALLOWED_BUILTINS) or top in ALLOWED_MODULES \
            or top.startswith("parcosim_")
        if not allowed:
            raise pickle.UnpicklingError(f"a parcosim FMU state cannot name {module}.{name}")
        return super().find_class(module, name)
