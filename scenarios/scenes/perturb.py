"""Perturbed scenes: the thesis' model error (7.1.5.6), generalised to every physical parameter.

The thesis simulates its controller with the model's inertial parameters 0, 20 and 40 % off
the plant's.  Here the *plant and the drives* are drawn off their nominal values, sample by
sample, while everything on the controller's side keeps the nominal model: the position
controller (its ``preset``), the current observers (their ``preset``), and the drives'
current controllers, which stay designed for the nominal motor (``R_design``, ``L_design``,
``kt_design``, ``ke_design``, ``b_design``; ``J_design`` already defaults to the preset's rotor).

Which parameters (:func:`perturbable`): per ``FiveBarPlant`` the base half-distance ``l0``,
each chain's ``l1, l2, lg1, lg2, m1, m2, Jz1, Jz2``, the rotor inertias and, when the scene
reads the encoders, the encoders' zero errors ``encoder_offset1/2``; per ``DCMotorDrive`` its
``R, L, kt, ke, b, mu``, and for a LuGre drive (``friction = "lugre"``) its break-away torque
``mu_s``.  Parameters whose nominal value is 0 (the thesis_sim rotors, a switched-off friction)
stay 0.

A LuGre drive needs mu_s >= mu (docs/friction.md), which a draw of ``mu`` alone would break
whenever it rose past the nominal ratio mu_s/mu (1.25 for the motor presets).  So ``mu_s``
*follows* ``mu``: its value is its nominal times mu's relative change, the scene's break-away
ratio kept in every sample.  Only a ``--perturb`` entry for ``mu_s`` itself gives it a draw of
its own (its uncertainty; 0 holds it at its nominal): then a sample with mu above mu_s is the
user's and the drive refuses it, naming both (a failed row).

How much (:data:`WEIGHTS`): parameter p gets its own uncertainty ``u_p = U * weight``; a
relative parameter is ``nominal * (1 + u_p * xi)``, an absolute one ``nominal + u_p * xi``,
with ``xi`` uniform in [-1, 1] or standard normal truncated at +-3 (sigma = u_p).  A
``--perturb FILE.toml`` sets ``u_p`` directly::

    distribution = "normal"        # optional, as --distribution
    [uncertainty]                  # parameter (or fnmatch pattern) -> its u_p; 0 keeps it nominal
    "plant.chain*_l?" = 0.01
    "drive*.mu" = 0.5
    "drive*.mu_s" = 0.2            # a LuGre drive's break-away torque drawn on its own

Draws are deterministic per (seed, sample, parameter name) (:func:`draw`): a sample's values
do not depend on the number of samples, on the other parameters (but a following ``mu_s`` on
its ``mu``) or on the order in which samples run.
"""
from __future__ import annotations

import fnmatch
import math
import tomllib
import zlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fmus.slave.refusals import PRESET_VALUE

from scenarios.scenes.scene import Scene

DISTRIBUTIONS = ("uniform", "normal")
#: The normal distribution is truncated at this many standard deviations.
TRUNCATE_SIGMA = 3.0
#: Encoder zero error per unit of U [rad]: U = 0.4 gives +-4 mrad (about 13 counts of the
#: 20000-count encoder, 0.5 mm at the 0.12 m proximal link): a homing a few counts off.
ENCODER_OFFSET_SCALE = 0.01
#: Link lengths are machined and measured, not estimated: their relative uncertainty is this
#: fraction of U (U = 0.4: +-0.4 %, +-0.5 mm on a 120 mm link); masses, inertias, centres of
#: mass (CAD estimates, Tables 4-5) and motor constants (identified, app. D) get U itself.
#: A length error is a kinematic error the controller cannot see: at 10x this weight it alone
#: sets e_ef (8 mm on bench_triangle_TCx at U = 0.4, against 0.5-0.9 mm without it).
LENGTH_WEIGHT = 0.01

#: Parameter kind -> weight (u_p = U * weight); absolute weights are in the parameter's unit.
WEIGHTS = {"length": LENGTH_WEIGHT, "inertial": 1.0, "motor": 1.0, "friction": 1.0,
           "encoder_offset": ENCODER_OFFSET_SCALE}

