"""FMI slave ``SpecPlant``: any translational parallel mechanism of a TOML spec
(:mod:`plant.spec`), a thin adapter over :class:`plant.specsim.SpecSimulator`.

``parcosim build-plant SPEC.toml OUT.fmu`` bundles the spec as the resource
:data:`SPEC_RESOURCE`; the variables follow it: one torque input per actuated
joint (its ``input`` name), every joint's angle and rate as outputs (its ``name``,
``d<name>``), the platform's ``x, y, z, dx, dy, dz``, the loop-closure ``residual``
and the start point ``x0, y0, z0`` as parameters (FiveBarPlant's interface,
generalised).
"""
from __future__ import annotations

import os

from fmus.slave import budget
from fmus.slave.base import GuardedSlave
from fmus.slave.designs import SPEC_RESOURCE
from fmus.slave.refusals import refuse_absurd, require_finite


class SpecPlant(GuardedSlave):
    """A spec-built translational parallel mechanism (thesis ch. 4-5, forward dynamics 5.66)."""

    author = "parcosim"
    description = "Translational parallel mechanism from a TOML spec (Coutinho 2019, ch. 4-5): torques in, motion out"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        from plant import IntegratorSettings
        from plant.spec import load

        self.spec = load(os.path.join(self.resources, SPEC_RESOURCE))
        if not self.spec.is_parallel:
            raise ValueError(f"{self.spec.source}: a serial chain (no [platform]) is no plant FMU")
        d = self.declare
        for k, _, info in self.spec.joints():
            if info.actuated:
                d(info.input, "input", 0.0, f"Torque (force) on joint {info.name}, about its axis [N m]")
        for k, _, info in self.spec.joints():
            kind = "actuated" if info.actuated else "passive"
            d(info.name, "output", 0.0, f"Joint {info.name} ({kind}) [rad or m]")
            d(f"d{info.name}", "output", 0.0, f"d {info.name}/dt [rad/s or m/s]")
        for axis in "xyz":
            d(axis, "output", 0.0, f"Platform (end effector) {axis} [m]")
            d(f"d{axis}", "output", 0.0, f"d {axis}/dt [m/s]")
        d("residual", "output", 0.0, "Norm of the loop-closure residual (5.18) [m]")
        for axis, value in zip("xyz", self.spec.start):
            d(f"{axis}0", "parameter", float(value), f"Start at rest with the platform's {axis} there [m]")
        defaults = IntegratorSettings()
        d("method", "parameter", defaults.method, "Integrator: 'rk4' (fixed step) or 'dopri5' (adaptive)")
        d("substeps", "parameter", defaults.substeps, "RK4 steps per communication step")
        d("rtol", "parameter", defaults.rtol, "Relative tolerance of dopri5")
        d("atol", "parameter", defaults.atol, "Absolute tolerance of dopri5")
        d("baumgarte", "parameter", defaults.baumgarte, "Baumgarte lambda of (5.66) [1/s]")
        self.sim = None

    def setup(self):
        from plant import IntegratorSettings
        from plant.specsim import AssemblyError, SpecSimulator

        numeric = {name: getattr(self, name) for name in ("x0", "y0", "z0", "rtol", "atol", "baumgarte")}
        require_finite(**numeric)
        refuse_absurd(**numeric)
        settings = IntegratorSettings(method=self.method, substeps=self.substeps, rtol=self.rtol, atol=self.atol,
                                      baumgarte=self.baumgarte, kernel="general")
        try:
            sim = SpecSimulator(self.spec, (self.x0, self.y0, self.z0), settings)
        except AssemblyError as exc:    # the start point, named by the slave's parameters
            raise ValueError(f"parameters x0 = {self.x0!r}, y0 = {self.y0!r}, z0 = {self.z0!r} m: no assembly "
                             f"starts there: {exc}") from None
        budget.check_rk4_substeps(sim, f"parameter substeps = {self.substeps!r}", "dopri5")
        self.sim = sim
        self._publish()

    def known_step_work(self) -> float:
        """The least CPU [s] a step is charged (:func:`fmus.slave.budget.known_step_work`)."""
        return budget.known_step_work(self.sim)

    def step(self, current_time, step_size):
        sim = self.sim
        sim.time = current_time
        torques = [getattr(self, name) for name in self.spec.inputs]
        budget.step_plant(sim, lambda limit: sim.step(torques, step_size, limit), current_time, step_size)
        self._publish()

    def _publish(self):
        for name, value in self.sim.outputs().items():
            setattr(self, name, float(value))
