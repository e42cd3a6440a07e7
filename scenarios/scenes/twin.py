"""The bench twin: the bench scenes with the real bench's imperfections, calibrated on the circle.

``bench_real_circle_<S>`` and ``bench_real_triangle_<S>`` (S: the thesis' eight strategies) are
:func:`scenarios.scenes.thesis.bench` with, on top of its model (encoder counts included):

* a one-sample computation delay (``Fidelity.delay_steps`` = :data:`DELAY_STEPS`);
* LuGre friction with stiction in both drives (:mod:`motor.friction`), its Coulomb level
  the motor identification's μ (Tables 16, 18) times ``friction_scale``, its break-away
  torque ``stiction_ratio`` times that, its Stribeck speed ``stribeck_speed``;
* PWM voltage resolution of :data:`PWM_COUNTS` steps of the 24 V supply;
* current-sensing noise (``current_noise``, Gaussian, a stateless function of (seed, drive,
  sample)) and offset (``current_offset``) on the current each drive's loop reads;
* the real links' masses and inertias ``1 + inertia_error`` times the CAD estimates of
  Tables 4-5, which the controller's model keeps (the plant is what differs from the tables);
* each encoder's zero at a random phase within one count (uniform, a function of (seed,
  encoder)): where the count edges fall relative to the true zero differs from run to run.

The six numbers in :data:`PARAMETERS` (name -> bounds, unit, meaning) are the twin's only
free parameters, the same for all eight strategies.  Their one source of truth is
:data:`TWIN_FILE` (``scenarios/scenes/bench_twin.toml``), written by the fit
(``python -m scenarios.studies.twin_fit``, :mod:`scenarios.studies.twin_fit`) and read here by the scenes.
The noise seeds (current noise and encoder phase) are fixed in this module before any fit: :data:`FIT_SEEDS` for the fit,
:data:`SPREAD_SEEDS` for the spread the report shows; a scene uses ``SPREAD_SEEDS[0]``.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, fields, replace
from pathlib import Path

from controller.strategies import STRATEGY_NAMES
from motor import get_motor_preset
from motor.drive import uniform
from motor.presets import STICTION_RATIO, motor1
from plant import ENCODER_COUNTS, get_preset

from scenarios.scenes.scene import Scene
from scenarios.scenes.thesis import Fidelity, bench

#: The one source of truth of the twin's parameters (written by :mod:`scenarios.studies.twin_fit`).
TWIN_FILE = Path(__file__).resolve().parent / "bench_twin.toml"
#: Computation delay of the bench's controller [samples of 1 ms] (docs/twin.md: an assumption,
#: not fitted: the Raspberry Pi computes the law between two samples).
DELAY_STEPS = 1
#: PWM steps of the supply voltage: a Raspberry Pi's hardware PWM counts its 19.2 MHz clock,
#: so at the driver's 20 kHz (7.2.1) one period has 960 counts (an assumption, not fitted).
PWM_COUNTS = 960
#: Noise seeds, fixed before fitting: the fit averages over FIT_SEEDS, the report shows the
#: spread over SPREAD_SEEDS (their first is the scenes').
FIT_SEEDS = (101, 102)
SPREAD_SEEDS = (101, 102, 103, 104, 105)
KINDS = ("circle", "triangle")
#: The twin scenes run this long after the reference stops [s] (the bench scenes: 3 s): with
#: stiction and noise the sliding-mode laws hunt around the stop point for seconds before
#: they settle within one count (docs/twin.md); past this the run says ``settled`` false.
TWIN_SETTLE_TIME = 5.0


@dataclass(frozen=True)
class Bound:
    """A free parameter's range, unit and meaning."""

    low: float
    high: float
    unit: str
    meaning: str


