"""A pythonfmu slave base that never lets an exception escape.

pythonfmu 0.7 turns an exception raised in any callback into fmi2Fatal and
the importer may go on calling a freed object; a ``do_step`` that returns
False becomes fmi2Discard, the only non-fatal failure status pythonfmu can
return.  So:

* parameters are validated in ``exit_initialization_mode``; a problem is
  logged (category ``logStatusError``) and remembered, and every later
  ``do_step`` refuses with that message instead of stepping (an output read in
  Initialization Mode builds the model earlier to calculate it; a problem there leaves the
  outputs at their start values with a warning, the refusal comes at initialisation);
* ``do_step`` catches everything, logs "<instance>: <what> at t = <time>",
  keeps the outputs of the last good step and returns False (fmi2Discard);
* log messages reach the importer only if it turned logging on, so the same
  message also goes to stderr (where a failed write is ignored) and to the String
  output ``error``; the String output ``refusal`` holds the refusal as a record
  (:meth:`fmus.status.RunError.to_json`: kind, instance, time, and for a model's refusal the
  variable, value, unit, code and reason), which the master reads instead of the message;
* :class:`FmiError` raised in a callback refuses that call with ``fmi2Error`` under
  parcosim's FMI wrapper (:mod:`fmus.export.wrapper`).

The FMU state (``fmi2GetFMUstate`` ...) is the slave's whole Python state, model objects
and refusal flag included (:mod:`fmus.slave.state`): restoring a state taken before a
refused step clears the refusal.  Serialised, it is data, never code (docs/state.md): a
state of another model, FMU or configuration, or one that does not fit the instance, is
refused with :class:`FmiError`.

What every parcosim FMU does with careless or hostile calls (the contract table of
docs/extremes.md, "The FMI calls under hostile use"):

* a set of an output, of a fixed parameter after initialisation, of an unknown value
  reference or of a variable of another type raises :class:`FmiError` naming the variable,
  the value and the time, and changes nothing;
* ``doStep`` refuses (fmi2Discard) a step size that is not finite, is below
  :data:`MIN_STEP`, ends after :data:`MAX_TIME`, or that the FMU's model cannot honour
  (:meth:`GuardedSlave.check_step_size`: a sampled component's sample time, :mod:`fmus.slave.sampling`), a
  communication point that does not follow the last one (the time of the state after
  ``fmi2SetFMUstate``), a step before initialisation or after ``fmi2Terminate``;
* after a refused step (fmi2Discard) every later step is refused, as FMI 2.0's
  ``stepFailed`` state wants, until ``fmi2SetFMUstate`` restores a state taken before it;
* ``fmi2SetupExperiment`` and ``fmi2EnterInitializationMode`` after
  ``fmi2EnterInitializationMode``, and ``fmi2ExitInitializationMode`` outside Initialization
  Mode, raise :class:`FmiError` naming the call and where the instance is, and change nothing
  (FMI 2.0's co-simulation state machine; docs/bundle.md).
"""
from __future__ import annotations

import json
import math
import operator
import os
import sys

from fmus.slave.identity import read_identity
from fmus.slave.refusals import FmiError
from fmus.slave.state_calls import SlaveState
from fmus.status import RunStatus, RunError, refusal_of
from kernels import timed

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
_TYPE_NAME = {Real: "Real", Integer: "Integer", String: "String", Boolean: "Boolean"}

#: Shortest step any parcosim FMU takes [s]: below it no model of ours changes, and step
#: counts (T / h) and rates (1 / h) overflow or lose their meaning.
MIN_STEP = 1e-9
#: Latest communication point t + h accepted [s] (about 32 years): beyond it a double
#: resolves time more coarsely than 0.1 µs and the models' samples lose their meaning.
MAX_TIME = 1e9


#: In a refusal's message: the call was interrupted by a KeyboardInterrupt (SIGINT).
INTERRUPTED_MARK = "interrupted (KeyboardInterrupt)"


