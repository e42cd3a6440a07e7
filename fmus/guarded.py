"""A pythonfmu slave base that never lets an exception escape.

pythonfmu 0.7 turns an exception raised in any callback into fmi2Fatal and
the importer may go on calling a freed object; a ``do_step`` that returns
False becomes fmi2Discard, the only non-fatal failure status pythonfmu can
return.  So:

* parameters are validated in ``exit_initialization_mode``; a problem is
  logged (category ``logStatusError``) and remembered, and every later
  ``do_step`` refuses with that message instead of stepping;
* ``do_step`` catches everything, logs "<instance>: <what> at t = <time>",
  keeps the outputs of the last good step and returns False (fmi2Discard);
* log messages reach the importer only if it turned logging on, so the same
  message also goes to stderr (where a failed write is ignored) and to the String
  output ``error``;
* :class:`FmiError` raised in a callback refuses that call with ``fmi2Error`` under
  parcosim's FMI wrapper (:mod:`fmus.wrapper`).

The FMU state (``fmi2GetFMUstate`` ...) is the slave's whole Python state, model objects
and refusal flag included (:mod:`fmus.fmustate`): restoring a state taken before a
refused step clears the refusal.
"""
from __future__ import annotations

import json
import math
import os
import sys

from fmus import fmustate

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String, Boolean
from pythonfmu.enums import Fmi2Initial, Fmi2Status

_CAUSALITY = {
    "input": Fmi2Causality.input,
    "output": Fmi2Causality.output,
    "parameter": Fmi2Causality.parameter,
}
#: In an FMU's resources: start values that replace the declared ones (name -> value).
START_VALUES_FILE = "start_values.json"
_KIND = {float: Real, int: Integer, str: String, bool: Boolean}


class GuardedSlave(Fmi2Slave):
    """Base of all parcosim slaves.

    Subclasses declare variables with :meth:`declare`, build their model in
    :meth:`setup` (called once parameters are final) and advance it in
    :meth:`step`; both may raise, the base turns that into a logged refusal.

    A sampled component (``sampled = True``: derivator, observer, controller) computes
    its outputs in ``doStep(t, h)`` from the inputs at t and holds them over the step;
    its Real outputs are declared ``variability="discrete"``, which tells a master
    (:mod:`fmus.master`) to step it before the components that read those outputs.
    Other outputs are values at the end of the step (t + h).
    """

    #: Outputs are samples at the step's start, held over the step (see above).
    sampled = False

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        # Fmi2Slave.__init__ resets these to None: copy the class's for modelDescription.xml.
        self.author = getattr(type(self), "author", None)
        self.description = getattr(type(self), "description", None)
        self.error = ""
        self.register_variable(String("error", causality=Fmi2Causality.output,
                                      variability=Fmi2Variability.discrete,
                                      description="Why the last step was refused ('' when all is well)"))
        self._ready = False

    # --- declaration -----------------------------------------------------------------
    def declare(self, name: str, causality: str, start, description: str = "", variability=None):
        """Register one variable with its start value; the Python type picks the FMI type."""
        setattr(self, name, start)
        kind = _KIND[type(start)]
        kwargs = {"causality": _CAUSALITY[causality], "description": description}
        if causality == "parameter":
            kwargs["variability"] = Fmi2Variability.fixed
        elif kind is not Real or (causality == "output" and self.sampled):
            kwargs["variability"] = Fmi2Variability.discrete
        if variability is not None:
            kwargs["variability"] = variability
        if causality == "output":
            kwargs["initial"] = Fmi2Initial.calculated
        if "." in name:   # "ctrl.lam" of a system FMU: a flat attribute, not an object path
            kwargs["getter"] = lambda: getattr(self, name)
            kwargs["setter"] = lambda value: setattr(self, name, value)
        self.register_variable(kind(name, **kwargs))

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        declare_variables = cls.__init__

        def __init__(self, *args, **kw):
            declare_variables(self, *args, **kw)
            if type(self) is cls:   # the most derived class: every variable is declared
                self._apply_start_values()

        cls.__init__ = __init__

    def _apply_start_values(self) -> None:
        """Give the variables the start values of ``resources/start_values.json``, if the FMU
        has one: an exported package (:mod:`fmus.ssp`) bakes each instance's parameters into
        its own copy of the FMU, so they hold in a tool that ignores parameter bindings."""
        resources = getattr(self, "resources", None)
        if not resources:
            return
        path = os.path.join(resources, START_VALUES_FILE)
        if not os.path.isfile(path):
            return
        with open(path, encoding="utf-8") as f:
            values = json.load(f)
        declared = {v.name for v in self.vars.values()}
        for name, value in values.items():
            if name in declared:
                setattr(self, name, value)

    # --- hooks for subclasses ------------------------------------------------------------
    def setup(self) -> None:
        """Build the model from the parameters; raise ValueError on bad ones."""

    def step(self, current_time: float, step_size: float) -> None:
        """Advance the model; raise on failure (state and outputs must stay valid)."""
        raise NotImplementedError

    # --- FMU state ---------------------------------------------------------------------
    def model_state(self) -> dict:
        """What the continuation depends on, as live references (:func:`fmus.fmustate.model_state`);
        a system slave replaces its inner system by that system's state."""
        return fmustate.model_state(self)

    def restore_model_state(self, state: dict) -> None:
        """Make ``state`` (of :meth:`model_state`, owned by the slave from now on) the slave's."""
        vars(self).update(state)

    def _get_fmu_state(self):
        return fmustate.captured(self.model_state())

    def _set_fmu_state(self, state):
        self.restore_model_state(fmustate.captured(state))

    # pythonfmu calls these two on the class.
    @classmethod
    def _fmu_state_to_bytes(cls, state) -> bytes:
        return fmustate.to_bytes(cls.__name__, state)

    @classmethod
    def _fmu_state_from_bytes(cls, data: bytes):
        return fmustate.from_bytes(cls.__name__, data)

    # --- FMI callbacks -------------------------------------------------------------------
    # get_real/set_real are on every step's path: pythonfmu's versions cost ~1 µs a
    # variable in type checks and lambdas, these look the name up directly.
    def get_real(self, vrs):
        names = self._real_names()
        try:
            return [float(getattr(self, names[vr])) for vr in vrs]
        except KeyError:
            return super().get_real(vrs)

    def set_real(self, vrs, values):
        names = self._real_names()
        try:
            for vr, value in zip(vrs, values):
                setattr(self, names[vr], value)
        except KeyError:
            super().set_real(vrs, values)

    def _real_names(self):
        try:
            return self.__real_names
        except AttributeError:
            self.__real_names = {vr: v.name for vr, v in self.vars.items() if isinstance(v, Real)}
            return self.__real_names

    def exit_initialization_mode(self):
        try:
            self.setup()
            self._ready = True
        except Exception as exc:  # noqa: BLE001 - nothing may escape to pythonfmu
            self._refuse(f"initialisation refused: {exc}")

    def do_step(self, current_time: float, step_size: float) -> bool:
        if not self._ready:
            self._refuse(self.error or "initialisation refused", current_time, repeat=True)
            return False
        try:
            self.step(current_time, step_size)
            return True
        except Exception as exc:  # noqa: BLE001
            self._refuse(str(exc), current_time)
            self._ready = False
            return False

    def _refuse(self, message: str, time: float | None = None, repeat: bool = False) -> None:
        text = message if (time is None or repeat or " t = " in message) else f"{message} (step from t = {time:.6g} s)"
        if repeat and time is not None:
            text = f"{message}; step from t = {time:.6g} s refused"
        self.error = message if repeat else text
        line = f"{self.instance_name}: {text}"
        self.log(line, Fmi2Status.error, category="logStatusError")
        try:   # a closed, full or unwritable stderr must not turn a refusal into a failure
            print(f"[parcosim] {line}", file=sys.stderr, flush=True)
        except (OSError, ValueError, AttributeError):   # ValueError: closed; AttributeError: sys.stderr is None
            pass