#: The twin's free parameters (at most six, physical, bounded; module docstring).
PARAMETERS = {
    "friction_scale": Bound(0.5, 4.0, "1", "Coulomb friction of each drive / the identified μ (Tables 16, 18)"),
    "stiction_ratio": Bound(1.0, 3.0, "1", "break-away torque / Coulomb torque (LuGre Fs / Fc)"),
    "stribeck_speed": Bound(0.01, 1.0, "rad/s", "Stribeck speed (LuGre ωs)"),
    "current_offset": Bound(-0.3, 0.3, "A", "offset of the current each drive's loop reads"),
    "current_noise": Bound(0.0, 0.3, "A", "standard deviation of the noise on that current"),
    "inertia_error": Bound(-0.3, 1.0, "1", "the real links' masses and inertias / Tables 4-5's, minus 1"),
}


@dataclass(frozen=True)
class Twin:
    """One value of each of :data:`PARAMETERS` (the twin's calibration)."""

    friction_scale: float = 1.0
    stiction_ratio: float = STICTION_RATIO          # the motor presets' LuGre defaults
    stribeck_speed: float = motor1.omega_s
    current_offset: float = 0.0
    current_noise: float = 0.0
    inertia_error: float = 0.0

    def __post_init__(self):
        for name, bound in PARAMETERS.items():
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and bound.low <= value <= bound.high):
                raise ValueError(f"twin parameter {name} = {value!r} must be in [{bound.low:g}, {bound.high:g}] "
                                 f"{bound.unit} ({bound.meaning})")

    def values(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


assert tuple(f.name for f in fields(Twin)) == tuple(PARAMETERS)


def load_twin(path: Path = TWIN_FILE) -> Twin:
    """The calibrated twin of ``path`` (section ``[parameters]``).

    Raises
    ------
    ValueError
        The file is missing or unreadable, a parameter is missing, unknown or out of its bounds.
    """
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"twin file {path}: {exc}") from None
    values = data.get("parameters", {})
    unknown = sorted(set(values) - set(PARAMETERS))
    missing = sorted(set(PARAMETERS) - set(values))
    if unknown or missing:
        raise ValueError(f"twin file {path}: [parameters] must name exactly {', '.join(PARAMETERS)}"
                         f" (unknown: {', '.join(unknown) or 'none'}; missing: {', '.join(missing) or 'none'})")
    return Twin(**{name: float(values[name]) for name in PARAMETERS})


def write_twin(twin: Twin, fit: dict, path: Path = TWIN_FILE) -> Path:
    """Write ``twin`` and what the fit says about it (``fit``: flat name -> number or string)
    as ``path``; :func:`load_twin` reads it back."""
    lines = ["# The bench twin's calibration (scenarios/scenes/twin.py): written by `python -m scenarios.studies.twin_fit`,",
             "# fitted on the thesis' circle only (Tables 9, 11, 13). Do not edit by hand: refit.", "",
             "[parameters]"]
    for name, value in twin.values().items():
        bound = PARAMETERS[name]
        lines.append(f"{name} = {value!r}   # [{bound.low:g}, {bound.high:g}] {bound.unit}: {bound.meaning}")
    lines += ["", "[fit]"]
    for key, value in fit.items():
        lines.append(f"{key} = {_toml_value(value)}")
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)


def _toml_value(value) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def read_fit(path: Path = TWIN_FILE) -> dict:
    """The ``[fit]`` section of the twin file (what the fit recorded)."""
    return tomllib.loads(Path(path).read_text(encoding="utf-8")).get("fit", {})


def twin_fidelity(twin: Twin, seed: int) -> Fidelity:
    """The bench's effects of ``twin`` with noise seed ``seed`` (drive friction levels:
    :func:`bench_real`)."""
    return Fidelity(delay_steps=DELAY_STEPS, friction="lugre", pwm_counts=PWM_COUNTS,
                    current_offset=twin.current_offset, current_noise=twin.current_noise, noise_seed=seed)