_CHAIN = (("l1", "length"), ("l2", "length"), ("lg1", "inertial"), ("lg2", "inertial"), ("m1", "inertial"),
          ("m2", "inertial"), ("Jz1", "inertial"), ("Jz2", "inertial"))
_MOTOR = (("R", "motor"), ("L", "motor"), ("kt", "motor"), ("ke", "motor"), ("b", "friction"), ("mu", "friction"))
#: The drive's design parameter that keeps the nominal value of each perturbed motor parameter.
_DESIGN = {"R": "R_design", "L": "L_design", "kt": "kt_design", "ke": "ke_design", "b": "b_design"}


@dataclass(frozen=True)
class Parameter:
    """One perturbable parameter of a scene.

    ``name`` is ``<instance>.<FMU parameter>`` (a column of sweep.csv); ``kind`` a key of
    :data:`WEIGHTS`; ``absolute``: drawn as nominal + u xi (else nominal (1 + u xi));
    ``follows``: the name of the parameter whose relative change this one takes when it has
    no uncertainty of its own (u None, :func:`uncertainties`), "" for none.
    """

    name: str
    nominal: float
    kind: str
    absolute: bool = False
    follows: str = ""

    @property
    def instance(self) -> str:
        return self.name.split(".", 1)[0]

    @property
    def variable(self) -> str:
        return self.name.split(".", 1)[1]


def _given(component, variable, nominal):
    """The component's own value of ``variable`` if the scene sets one, else ``nominal``."""
    value = component.parameters.get(variable, PRESET_VALUE)
    return float(nominal) if value == PRESET_VALUE else float(value)


def perturbable(scene: Scene) -> list:
    """The :class:`Parameter` list of ``scene``, in a fixed order (plants, then drives)."""
    from motor import get_motor_preset
    from plant import get_preset

    system = scene.system
    read = {c.source for c in system.connections}
    out = []
    for c in system.components:
        if c.model != "FiveBarPlant":
            continue
        params = get_preset(c.parameters.get("preset", "thesis_sim"))
        out.append(Parameter(f"{c.name}.l0", _given(c, "l0", params.l0), "length"))
        for k, chain in ((1, params.chain1), (2, params.chain2)):
            for field, kind in _CHAIN:
                if field.startswith("Jz") and not c.parameters.get("link_inertias", True):
                    continue
                out.append(Parameter(f"{c.name}.chain{k}_{field}", _given(c, f"chain{k}_{field}",
                                                                          getattr(chain, field)), kind))
            out.append(Parameter(f"{c.name}.J_rotor{k}", _given(c, f"J_rotor{k}", chain.J_rotor), "inertial"))
        for k in (1, 2):
            if f"{c.name}.q{k}_enc" in read:
                out.append(Parameter(f"{c.name}.encoder_offset{k}",
                                     float(c.parameters.get(f"encoder_offset{k}", 0.0)), "encoder_offset", True))
    for c in system.components:
        if c.model != "DCMotorDrive":
            continue
        motor = get_motor_preset(c.parameters.get("preset", "motor1"))
        for field, kind in _MOTOR:
            out.append(Parameter(f"{c.name}.{field}", _given(c, field, getattr(motor, field)), kind))
        if c.parameters.get("friction", "tanh") == "lugre":     # mu_s >= mu: the ratio kept
            out.append(Parameter(f"{c.name}.mu_s", _given(c, "mu_s", motor.mu_s), "friction",
                                 follows=f"{c.name}.mu"))
    return [p for p in out if p.absolute or p.nominal != 0.0]


