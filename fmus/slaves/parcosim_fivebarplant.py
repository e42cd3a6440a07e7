"""FMI slave ``FiveBarPlant``: a thin adapter over :class:`plant.PlantSimulator`.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from dataclasses import replace

from fmus.guarded import PRESET_VALUE, GuardedSlave, refuse_absurd, require_finite
from plant import IntegratorSettings, PlantSimulator, get_preset

_DEFAULTS = IntegratorSettings()
#: Start value of J_rotor1/2 meaning "the preset's rotor inertia".
PRESET_ROTOR = PRESET_VALUE
OUTPUTS = ("q1", "q2", "dq1", "dq2", "x", "y", "dx", "dy", "q1_enc", "q2_enc", "residual")


class FiveBarPlant(GuardedSlave):
    """The 5R mechanism of thesis ch. 7.1 (forward dynamics 5.66), torque in, motion out."""

    author = "parcosim"
    description = "5R parallel robot (Coutinho 2019, ch. 4-5, 7.1): joint torques in, motion out"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        d = self.declare
        d("tau1", "input", 0.0, "Torque on chain 1's base joint, CCW positive [N m]")
        d("tau2", "input", 0.0, "Torque on chain 2's base joint, CCW positive [N m]")
        for name, text in (
            ("q1", "Chain 1 actuated angle, CCW from +x [rad]"),
            ("q2", "Chain 2 actuated angle, CCW from +x [rad]"),
            ("dq1", "d q1/dt [rad/s]"), ("dq2", "d q2/dt [rad/s]"),
            ("x", "End effector x [m]"), ("y", "End effector y [m]"),
            ("dx", "d x/dt [m/s]"), ("dy", "d y/dt [m/s]"),
            ("q1_enc", "q1 quantised to encoder counts [rad]"),
            ("q2_enc", "q2 quantised to encoder counts [rad]"),
            ("residual", "Norm of the loop-closure residual (5.18) [m]"),
        ):
            d(name, "output", 0.0, text)
        d("preset", "parameter", "thesis_sim", "Mechanism parameters: 'thesis_sim' (Table 3) or 'bench' (Tables 4-5)")
        d("x0", "parameter", 0.07, "Start at rest with the end effector at (x0, y0) [m]")
        d("y0", "parameter", 0.17, "Start at rest with the end effector at (x0, y0) [m]")
        d("J_rotor1", "parameter", PRESET_ROTOR, "Rotor inertia on q1 [kg m2]; -1: the preset's (bench: Table 16)")
        d("J_rotor2", "parameter", PRESET_ROTOR, "Rotor inertia on q2 [kg m2]; -1: the preset's (bench: Table 18)")
        d("m0", "parameter", 0.0, "End-effector point mass [kg]")
        d("l0", "parameter", 0.05, "Half the distance between the base joints [m]")
        d("gravity_x", "parameter", 0.0, "Gravity, world x [m/s2]")
        d("gravity_y", "parameter", 0.0, "Gravity, world y [m/s2]")
        d("gravity_z", "parameter", 0.0, "Gravity, world z [m/s2] (no effect on the planar motion)")
        d("link_inertias", "parameter", True, "Links have their inertias Jz (false: point masses at the centres of mass)")
        d("encoder_counts", "parameter", 20000, "Encoder counts per revolution (quadrature)")
        d("method", "parameter", _DEFAULTS.method, "Integrator: 'rk4' (fixed step) or 'dopri5' (adaptive)")
        d("substeps", "parameter", _DEFAULTS.substeps, "RK4 steps per communication step")
        d("rtol", "parameter", _DEFAULTS.rtol, "Relative tolerance of dopri5")
        d("atol", "parameter", _DEFAULTS.atol, "Absolute tolerance of dopri5")
        d("baumgarte", "parameter", _DEFAULTS.baumgarte, "Baumgarte lambda of (5.66) [1/s]")
        d("project", "parameter", _DEFAULTS.project, "Project q, dq on the constraints after each step")
        d("kernel", "parameter", _DEFAULTS.kernel, "'fast' (compiled 5R) or 'general' (thesis algorithm in numpy)")
        self.sim = None

    def setup(self):
        params = get_preset(self.preset)
        numeric = {name: getattr(self, name) for name in (
            "J_rotor1", "J_rotor2", "m0", "l0", "gravity_x", "gravity_y", "gravity_z", "baumgarte", "rtol", "atol")}
        require_finite(**numeric)
        refuse_absurd(**numeric)
        for name in ("J_rotor1", "J_rotor2"):
            value = getattr(self, name)
            if value < 0.0 and value != PRESET_ROTOR:
                raise ValueError(f"{name} = {value!r} must be >= 0 (or -1 for the preset's value)")
        params = params.with_rotors(
            params.chain1.J_rotor if self.J_rotor1 == PRESET_ROTOR else self.J_rotor1,
            params.chain2.J_rotor if self.J_rotor2 == PRESET_ROTOR else self.J_rotor2,
        )
        params = replace(params, m0=self.m0, l0=self.l0,
                         gravity=(self.gravity_x, self.gravity_y, self.gravity_z))
        if not self.link_inertias:
            params = replace(params, chain1=replace(params.chain1, Jz1=0.0, Jz2=0.0),
                             chain2=replace(params.chain2, Jz1=0.0, Jz2=0.0))
        settings = IntegratorSettings(
            method=self.method, substeps=self.substeps, rtol=self.rtol, atol=self.atol,
            baumgarte=self.baumgarte, project=bool(self.project), kernel=self.kernel,
        )
        self.sim = PlantSimulator(params, self.x0, self.y0, settings, encoder_counts=self.encoder_counts)
        self._publish()

    def step(self, current_time, step_size):
        self.sim.time = current_time
        self.sim.step(self.tau1, self.tau2, step_size)
        self._publish()

    def _publish(self):
        for name, value in self.sim.outputs().items():
            setattr(self, name, float(value))
