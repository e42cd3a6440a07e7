"""The wheeled pendulum's scenes (seed 000): the same drives and master, another plant and controller.

Scenes (:data:`PENDULUM_SCENES`):

``pendulum_balance``
    released at rest tilted 5 degrees, the controller holds it at the origin for 5 s;
``pendulum_drive``
    1 m forward along +x (0.5-5.5 s), then a 90 degree left turn in place (6-8 s), 10 s;
``pendulum_push``
    upright at rest, a torque impulse on the body (:data:`PUSH`), 5 s.

Components: ``plant`` (WheeledPendulum), ``ctrl`` (BalanceController: encoders and gyro in,
voltages out), ``drive_l``/``drive_r`` (DCMotorDrive, preset ``seed000``, voltage mode,
quasi-static electrics).  Columns: section 6's (``x_d``, ``y_d`` the reference axle position,
``tau1``, ``tau2`` the left and right wheel torques) plus ``psi``, ``phi``, ``theta`` and the
drives' ``v_l``, ``v_r``, ``i_l``, ``i_r``.  Fidelity switches (:class:`PendulumFidelity`):
yaw on/off, electrics quasi-static/ideal, friction on/off.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fmus.cosim.system import Component, Connection, System
from scenarios.scenes.scene import Scene

#: Release tilt of ``pendulum_balance`` [rad].
RELEASE_TILT = math.radians(5.0)
#: ``pendulum_push``: (torque [N m], start [s], duration [s]) on the body, + toward the heading.
PUSH = (0.2, 1.0, 0.05)
#: The balance criterion of ``pendulum_balance``: |psi| <= this over the last second [deg].
BALANCED_DEG = 0.1
PENDULUM_SCENES = ("pendulum_balance", "pendulum_drive", "pendulum_push")


@dataclass(frozen=True)
class PendulumFidelity:
    """What a pendulum scene models.

    Parameters
    ----------
    yaw : bool
        The yaw degree of freedom (False: heading locked, the controller drops the yaw rows).
    electrics : {"quasi_static", "ideal"}
        Seed 000's drives (22) as ``DCMotorDrive`` components, or ideal torque sources (no
        drive components; the controller's ``tau_l``, ``tau_r`` = (K_t/R_m) v go to the plant).
    friction : bool
        The motors' f_m (drive ``b``).
    model : {"exact", "seed"}
        The plant's equations.
    """

    yaw: bool = True
    electrics: str = "quasi_static"
    friction: bool = True
    model: str = "exact"

    def __post_init__(self):
        if self.electrics not in ("quasi_static", "ideal"):
            raise ValueError(f"electrics = {self.electrics!r}; valid: quasi_static, ideal")
        if self.model not in ("exact", "seed"):
            raise ValueError(f"model = {self.model!r}; valid: exact, seed")


def pendulum_scene(name: str, fidelity: PendulumFidelity = PendulumFidelity(), sample_time: float = 1e-3,
                   v_battery: float = 8.0):
    """The scene called ``name`` (:data:`PENDULUM_SCENES`) with ``fidelity``."""
    if name not in PENDULUM_SCENES:
        raise ValueError(f"unknown pendulum scene {name!r}; valid: {', '.join(PENDULUM_SCENES)}")
    f = fidelity
    route = "forward_turn" if name == "pendulum_drive" else "hold"
    stop = 10.0 if name == "pendulum_drive" else 5.0
    plant = {"model": f.model, "yaw": f.yaw}
    if name == "pendulum_balance":
        plant["psi0"] = RELEASE_TILT
    if name == "pendulum_push":
        plant.update(push_torque=PUSH[0], push_start=PUSH[1], push_duration=PUSH[2])
    ctrl = {"route": route, "T": sample_time, "v_battery": v_battery, "electrics": f.electrics,
            "friction": f.friction, "yaw": f.yaw}
    components = [Component("ctrl", "BalanceController", ctrl)]
    wiring = [("plant.enc_l", "ctrl.enc_l"), ("plant.enc_r", "ctrl.enc_r"), ("plant.gyro", "ctrl.gyro")]
    columns = {"x": "plant.x", "y": "plant.y", "x_d": "ctrl.x_d", "y_d": "ctrl.y_d"}
    if f.electrics == "quasi_static":
        for side in ("l", "r"):
            drive = {"preset": "seed000", "mode": "voltage", "method": "quasi_static", "v_max": v_battery}
            if not f.friction:
                drive["b"] = 0.0
            components.append(Component(f"drive_{side}", "DCMotorDrive", drive))
            wiring += [(f"ctrl.v_{side}", f"drive_{side}.v_ref"), (f"plant.omega_{side}", f"drive_{side}.omega"),
                       (f"drive_{side}.tau", f"plant.tau_{side}")]
        columns.update({"tau1": "drive_l.tau", "tau2": "drive_r.tau"})
    else:
        wiring += [("ctrl.tau_l", "plant.tau_l"), ("ctrl.tau_r", "plant.tau_r")]
        columns.update({"tau1": "ctrl.tau_l", "tau2": "ctrl.tau_r"})
    components.append(Component("plant", "WheeledPendulum", plant))
    columns.update({"psi": "plant.psi", "phi": "plant.phi", "theta": "plant.theta",
                    "omega_l": "plant.omega_l", "omega_r": "plant.omega_r",
                    "v_l": "ctrl.v_l", "v_r": "ctrl.v_r", "psi_hat": "ctrl.psi_hat"})
    if f.electrics == "quasi_static":
        columns.update({"i_l": "drive_l.i", "i_r": "drive_r.i"})
    system = System(tuple(components), tuple(Connection(s, t) for s, t in wiring),
                    tuple(dict.fromkeys(columns.values())), stop_time=stop, step=sample_time)
    what = {"pendulum_balance": f"released at rest tilted {math.degrees(RELEASE_TILT):g} deg, held at the origin",
            "pendulum_drive": "1 m forward, then a 90 deg left turn in place",
            "pendulum_push": f"a {PUSH[0]:g} N m torque on the body for {1e3 * PUSH[2]:g} ms at t = {PUSH[1]:g} s"}[name]
    description = f"Wheeled pendulum (seed 000), {what}; {f.model} model"
    if f != PendulumFidelity():
        description += f"; fidelity yaw={f.yaw}, electrics={f.electrics}, friction={f.friction}"
    return Scene(name, description, system, columns, (0.0, stop), 8.0 if route == "forward_turn" else 0.0, "LQR")


def pendulum_metrics(columns: dict, step: float) -> dict:
    """Peak pitch, settling time, final position error, energy drawn, last-second pitch.

    ``settling_time_s``: from when on |psi| stays within :data:`BALANCED_DEG` (NaN if it never
    does); ``energy_J``: the electrical energy the drives drew, sum over both of the
    integral of v i dt (negative while regenerating; NaN without drives);
    ``final_position_error_mm``: |axle - reference| at the last sample.
    """
    t, psi = columns["t"], np.degrees(columns["psi"])
    if not len(t):
        return {}
    outside = np.nonzero(np.abs(psi) > BALANCED_DEG)[0]
    settled = float(t[outside[-1] + 1]) if len(outside) and outside[-1] + 1 < len(t) else (
        0.0 if not len(outside) else float("nan"))
    last = t >= t[-1] - 1.0 + 1e-9
    energy = (float(step * np.sum(columns["v_l"] * columns["i_l"] + columns["v_r"] * columns["i_r"]))
              if "i_l" in columns else float("nan"))
    return {
        "peak_pitch_deg": float(np.max(np.abs(psi))),
        "last_second_pitch_deg": float(np.max(np.abs(psi[last]))),
        "settling_time_s": settled,
        "final_position_error_mm": 1e3 * float(math.hypot(columns["x"][-1] - columns["x_d"][-1],
                                                          columns["y"][-1] - columns["y_d"][-1])),
        "final_yaw_deg": float(np.degrees(columns["phi"][-1])),
        "energy_J": energy,
    }


def pendulum_line(metrics: dict) -> str:
    """What ``parcosim run`` says of a pendulum run: its pitch, settling and position error."""
    settle = metrics.get("settling_time_s", float("nan"))
    settled = f"settled within {BALANCED_DEG:g} deg at {settle:.2f} s" if math.isfinite(settle) else \
        f"not within {BALANCED_DEG:g} deg at the end"
    return (f"pitch peak {metrics['peak_pitch_deg']:.3g} deg, last second {metrics['last_second_pitch_deg']:.3g} deg "
            f"({settled}), final position error {metrics['final_position_error_mm']:.3g} mm")


def plot_pendulum(scene, columns: dict, out_dir) -> list:
    """The pendulum's figures: ``pitch.png`` (psi and the observer's estimate), ``wheel_speeds.png``,
    ``voltages.png`` (and the currents when the drives are modelled), ``path.png`` (the axle
    against its reference, at least 10 cm wide: a balance scene hardly moves)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir, t = Path(out_dir), columns["t"]
    panels = {"pitch.png": [(("psi", "psi_hat"), "pitch [deg]", np.degrees)],
              "wheel_speeds.png": [(("omega_l",), "left wheel [rad/s]", None),
                                   (("omega_r",), "right wheel [rad/s]", None)],
              "voltages.png": [(("v_l", "v_r"), "voltage [V]", None)]}
    if "i_l" in columns:
        panels["voltages.png"].append((("i_l", "i_r"), "current [A]", None))
    files = []
    for name, rows in panels.items():
        fig, axes = plt.subplots(len(rows), 1, figsize=(7, 2.5 * len(rows) + 0.5), sharex=True, squeeze=False)
        for ax, (keys, label, scale) in zip(axes[:, 0], rows):
            for key in keys:
                ax.plot(t, columns[key] if scale is None else scale(columns[key]), lw=0.8, label=key)
            ax.set_ylabel(label)
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right")
        axes[-1, 0].set_xlabel("t [s]")
        axes[0, 0].set_title(scene.name)
        files.append(out_dir / name)
        fig.savefig(files[-1], dpi=120, bbox_inches="tight")
        plt.close(fig)
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(1e3 * columns["x_d"], 1e3 * columns["y_d"], "k--", lw=1, label="reference")
    ax.plot(1e3 * columns["x"], 1e3 * columns["y"], "C0", lw=1, label="axle")
    xs = 1e3 * np.concatenate([columns["x"], columns["x_d"]])
    ys = 1e3 * np.concatenate([columns["y"], columns["y_d"]])
    half = max(50.0, 0.55 * max(np.ptp(xs), np.ptp(ys)))
    cx, cy = 0.5 * (xs.min() + xs.max()), 0.5 * (ys.min() + ys.max())
    ax.set(xlabel="x [mm]", ylabel="y [mm]", title=scene.name, aspect="equal",
           xlim=(cx - half, cx + half), ylim=(cy - half, cy + half))
    ax.legend()
    files.append(out_dir / "path.png")
    fig.savefig(files[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    return files