#: The plant's link parameters ``inertia_error`` scales (masses and inertias of both links of
#: both chains; the rotors are the motor identification's, Tables 16 and 18, not CAD).
LINK_INERTIAS = ("m1", "m2", "Jz1", "Jz2")
#: The encoders' phase draws use instances ENCODER_STREAM + k, apart from the drives' noise (1, 2).
ENCODER_STREAM = 1 << 32


def encoder_phase(seed: int, k: int, counts: int = ENCODER_COUNTS) -> float:
    """Encoder ``k``'s zero error [rad] for noise seed ``seed``: uniform in [-1/2, 1/2) of one
    count of a ``counts``-count encoder, a function of (seed, k) only
    (:func:`motor.drive.uniform`)."""
    return (uniform(seed, ENCODER_STREAM + k, 0) - 0.5) * 2.0 * math.pi / counts


def twin_plant(parameters: dict, twin: Twin, seed: int) -> dict:
    """The bench plant's ``parameters`` with the twin's links (``inertia_error``, from the
    preset's Tables 4-5 values) and each encoder's phase (:func:`encoder_phase`)."""
    params = get_preset(parameters["preset"])
    out = dict(parameters)
    for k, chain in ((1, params.chain1), (2, params.chain2)):
        for name in LINK_INERTIAS:
            out[f"chain{k}_{name}"] = getattr(chain, name) * (1.0 + twin.inertia_error)
        out[f"encoder_offset{k}"] = encoder_phase(seed, k, parameters.get("encoder_counts", ENCODER_COUNTS))
    return out


def bench_real(strategy: str, kind: str = "circle", twin: Twin | None = None, seed: int | None = None) -> Scene:
    """The twin scene ``bench_real_<kind>_<strategy>``: :func:`scenarios.scenes.thesis.bench` with
    :func:`twin_fidelity`, each drive's LuGre levels (its own μ times ``friction_scale``,
    break-away ``stiction_ratio`` times that, Stribeck speed ``stribeck_speed``) and the plant
    of :func:`twin_plant`.  ``twin``
    defaults to :func:`load_twin`, ``seed`` to ``SPREAD_SEEDS[0]``."""
    if strategy not in STRATEGY_NAMES:
        raise ValueError(f"strategy = {strategy!r}; the twin has the thesis' eight: {', '.join(STRATEGY_NAMES)}")
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r}; valid: {', '.join(KINDS)}")
    twin = load_twin() if twin is None else twin
    seed = SPREAD_SEEDS[0] if seed is None else seed
    scene = bench(strategy, kind, fidelity=twin_fidelity(twin, seed))
    components = []
    for c in scene.system.components:
        if c.model == "DCMotorDrive":
            mu = twin.friction_scale * get_motor_preset(c.parameters["preset"]).mu
            c = replace(c, parameters={**c.parameters, "mu": mu, "mu_s": twin.stiction_ratio * mu,
                                       "omega_s": twin.stribeck_speed})
        elif c.model == "FiveBarPlant":
            c = replace(c, parameters=twin_plant(c.parameters, twin, seed))
        components.append(c)
    values = ", ".join(f"{k} {v:.4g}" for k, v in twin.values().items())
    system = replace(scene.system, components=tuple(components), stop_time=scene.reference_end + TWIN_SETTLE_TIME)
    return replace(scene, name=f"bench_real_{kind}_{strategy}", system=system,
                   description=f"Bench twin (docs/twin.md), {kind} trajectory, strategy {strategy}: the bench scene with "
                               f"a {DELAY_STEPS}-sample delay, {PWM_COUNTS}-step PWM, LuGre friction, noise and "
                               f"encoder-phase seed {seed}; {values}")


def twin_scenes() -> dict:
    """The twin's scene names -> (kind, strategy) of :func:`bench_real`."""
    return {f"bench_real_{kind}_{s}": (kind, s) for kind in KINDS for s in STRATEGY_NAMES}


def twin_scene_names() -> list[str]:
    return list(twin_scenes())