def load_perturb_file(path) -> dict:
    """``--perturb FILE.toml`` -> {"uncertainty": {pattern: u}, "distribution": str or None}.

    Raises
    ------
    ValueError
        Naming the file and the key for an unreadable file, an unknown key, a value that is
        not a finite number >= 0, or an unknown distribution.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"--perturb {path}: {exc}") from None
    unknown = set(data) - {"uncertainty", "distribution"}
    if unknown:
        raise ValueError(f"--perturb {path}: unknown key(s) {sorted(unknown)}; valid: distribution, [uncertainty]")
    table = data.get("uncertainty", {})
    if not isinstance(table, dict):
        raise ValueError(f"--perturb {path}: 'uncertainty' must be a table of parameter = number")
    for key, value in table.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value >= 0):
            raise ValueError(f"--perturb {path}: uncertainty {key!r} = {value!r} must be a finite number >= 0")
    distribution = data.get("distribution")
    if distribution is not None and distribution not in DISTRIBUTIONS:
        raise ValueError(f"--perturb {path}: distribution = {distribution!r}; valid: {', '.join(DISTRIBUTIONS)}")
    return {"uncertainty": {k: float(v) for k, v in table.items()}, "distribution": distribution}


def uncertainties(parameters: list, U: float, overrides: dict | None = None) -> dict:
    """Parameter name -> its u_p: ``U * WEIGHTS[kind]``, or the last matching pattern of
    ``overrides`` (fnmatch against the name).  A parameter that follows another (a LuGre
    drive's ``mu_s``) has None unless a pattern matches it.  A pattern that matches nothing
    is an error (ValueError naming it): a typo must not silently leave a parameter nominal."""
    if not (isinstance(U, (int, float)) and math.isfinite(U) and U >= 0.0):
        raise ValueError(f"uncertainty U = {U!r} must be a finite number >= 0")
    result = {p.name: None if p.follows else U * WEIGHTS[p.kind] for p in parameters}
    for pattern, u in (overrides or {}).items():
        matched = [name for name in result if fnmatch.fnmatchcase(name, pattern)]
        if not matched:
            raise ValueError(f"perturbation {pattern!r} matches no parameter of the scene; "
                             f"parameters: {', '.join(result)}")
        for name in matched:
            result[name] = float(u)
    return result


def _xi(seed: int, sample: int, name: str, distribution: str) -> float:
    """The standard draw of parameter ``name`` in ``sample``: its own stream, spawned from
    ``seed`` by (sample, crc32(name)) (numpy SeedSequence), independent of everything else."""
    sequence = np.random.SeedSequence(seed, spawn_key=(sample, zlib.crc32(name.encode())))
    rng = np.random.default_rng(sequence)
    if distribution == "uniform":
        return float(rng.uniform(-1.0, 1.0))
    while True:
        z = float(rng.standard_normal())
        if abs(z) <= TRUNCATE_SIGMA:
            return z


def draw(parameters: list, spread: dict, seed: int, sample: int, distribution: str = "uniform") -> dict:
    """Parameter name -> value of ``sample``: nominal (1 + u xi) or nominal + u xi.

    A parameter with u = 0 keeps exactly its nominal value; one with u None takes the relative
    change of the parameter it follows (which must be among ``parameters``)."""
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"distribution = {distribution!r}; valid: {', '.join(DISTRIBUTIONS)}")
    values = {}
    for p in parameters:
        u = spread[p.name]
        if u is None:
            continue
        if u == 0.0:
            values[p.name] = p.nominal
            continue
        xi = _xi(seed, sample, p.name, distribution)
        values[p.name] = p.nominal + u * xi if p.absolute else p.nominal * (1.0 + u * xi)
    nominal = {p.name: p.nominal for p in parameters}
    for p in parameters:
        if spread[p.name] is None:
            if p.follows not in values:
                raise ValueError(f"parameter {p.name} follows {p.follows!r}, which is not drawn with it")
            values[p.name] = p.nominal * (values[p.follows] / nominal[p.follows])
    return values


def perturbed(scene: Scene, parameters: list, values: dict) -> Scene:
    """``scene`` with the ``values`` set on its components; every drive whose motor is
    perturbed keeps its current controller designed for the nominal motor."""
    by_instance = {}
    for p in parameters:
        by_instance.setdefault(p.instance, {})[p.variable] = values[p.name]
        if p.variable in _DESIGN and scene.system.component(p.instance).model == "DCMotorDrive":
            design = _DESIGN[p.variable]
            current = scene.system.component(p.instance).parameters.get(design, PRESET_VALUE)
            by_instance[p.instance][design] = p.nominal if current == PRESET_VALUE else current
    components = tuple(replace(c, parameters={**c.parameters, **by_instance[c.name]}) if c.name in by_instance
                       else c for c in scene.system.components)
    return replace(scene, system=replace(scene.system, components=components))