class FmiError(Exception):
    """Refuse the current FMI call with ``fmi2Error``.

    parcosim's FMI wrapper (``fmus/wrapper/parcosim_fmi2.c``) turns this exception, raised
    in any callback of a slave, into ``fmi2Error`` and logs its message alone (category
    ``logStatusError``); any other exception, ``KeyboardInterrupt`` included, also becomes
    ``fmi2Error``, logged as ``<Type>: <message>``.  The instance stays valid: the importer
    may go on calling it or free it.  (Under pythonfmu's own wrapper any exception is
    ``fmi2Fatal``.)
    """


#: Start value of a numeric parameter meaning "the preset's value".
PRESET_VALUE = -1.0

#: A numeric parameter beyond this magnitude (SI units) is refused as absurd: no quantity of
#: the robot, its drives or its controller comes near it, and beyond it the models' products
#: overflow, their designs fail without naming the culprit or their loops never end
#: (docs/extremes.md).
ABSURD = 1e6


def with_overrides(params, slave, names):
    """``params`` (a validated frozen dataclass with ``with_``) with the slave's parameters
    that are not PRESET_VALUE replacing its fields.

    ``names`` are (field, FMU variable) pairs.  A negative value other than
    the sentinel is refused naming the variable; the dataclass's own
    validation names any other non-physical value (as the FMU variable).
    """
    changes = {}
    for field, var in names:
        value = float(getattr(slave, var))
        if value == PRESET_VALUE:
            continue
        if value < 0.0:
            raise ValueError(f"parameter {var} = {value!r} is negative (use -1 for the preset's value)")
        refuse_absurd(**{var: value})
        changes[field] = value
    try:
        return params.with_(**changes)
    except ValueError as exc:
        message = str(exc)
        for field, var in names:
            if field != var and message.startswith(f"{field} "):
                message = var + message[len(field):]
        raise ValueError(f"parameter {message}") from None


def require_finite(**values) -> None:
    """Raise ValueError naming the first non-finite value."""
    for name, value in values.items():
        if not math.isfinite(value):
            raise ValueError(f"{name} = {value!r} is not finite")


def refuse_absurd(**values) -> None:
    """Raise ValueError naming the first parameter whose magnitude exceeds :data:`ABSURD`
    (non-finite values pass: the caller's own checks name them)."""
    for name, value in values.items():
        if math.isfinite(value) and abs(value) > ABSURD:
            raise ValueError(f"parameter {name} = {value!r} is absurd: |{name}| must be <= {ABSURD:g} (SI units)")
