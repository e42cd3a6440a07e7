"""The FMU state calls of a parcosim slave: fmi2GetFMUstate, fmi2SetFMUstate and their
serialisation (docs/state.md).

:class:`SlaveState` is a base of :class:`fmus.slave.base.GuardedSlave`; it relies on the slave's
``_initialised`` flag, ``_now()`` (the time, for messages), the parameters among its
variables, and two hooks the slave base provides: :meth:`SlaveState.new_instance` (a slave
like this one, fresh) and :meth:`SlaveState.state_restored` (what to recheck after a restore).
What a state holds and how bytes are laid over an instance: :mod:`fmus.slave.state`.
"""
from __future__ import annotations

from fmus.slave import state as fmustate
from fmus.slave.refusals import FmiError


class SlaveState:
    """The FMU state calls (pythonfmu's ``_get_fmu_state`` ... protocol) of a slave."""

    #: Version of the slave's state layout, written into serialised states (docs/state.md).
    STATE_LAYOUT = 1

    def model_state(self) -> dict:
        """What the continuation depends on, as live references (:func:`fmus.slave.state.model_state`);
        a system slave replaces its inner system by that system's state."""
        return fmustate.model_state(self)

    def restore_model_state(self, state: dict) -> None:
        """Make ``state`` (of :meth:`model_state`, owned by the slave from now on) the slave's."""
        vars(self).update(state)

    def _config_digest(self) -> bytes:
        """The digest of the parameters (:func:`fmus.slave.state.config_digest`), computed once
        after initialisation, when they are fixed (15-25 % of an fmi2GetFMUstate, which the
        master's retry takes every step); a state set forgets it (it may end initialisation)."""
        digest = self.__dict__.get("_SlaveState__digest") if self._initialised else None
        if digest is None:
            digest = fmustate.config_digest(type(self).__name__, fmustate.parameter_values(self))
            self.__digest = digest if self._initialised else None
        return digest

    def _get_fmu_state(self):
        return fmustate.Snapshot(fmustate.captured(self.model_state()), type(self).__name__, self.fmu_guid,
                                 self._config_digest())

    def _set_fmu_state(self, state):
        """fmi2SetFMUstate: a snapshot of this model in this configuration (any configuration
        before initialisation, when the parameters are still free), or a state read from bytes;
        anything else raises :class:`FmiError` and changes nothing."""
        if isinstance(state, fmustate.Decoded):   # pythonfmu's binary deserialises on the class
            state = self.deserialize_fmu_state(state)
        if not isinstance(state, fmustate.Snapshot):
            raise FmiError(f"fmi2SetFMUstate: a {type(state).__name__} is not an FMU state of "
                           f"{type(self).__name__} ({self._now()}); nothing was set")
        if state.model != type(self).__name__:
            raise FmiError(f"fmi2SetFMUstate: the FMU state of a {state.model} cannot be set in a "
                           f"{type(self).__name__} ({self._now()}); nothing was set")
        self._check_configuration(state.config, state.values, "fmi2SetFMUstate")
        self.restore_model_state(fmustate.captured(state.values))
        self.__digest = None
        self.state_restored()

    def _check_configuration(self, config: bytes, values, call: str) -> None:
        """Raise FmiError if this instance is initialised and ``config`` is not its configuration."""
        if self._initialised and config != self._config_digest():
            which = fmustate.differing_parameter(values, fmustate.parameter_values(self)) or \
                "its configuration digest differs"
            raise FmiError(f"{call}: the FMU state was taken in another configuration ({which}); "
                           f"{type(self).__name__} refuses it ({self._now()}); nothing was set")

    # pythonfmu calls these two on the class.
    @classmethod
    def _fmu_state_to_bytes(cls, state) -> bytes:
        if not isinstance(state, fmustate.Snapshot):
            raise FmiError(f"fmi2SerializeFMUstate: a {type(state).__name__} is not an FMU state of {cls.__name__}")
        return fmustate.to_bytes(state, cls.STATE_LAYOUT)

    @classmethod
    def _fmu_state_from_bytes(cls, data: bytes):
        """The bytes read and checked against the model (:class:`fmus.slave.state.Decoded`);
        :meth:`deserialize_fmu_state` checks them against an instance."""
        try:
            decoded = fmustate.read(data)
        except ValueError as exc:
            raise FmiError(f"fmi2DeSerializeFMUstate: {exc}; nothing was read") from None
        header = decoded.header
        if header.model != cls.__name__:
            raise FmiError(f"fmi2DeSerializeFMUstate: the bytes are a state of {header.model!r}, not of "
                           f"{cls.__name__}; nothing was read")
        if header.layout != cls.STATE_LAYOUT:
            raise FmiError(f"fmi2DeSerializeFMUstate: state layout {header.layout}; {cls.__name__} reads "
                           f"layout {cls.STATE_LAYOUT}; nothing was read")
        return decoded

    def deserialize_fmu_state(self, data) -> fmustate.Snapshot:
        """fmi2DeSerializeFMUstate in this instance: the bytes (or a :class:`fmus.slave.state.Decoded`)
        as a snapshot that :meth:`_set_fmu_state` takes.  The state must be of this FMU (model,
        GUID, layout), of its configuration once initialised, and fit the instance's own state
        (:func:`fmus.slave.state.apply`); otherwise :class:`FmiError` names what did not match."""
        decoded = data if isinstance(data, fmustate.Decoded) else type(self)._fmu_state_from_bytes(data)
        header, call = decoded.header, "fmi2DeSerializeFMUstate"
        guid = self.fmu_guid
        if header.guid != guid:
            raise FmiError(f"{call}: the state is of the FMU with GUID {header.guid!r}, this is {guid!r} "
                           f"({self._now()}); nothing was read")
        self._check_configuration(header.config, decoded.tree, call)
        try:
            values = self._laid_over_template(decoded.tree)
        except ValueError as exc:
            raise FmiError(f"{call}: {exc} ({self._now()}); nothing was read") from None
        return fmustate.Snapshot(values, type(self).__name__, guid, header.config)

    def _laid_over_template(self, tree) -> dict:
        """``tree`` laid over this instance's state or, where that does not fit (the model not
        built yet), over a new instance's built with the state's parameters."""
        try:
            return fmustate.apply(fmustate.captured(self.model_state()), tree)
        except fmustate.StateMismatch as first:
            template = self._built_template(tree)
            if template is None:
                raise first from None
            return fmustate.apply(template, tree)

    def _built_template(self, tree):
        """The state of a new instance of this model given the parameters of ``tree`` and set up,
        or None if it cannot be built from them (its own code, never code the state names)."""
        if not isinstance(tree, dict):
            return None
        fresh = self.new_instance()
        for name, value in fmustate.parameter_values(fresh).items():
            given = tree.get(name, value)
            if type(given) is not type(value):
                return None
            setattr(fresh, name, given)
        try:
            fresh.setup()
        except Exception:  # noqa: BLE001 - parameters that do not build: the first mismatch stands
            return None
        return fmustate.captured(fresh.model_state())

    # --- hooks of the slave base ------------------------------------------------------------
    def new_instance(self):
        """A new, uninitialised slave of this model, made as this one was."""
        raise NotImplementedError

    def state_restored(self) -> None:
        """Called after a state was set: derived values to forget or check again."""
