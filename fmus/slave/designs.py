"""What an FMU computes ahead, when it is built, and carries in its resources.

Starting one of our FMUs must build nothing and import no more than its model needs
(issue 27, item 5).  Three things its initialisation would otherwise compute are made at
its build, for its parameters then (the defaults, or a system's values), and written into
its resources as ``designs.npz`` (:func:`write`):

* the drives' current controllers (``motor.current_controller``: the ZOH model of G_I
  needs python-control, 1-2 s to import);
* the derivators' Bessel filters (``controller.derivators``: scipy.signal, about 1 s);
* the position controller's tabulated model (``controller.model``: about 0.2 s a table,
  and otherwise a file in the user's cache folder).

Each model module keeps them in its ``PRECOMPUTED`` dict, keyed by everything the result
depends on; an FMU's slave fills those dicts from its resources when it is instantiated
(:func:`load`).  Parameters set to other values give other keys: the result is then
computed as without an FMU (importing python-control or scipy.signal, building the table).
The file holds arrays only (``np.load`` without pickle); its ``index`` names, per entry, the
module and the key.
"""
from __future__ import annotations

import importlib
import json
import os
from contextlib import contextmanager

import numpy as np

#: In an FMU's resources: the designs computed at its build.
DESIGNS_FILE = "designs.npz"
#: The mechanism spec a ``SpecPlant`` FMU carries in its resources (``parcosim build-plant``).
SPEC_RESOURCE = "plant_spec.toml"
#: The model modules that keep designs (each has ``PRECOMPUTED`` and ``RECORDING``).
MODULES = ("motor.current_controller", "controller.derivators", "controller.model")
#: This package's prefix: "" in the repository, "parcosim_<hash>." inside an FMU's bundle.
_PREFIX = __name__[: -len("fmus.slave.designs")]
#: Resources folders whose designs this process has loaded.
_loaded = set()


def _module(name: str):
    return importlib.import_module(_PREFIX + name)


@contextmanager
def isolated():
    """Within: the model modules' designs may be changed (loaded, recorded); afterwards they
    are as before.  Yields the modules, ``{name: module}``.  The build uses it around what
    instantiates the repository's slaves with an FMU's resources (pythonfmu's reading of
    the model description loads them), so the process keeps computing its own designs."""
    modules = {name: _module(name) for name in MODULES}
    saved = {name: (dict(m.PRECOMPUTED), m.RECORDING) for name, m in modules.items()}
    try:
        yield modules
    finally:
        for name, m in modules.items():
            m.PRECOMPUTED.clear()
            m.PRECOMPUTED.update(saved[name][0])
            m.RECORDING = saved[name][1]


@contextmanager
def recording():
    """Within: every design the model modules compute or load is kept, starting from none
    (so each is computed, not taken from an earlier FMU's).  Yields a function returning
    the designs kept so far, ``{module: {key: design}}``; afterwards the dicts are as
    before (:func:`isolated`)."""
    with isolated() as modules:
        for m in modules.values():
            m.PRECOMPUTED.clear()
            m.RECORDING = True
        yield lambda: {name: dict(m.PRECOMPUTED) for name, m in modules.items() if m.PRECOMPUTED}


def write(designs: dict, path) -> None:
    """Write ``designs`` (``{module: {key: design}}``, from :func:`recording`) to ``path``."""
    arrays, index = {}, []
    for module, entries in designs.items():
        for key, design in entries.items():
            for field, array in _encode(module, design).items():
                arrays[f"{len(index)}.{field}"] = array
            index.append([module, key if isinstance(key, str) else list(key)])
    np.savez(path, index=np.array(json.dumps(index)), **arrays)


def load(resources) -> int:
    """Put the designs of the FMU whose resources folder is ``resources`` into the model
    modules' ``PRECOMPUTED`` (once per folder and process); return how many.  No file (an
    FMU built without designs, or in process: ``resources`` None) loads none."""
    if not resources or resources in _loaded:
        return 0
    path = os.path.join(resources, DESIGNS_FILE)
    if not os.path.isfile(path):
        return 0
    with np.load(path) as data:
        index = json.loads(str(data["index"]))
        for k, (module, key) in enumerate(index):
            fields = {name.split(".", 1)[1]: data[name] for name in data.files if name.split(".", 1)[0] == str(k)}
            _module(module).PRECOMPUTED[key if isinstance(key, str) else _tuple(key)] = _decode(module, fields)
    _loaded.add(resources)
    return len(index)


def _tuple(key):
    return tuple(_tuple(k) if isinstance(k, list) else k for k in key)


def _encode(module: str, design) -> dict:
    if module == "motor.current_controller":
        d = design
        return {"coefficients": np.array([d.alpha, d.beta, d.gamma, d.delta, d.T]),
                "desired_poles": np.asarray(d.desired_poles), "closed_loop_poles": np.asarray(d.closed_loop_poles)}
    if module == "controller.derivators":
        return {"sos": np.asarray(design)}
    if module == "controller.model":
        xs, ys, table = design
        return {"xs": xs, "ys": ys, "table": table}
    raise ValueError(f"no designs of module {module!r}")


def _decode(module: str, fields: dict):
    if module == "motor.current_controller":
        alpha, beta, gamma, delta, T = (float(c) for c in fields["coefficients"])
        return _module(module).CurrentControllerDesign(alpha, beta, gamma, delta, T, None, None,
                                                       fields["desired_poles"], fields["closed_loop_poles"])
    if module == "controller.derivators":
        return fields["sos"]
    if module == "controller.model":
        return fields["xs"], fields["ys"], fields["table"]
    raise ValueError(f"{DESIGNS_FILE}: no designs of module {module!r}")