class GuardedSlave(SlaveState, Fmi2Slave):
    """Base of all parcosim slaves.

    Subclasses declare variables with :meth:`declare`, build their model in
    :meth:`setup` (called once parameters are final) and advance it in
    :meth:`step`; both may raise, the base turns that into a logged refusal.

    A sampled component (``sampled = True``: derivator, observer, controller;
    :mod:`fmus.slave.sampling`) computes its outputs in ``doStep(t, h)`` from the inputs at t and
    holds them over the step (sub-steps h = T / n: until its next sample);
    its Real outputs are declared ``variability="discrete"``, which tells a master
    (:mod:`fmus.cosim.master`) to step it before the components that read those outputs.
    Other outputs are values at the end of the step (t + h).
    """

    #: Outputs are samples at the step's start, held over the step (see above).
    sampled = False
    #: The step size the last :meth:`check_step_size` accepted (derived, not FMU state: its
    #: mangled name keeps it out of :func:`fmus.slave.state.model_state`).
    __accepted_step = None

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        # Fmi2Slave.__init__ resets these to None: copy the class's for modelDescription.xml.
        self.author = getattr(type(self), "author", None)
        self.description = getattr(type(self), "description", None)
        self.error = ""
        self.register_variable(String("error", causality=Fmi2Causality.output,
                                      variability=Fmi2Variability.discrete,
                                      description="Why the last step was refused ('' when all is well)"))
        self.refusal = ""            # the present refusal's RunError as JSON (the output ``refusal``)
        #: The present refusal in its own words: the exception's message, without the time and
        #: the framing of ``error`` ("initialisation refused: ..."); "" when all is well.
        self.refused_because = ""
        self._step_refused = False   # a step was refused (not the initialisation): later steps say so
        self._ready = False          # initialised well, no step refused since
        self._initialising = False   # in Initialization Mode (fmi2EnterInitializationMode was called)
        self._initialised = False    # fmi2ExitInitializationMode was called
        self._terminated = False     # fmi2Terminate was called
        self._start_time = 0.0       # of fmi2SetupExperiment
        self._next_time = None       # the communication point the next doStep must start at
        self._last_step = None
        # Before initialisation: setup() ran for a read of an output, and since then no parameter
        # was set (the outputs read are current) / nothing at all was set (initialisation keeps it).
        self._initial_outputs = self._built_for_exit = False
        self._initial_warning = ""      # the last reason logged for outputs left at their start values
        # value-reference lists resolved by get_real/set_real (derived: not FMU state)
        self.__readers, self.__writers = {}, {}
        self.__init_kwargs = dict(kwargs)   # a new instance like this one (a state's template)
        #: The GUID of this slave's FMU (its modelDescription.xml's, from the identity the build
        #: writes into the resources, :mod:`fmus.slave.identity`); "" in process, where there is no FMU.
        self.fmu_guid = str(read_identity(getattr(self, "resources", None)).get("guid", ""))
        _drop_duplicate_path_entries()

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

    def to_xml(self, model_options=None):
        """pythonfmu's modelDescription with each Real start value written to the last bit:
        pythonfmu writes 16 significant digits, which give back about three doubles in four
        (WheeledPendulum's J_psi = 0.0010367999999999998 read back as 0.0010368)."""
        root = super().to_xml(model_options or {})
        for variable, element in zip(self.vars.values(), root.find("ModelVariables")):
            if isinstance(variable, Real) and isinstance(variable.start, float):
                element.find("Real").set("start", repr(variable.start))
        return root

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        declare_variables = cls.__init__

        def __init__(self, *args, **kw):
            declare_variables(self, *args, **kw)
            if type(self) is cls:   # the most derived class: every variable is declared
                self._declare_refusal()
                self._apply_start_values()

        cls.__init__ = __init__

    def _declare_refusal(self) -> None:
        """Register the String output ``refusal`` last (the other value references stay as they were)."""
        self.register_variable(String("refusal", causality=Fmi2Causality.output, variability=Fmi2Variability.discrete,
                                      description="The last refusal as a JSON record: kind, instance, time, variable, "
                                                  "value, unit, code, reason, message ('' when all is well)"))

    def _apply_start_values(self) -> None:
        """Give the variables the start values of ``resources/start_values.json``, if the FMU
        has one: an exported package (:mod:`fmus.ssp.export`) bakes each instance's parameters into
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

    def accepted_steps(self) -> str:
        """The step sizes this FMU accepts, in words (for refusals and docs/extremes.md)."""
        return f"any step size h with {MIN_STEP:g} s <= h and t + h <= {MAX_TIME:g} s"

    def check_step_size(self, current_time: float, step_size: float) -> None:
        """Raise ValueError if the model cannot honour ``step_size``; subclasses with a
        sample time add their rule to this one (finite, >= :data:`MIN_STEP`, ending by
        :data:`MAX_TIME`)."""
        h = step_size
        if not math.isfinite(h) or h <= 0.0:
            why = "is not a finite positive number"
        elif h < MIN_STEP:
            why = f"is below the shortest step {MIN_STEP:g} s"
        elif not current_time + h <= MAX_TIME:
            why = f"ends after t = {MAX_TIME:g} s"
        else:
            return
        raise timed(ValueError(self.step_size_message(current_time, h, why)))

    def step_size_message(self, current_time: float, step_size: float, why: str) -> str:
        """'step size h = ... s at t = ... s <why>; <Model> accepts <accepted_steps()>'."""
        return (f"step size h = {step_size!r} s at t = {current_time!r} s {why}; "
                f"{type(self).__name__} accepts {self.accepted_steps()}")

    # --- hooks of the FMU state (fmus.slave.state_calls) ---------------------------------------
    def new_instance(self):
        return type(self)(**self.__init_kwargs)

    def state_restored(self) -> None:
        self.__accepted_step = None   # the step-size rule is checked again at the next step

    # --- FMI callbacks -------------------------------------------------------------------
    # get_real/set_real are on every step's path: pythonfmu's versions cost ~1 µs a variable in
    # type checks and lambdas.  These resolve a list of value references once (names, checks)
    # into one attrgetter or one dict update, cached by the list once initialised
    # (:data:`_CACHED_VR_LISTS` of them: an importer moves the same few lists every step).  A
    # list cached then holds inputs only, which any later set may change.
    def get_real(self, vrs):
        key = tuple(vrs)
        read = self.__readers.get(key)
        if read is None:
            names = self._real_names()
            try:
                chosen = [names[vr] for vr in key]
            except (KeyError, TypeError):
                self._refuse_get(vrs, Real)
            read = attribute_reader(chosen)
            if self._initialised:
                _remember(self.__readers, key, read)
            else:
                self._calculate_outputs_for(chosen)
        return read(self)

    def set_real(self, vrs, values):
        key = tuple(vrs)
        write = self.__writers.get(key)
        if write is None:
            names = self._settable(Real)
            try:
                targets = [names[vr] for vr in key]
            except (KeyError, TypeError):
                self._refuse_set(vrs, values, Real)
            write = attribute_writer(type(self), targets)
            if self._initialised:
                _remember(self.__writers, key, write)
            else:
                self._parameters_set(targets)
        write(self, values)

    def get_integer(self, vrs):
        return self._get(vrs, Integer, int)

    def get_boolean(self, vrs):
        return self._get(vrs, Boolean, bool)

    def get_string(self, vrs):
        return self._get(vrs, String, str)

    def set_integer(self, vrs, values):
        self._set(vrs, values, Integer)

    def set_boolean(self, vrs, values):
        self._set(vrs, values, Boolean)

    def set_string(self, vrs, values):
        self._set(vrs, values, String)

    def _get(self, vrs, kind, convert):
        variables = self.vars
        try:
            chosen = [variables[vr] for vr in vrs]
        except KeyError:
            chosen = []
        if len(chosen) != len(vrs) or not all(isinstance(v, kind) for v in chosen):
            self._refuse_get(vrs, kind)
        if not self._initialised:
            self._calculate_outputs_for([v.name for v in chosen])
        return [convert(v.getter()) for v in chosen]

    def _set(self, vrs, values, kind):
        names = self._settable(kind)
        if not all(vr in names for vr in vrs):
            self._refuse_set(vrs, values, kind)
        for var, value in [(self.vars[vr], value) for vr, value in zip(vrs, values)]:
            var.setter(value)
        if not self._initialised:
            self._parameters_set([names[vr] for vr in vrs])

    def _calculate_outputs_for(self, names) -> None:
        """Before initialisation, a get of an output (initial="calculated") runs :meth:`setup`
        with the present parameters and start time, once for each set of them, so a master
        reading outputs in Initialization Mode (FMI 2.0, 4.2.4; libcosim does, docs/ssp_tools.md)
        gets the values the FMU starts from, not placeholders; fmi2ExitInitializationMode then
        keeps that setup.  Reading ``error`` builds nothing.

        A setup refused here is not an error of the read: the outputs keep their start values and
        the reason is logged (once, as a warning); fmi2ExitInitializationMode refuses the
        initialisation with it, as without the read.  An fmi2Error here would end the run of a
        tool that aborts on any error in Initialization Mode (libcosim on its worker threads,
        measured: exit status -6) instead of stopping it at the first step with the reason."""
        if self._initial_outputs or not any(name in self._calculated_names() for name in names):
            return
        try:
            self.setup()
        except Exception as exc:  # noqa: BLE001 - nothing may escape to pythonfmu
            message = (f"{self.instance_name}: the outputs read in Initialization Mode keep their start values: "
                       f"{exc}; fmi2ExitInitializationMode will refuse the initialisation")
            if message != self._initial_warning:
                self._initial_warning = message
                self.log(message if self._wrapper_is_ours() else message.replace("%", "%%"), Fmi2Status.warning,
                         category="logStatusWarning")
            return
        self._initial_outputs = self._built_for_exit = True

    def _parameters_set(self, names) -> None:
        """Before initialisation: outputs calculated earlier are stale once a parameter changes
        (the models' initial outputs follow from parameters); initialisation builds again after
        any set, an input's included."""
        self._built_for_exit = False
        if self._initial_outputs and any(name in self._names_of(Fmi2Causality.parameter) for name in names):
            self._initial_outputs = False

    def _calculated_names(self) -> frozenset:
        return self._memo("calculated", lambda: self._names_of(Fmi2Causality.output) - {"error", "refusal"})

    def _names_of(self, causality) -> frozenset:
        return self._memo(("causality", causality), lambda: frozenset(
            v.name for v in self.vars.values() if v.causality == causality))

    def _real_names(self):
        return self._memo("real", lambda: {vr: v.name for vr, v in self.vars.items() if isinstance(v, Real)})

    def _memo(self, key, compute):
        """A value derived from the declared variables, computed once per instance and ``key``
        (its mangled name keeps the cache out of the FMU state)."""
        try:
            cache = self.__memo
        except AttributeError:
            cache = self.__memo = {}
        value = cache.get(key)
        if value is None:
            value = cache[key] = compute()
        return value

    def _settable(self, kind) -> dict:
        """Value reference -> name of the variables of ``kind`` a set may change now: inputs,
        tunable parameters, and fixed parameters until initialisation."""
        return self._memo(("settable", kind, self._initialised), lambda: {
            vr: v.name for vr, v in self.vars.items()
            if isinstance(v, kind) and (v.causality == Fmi2Causality.input or (
                v.causality == Fmi2Causality.parameter and (
                    not self._initialised or v.variability == Fmi2Variability.tunable)))})

    def _now(self) -> str:
        if not self._initialised:
            return "before initialisation"
        t = self._next_time if self._next_time is not None else self._start_time
        return f"at t = {t!r} s"

    def _refuse_get(self, vrs, kind):
        for vr in vrs:
            var = self.vars.get(vr)
            if var is None:
                raise FmiError(f"fmi2Get{_TYPE_NAME[kind]}: value reference {vr!r} is no variable of "
                               f"{type(self).__name__} ({self._now()})")
            if not isinstance(var, kind):
                raise FmiError(f"fmi2Get{_TYPE_NAME[kind]}: {var.name} (value reference {vr}) is a "
                               f"{_TYPE_NAME[type(var)]} ({self._now()})")
        raise FmiError(f"fmi2Get{_TYPE_NAME[kind]}: value references {list(vrs)!r} refused ({self._now()})")

    def _refuse_set(self, vrs, values, kind):
        """Raise FmiError naming the first variable of a refused set, its value and the time."""
        call = f"fmi2Set{_TYPE_NAME[kind]}"
        settable = self._settable(kind)
        for vr, value in zip(vrs, values):
            if vr in settable:
                continue
            var = self.vars.get(vr)
            if var is None:
                raise FmiError(f"{call}: value reference {vr!r} (value {value!r}) is no variable of "
                               f"{type(self).__name__} ({self._now()}); nothing was set")
            if not isinstance(var, kind):
                raise FmiError(f"{call}: {var.name} (value reference {vr}) is a {_TYPE_NAME[type(var)]}, "
                               f"value {value!r} refused ({self._now()}); nothing was set")
            old = getattr(self, var.name, None)
            if var.causality == Fmi2Causality.parameter:
                raise FmiError(f"{call}: parameter {var.name} = {value!r} refused after initialisation "
                               f"({self._now()}): a fixed parameter keeps its value {old!r}; nothing was set")
            raise FmiError(f"{call}: {var.name} is an output ({var.causality.name}), value {value!r} refused "
                           f"({self._now()}): it keeps {old!r}; nothing was set")
        raise FmiError(f"{call}: value references {list(vrs)!r} refused ({self._now()})")

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._refuse_out_of_order("fmi2SetupExperiment", start_time=start_time)
        check_experiment_times(start_time, stop_time)
        self._start_time = float(start_time)
        self._initial_outputs = self._built_for_exit = False

    def enter_initialization_mode(self):
        self._refuse_out_of_order("fmi2EnterInitializationMode")
        self._initialising = True

    def _refuse_out_of_order(self, call: str, **arguments) -> None:
        """Raise FmiError for ``call`` (fmi2SetupExperiment, fmi2EnterInitializationMode) after
        fmi2EnterInitializationMode: FMI 2.0 allows both once, right after instantiation."""
        if self._initialising or self._initialised or self._terminated:
            given = "".join(f" ({name} = {value!r})" for name, value in arguments.items())
            raise FmiError(f"{call}{given} refused {self._mode()}: it is allowed only once, between "
                           "fmi2Instantiate and fmi2EnterInitializationMode; nothing was changed")

    def _mode(self) -> str:
        """Where the FMI 2.0 state machine is, for call-order refusals."""
        if self._terminated:
            return "after fmi2Terminate"
        if self._initialised:
            return f"in Step Mode ({self._now()})"
        return "in Initialization Mode" if self._initialising else "before fmi2EnterInitializationMode"

    def exit_initialization_mode(self):
        if not self._initialising:
            raise FmiError(f"fmi2ExitInitializationMode refused {self._mode()}: it ends Initialization Mode "
                           "(after fmi2EnterInitializationMode); nothing was changed, the model is not rebuilt")
        self._initialising = False
        self.__accepted_step = None
        self._initialised = True
        self._next_time, self._last_step = self._start_time, None
        try:
            if not self._built_for_exit:   # a read in Initialization Mode ran it, nothing set since
                self.setup()
            self._ready = True
            self.error = self.refusal = self.refused_because = ""
            self._step_refused = False
        except KeyboardInterrupt as exc:
            self._ready = self._step_refused = False
            self.refused_because = INTERRUPTED_MARK
            self._refuse(f"initialisation refused: {INTERRUPTED_MARK} (t = {self._start_time:.6g} s)",
                         cause=(exc, RunStatus.INTERRUPTED, self._start_time))
        except Exception as exc:  # noqa: BLE001 - nothing may escape to pythonfmu
            self._ready = self._step_refused = False
            self.refused_because = str(exc)
            self._refuse(f"initialisation refused: {exc} (t = {self._start_time:.6g} s)",
                         cause=(exc, RunStatus.INITIALISATION, self._start_time))

    def terminate(self):
        self._terminated = True

    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._ready and not self._terminated:   # initialised, nothing refused: the usual case
            try:
                if current_time != self._next_time:   # equal: the check passes (the usual case)
                    self._check_communication_point(current_time)
                # The step-size rule depends on h and fixed parameters alone (and on t through
                # t + h <= MAX_TIME): an h accepted since initialisation is not checked again.
                end = current_time + step_size
                if step_size != self.__accepted_step or not end <= MAX_TIME:
                    self.check_step_size(current_time, step_size)
                    self.__accepted_step = step_size
                self.step(current_time, step_size)
                self._next_time, self._last_step = end, step_size
                return True
            except KeyboardInterrupt as exc:
                self.refused_because = INTERRUPTED_MARK
                self._refuse(f"step {INTERRUPTED_MARK} at t = {current_time!r} s", current_time,
                             cause=(timed(exc), RunStatus.INTERRUPTED, current_time))
                self._ready, self._step_refused = False, True
                return False
            except Exception as exc:  # noqa: BLE001
                self.refuse_step(exc, current_time)
                return False
        if self._terminated:
            self._refuse(f"doStep from t = {current_time!r} s after fmi2Terminate refused", repeat=True,
                         cause=(None, RunStatus.REFUSED, current_time))
            return False
        if not self._initialised:
            self._refuse(f"doStep from t = {current_time!r} s before initialisation "
                         "(fmi2ExitInitializationMode) refused", repeat=True,
                         cause=(None, RunStatus.REFUSED, current_time))
            return False
        if self._step_refused:
            self._refuse(f"an earlier step was refused ({self.error}); restore an FMU state taken before it "
                         "(fmi2SetFMUstate) to go on", current_time, repeat=True, keep_error=True)
        elif self.error:          # the initialisation's refusal, said again (its record kept)
            self._refuse(self.error, current_time, repeat=True, keep_error=True)
        else:
            self._refuse("initialisation refused", current_time, repeat=True,
                         cause=(None, RunStatus.INITIALISATION, current_time))
        return False

    def refuse_step(self, exc: Exception, current_time: float) -> None:
        """Refuse the step from ``current_time`` for ``exc`` (its message, its record), as
        ``do_step`` does when the step raises it; the compiled loop uses it for a step a kernel
        declined, with the record the kernel returned (:meth:`fmus.cosim.adapter.Adapter.refused`)."""
        self.refused_because = str(exc)
        self._refuse(str(exc), current_time, cause=(exc, RunStatus.REFUSED, current_time))
        self._ready, self._step_refused = False, True

    def _check_communication_point(self, current_time: float) -> None:
        """Raise ValueError unless ``current_time`` is the last point plus the last step, to
        rounding: 1e-9 of max(|t|, 1 ms), at most half the last step."""
        expected = self._next_time
        if expected is None:
            return
        tolerance = 1e-9 * max(abs(expected), 1e-3)
        if self._last_step:
            tolerance = min(tolerance, 0.5 * self._last_step)
        if not abs(current_time - expected) <= tolerance:
            raise timed(ValueError(f"communication point t = {current_time!r} s does not follow the last one: "
                                   f"the next doStep must start at t = {expected!r} s (the last step's end, or the "
                                   "time of the state set by fmi2SetFMUstate)"))

    def _refuse(self, message: str, time: float | None = None, repeat: bool = False,
                keep_error: bool = False, cause: tuple | None = None) -> None:
        """Log ``message`` as the instance's refusal, with the step's ``time`` unless ``cause``'s
        exception names it (``names_time``: :func:`kernels.timed`); unless ``keep_error``, it
        becomes ``error`` and ``cause`` (exception or None, its :class:`RunStatus`, the time) the
        record in ``refusal``."""
        names_time = cause is not None and getattr(cause[0], "names_time", False)
        text = message if (time is None or repeat or names_time) else f"{message} (step from t = {time:.6g} s)"
        if repeat and time is not None:
            text = f"{message}; step from t = {time:.6g} s refused"
        if not keep_error:
            self.error = message if repeat else text
            exc, kind, when = cause
            try:
                self.refusal = refusal_of(exc, kind, self.error, self.instance_name, when).to_json()
            except Exception:  # noqa: BLE001 - a record that does not fit JSON: the bare refusal, never an escape
                self.refusal = RunError(kind, self.error, self.instance_name).to_json()
        line = f"{self.instance_name}: {text}"
        self.log(line if self._wrapper_is_ours() else line.replace("%", "%%"), Fmi2Status.error,
                 category="logStatusError")
        try:
            print(f"[parcosim] {line}", file=sys.stderr, flush=True)
        except (OSError, ValueError, AttributeError):   # stderr full, closed or absent: the log and
            pass                                          # ``error`` still carry the message

    def _wrapper_is_ours(self) -> bool:
        """True when the FMU's binary is parcosim's own FMI wrapper (it exports
        :data:`WRAPPER_SYMBOL` and passes log messages as data).  pythonfmu's binary hands the
        message to the importer's logger as its printf format, so ``%`` is doubled for it."""
        try:
            return self.__wrapper_is_ours
        except AttributeError:
            self.__wrapper_is_ours = wrapper_symbol_present(getattr(self, "resources", None), type(self).__name__)
            return self.__wrapper_is_ours


#: A start time t0 is refused where t0 + TIME_RESOLUTION == t0: time could not advance there.
TIME_RESOLUTION = 1e-6


def check_experiment_times(start_time, stop_time=None) -> None:
    """Refuse (:class:`FmiError`, nothing set) a ``fmi2SetupExperiment`` whose start time is not
    finite or so large that t0 + :data:`TIME_RESOLUTION` == t0 (time would never advance), or
    whose stop time, when defined (not None), is not finite or before the start.  The message
    names the argument and its value (the wrapper adds the function and the time)."""
    start = float(start_time)
    if not math.isfinite(start):
        raise FmiError(f"startTime = {start!r} s is not finite; nothing was set")
    if start + TIME_RESOLUTION == start:
        raise FmiError(f"startTime = {start!r} s is too large in magnitude: startTime + "
                       f"{TIME_RESOLUTION:g} s == startTime, time could not advance; nothing was set")
    if stop_time is None:
        return
    stop = float(stop_time)
    if not (math.isfinite(stop) and stop >= start):
        why = "is not finite" if not math.isfinite(stop) else f"is before startTime = {start!r} s"
        raise FmiError(f"stopTime = {stop!r} s {why}; nothing was set")


#: How many value-reference lists a slave's get_real/set_real remember (resolved names).
_CACHED_VR_LISTS = 32


def _remember(cache: dict, key, value) -> None:
    """``cache[key] = value`` unless the cache is full (a careless importer's endless lists)."""
    if len(cache) < _CACHED_VR_LISTS:
        cache[key] = value


def attribute_reader(names: list, converters=None):
    """``slave -> [convert(slave.<name>) for name in names]`` in one attrgetter call.

    ``converters``: one callable per name (default: all ``float``, the FMI Reals).  The
    slaves' :meth:`GuardedSlave.get_real` and the master's in-process instances
    (:meth:`fmus.cosim.backends.InProcessInstance.bind`) read their variables with it.
    """
    converters = tuple(converters or (float,) * len(names))
    if any("." in name for name in names):   # "ctrl.lam" of a system FMU: a flat attribute, not attrgetter's path
        pairs = tuple(zip(converters, names))
        return lambda slave: [convert(getattr(slave, name)) for convert, name in pairs]
    if len(names) == 1:
        name, convert = names[0], converters[0]
        return lambda slave: [convert(getattr(slave, name))]
    getter = operator.attrgetter(*names) if names else (lambda slave: ())
    if all(c is float for c in converters):
        return lambda slave: list(map(float, getter(slave)))
    return lambda slave: [convert(value) for convert, value in zip(converters, getter(slave))]


def attribute_writer(cls, names: list, converters=None):
    """``(slave, values) -> the attributes names set to values``, each converted by its
    converter (``converters``, one per name; default: as given): one dict update when they
    are plain instance attributes (every parcosim variable) converted alike, else setattr
    one by one.  :meth:`GuardedSlave.set_real` and :meth:`fmus.cosim.backends.InProcessInstance.bind`
    use it."""
    if not any(hasattr(getattr(cls, name, None), "__set__") for name in names):
        if converters is None:
            return lambda slave, values: vars(slave).update(zip(names, values))
        if all(c is float for c in converters):
            return lambda slave, values: vars(slave).update(zip(names, map(float, values)))
    if converters is None:
        def write(slave, values):
            for name, value in zip(names, values):
                setattr(slave, name, value)
        return write
    pairs = tuple(zip(names, converters))

    def write_converted(slave, values):
        for (name, convert), value in zip(pairs, values):
            setattr(slave, name, convert(value))
    return write_converted


#: Exported by parcosim's own FMI 2.0 wrapper (not by pythonfmu's binary).
WRAPPER_SYMBOL = "parcosimFmi2WrapperVersion"


def wrapper_symbol_present(resources, model: str) -> bool:
    """Whether the FMU binary next to ``resources`` (``../binaries/<platform>/<model>.so``)
    exports :data:`WRAPPER_SYMBOL`; False when there is no such binary (in process)."""
    if not resources:
        return False
    import ctypes
    import glob

    binaries = os.path.join(os.path.dirname(os.path.abspath(resources)), "binaries")
    for path in glob.glob(os.path.join(binaries, "*", f"{model}.*")):
        try:
            return hasattr(ctypes.CDLL(path), WRAPPER_SYMBOL)
        except OSError:
            continue
    return False


def _drop_duplicate_path_entries() -> None:
    """Remove repeated entries of ``sys.path`` (keeping the first of each), in place.

    pythonfmu's wrapper puts the FMU's resources on ``sys.path`` at every instantiation;
    without this, ``sys.path`` grows by one entry per instance.  A later duplicate never
    changes what an import finds, so dropping it is safe.
    """
    seen = set()
    keep = []
    for entry in sys.path:
        if entry not in seen:
            seen.add(entry)
            keep.append(entry)
    if len(keep) != len(sys.path):
        sys.path[:] = keep
