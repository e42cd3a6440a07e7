"""scenarios/scenes/pendulum.py without a run: the scenes as data at a sample time of 2 ms and
with each fidelity switch away from its default, and ``pendulum_metrics`` on synthetic columns
at 2 ms against its docstring written again here (issue 31: a second sample time, switches
and values off their defaults, values compared whole)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.scenes.pendulum import (BALANCED_DEG, PUSH, RELEASE_TILT, PendulumFidelity, pendulum_line,
                                       pendulum_metrics, pendulum_scene)

H = 2e-3


def test_a_scene_at_2ms_samples_its_controller_and_steps_its_master_at_2ms():
    """Catches the sample time reaching only one of the controller's T and the master's step,
    or the battery voltage not reaching both the controller and the drives."""
    scene = pendulum_scene("pendulum_drive", sample_time=H, v_battery=9.5)
    assert scene.system.step == H and scene.system.stop_time == 10.0
    ctrl = scene.system.component("ctrl").parameters
    assert ctrl == {"route": "forward_turn", "T": H, "v_battery": 9.5, "electrics": "quasi_static",
                    "friction": True, "yaw": True}
    for side in ("l", "r"):
        assert scene.system.component(f"drive_{side}").parameters == {
            "preset": "seed000", "mode": "voltage", "method": "quasi_static", "v_max": 9.5}
    assert scene.window == (0.0, 10.0) and scene.reference_end == 8.0 and scene.strategy == "LQR"


def test_each_scene_sets_its_own_start_and_the_others_do_not():
    """balance: released at 5 degrees; push: the torque impulse; each reference ends where its
    route stops.  Catches a scene's setting given to another, the push's fields swapped."""
    balance, push = pendulum_scene("pendulum_balance"), pendulum_scene("pendulum_push")
    assert balance.system.component("plant").parameters == {"model": "exact", "yaw": True, "psi0": RELEASE_TILT}
    assert RELEASE_TILT == pytest.approx(math.pi / 36, rel=1e-15)
    assert push.system.component("plant").parameters == {"model": "exact", "yaw": True, "push_torque": PUSH[0],
                                                         "push_start": PUSH[1], "push_duration": PUSH[2]}
    assert push.description == ("Wheeled pendulum (seed 000), a 0.2 N m torque on the body for 50 ms at t = 1 s; "
                                "exact model")
    for scene in (balance, push):
        assert scene.system.stop_time == 5.0 and scene.reference_end == 0.0
        assert scene.system.component("ctrl").parameters["route"] == "hold"


def test_ideal_electrics_wire_the_controllers_torques_to_the_plant_and_drop_the_drives():
    """Catches the drives kept, the torques wired crosswise, the current columns left in."""
    scene = pendulum_scene("pendulum_balance", PendulumFidelity(electrics="ideal", yaw=False, friction=False,
                                                                model="seed"), sample_time=H)
    assert [c.name for c in scene.system.components] == ["ctrl", "plant"]
    pairs = {(c.source, c.target) for c in scene.system.connections}
    assert pairs == {("plant.enc_l", "ctrl.enc_l"), ("plant.enc_r", "ctrl.enc_r"), ("plant.gyro", "ctrl.gyro"),
                     ("ctrl.tau_l", "plant.tau_l"), ("ctrl.tau_r", "plant.tau_r")}
    assert scene.columns["tau1"] == "ctrl.tau_l" and scene.columns["tau2"] == "ctrl.tau_r"
    assert "i_l" not in scene.columns and len(scene.system.record) == len(set(scene.columns.values()))
    assert scene.system.component("plant").parameters == {"model": "seed", "yaw": False, "psi0": RELEASE_TILT}
    ctrl = scene.system.component("ctrl").parameters
    assert (ctrl["electrics"], ctrl["friction"], ctrl["yaw"], ctrl["T"]) == ("ideal", False, False, H)
    assert scene.description.endswith("; seed model; fidelity yaw=False, electrics=ideal, friction=False")


def test_quasi_static_drives_without_friction_have_no_viscous_term_and_are_wired_side_by_side():
    """Catches the pendulum's drives crossed (left controller output to the right drive), or friction left
    on when switched off."""
    scene = pendulum_scene("pendulum_push", PendulumFidelity(friction=False))
    assert scene.system.component("drive_l").parameters["b"] == 0.0
    pairs = {(c.source, c.target) for c in scene.system.connections}
    for side in ("l", "r"):
        assert {(f"ctrl.v_{side}", f"drive_{side}.v_ref"), (f"plant.omega_{side}", f"drive_{side}.omega"),
                (f"drive_{side}.tau", f"plant.tau_{side}")} <= pairs
    assert scene.columns["i_r"] == "drive_r.i" and scene.columns["tau2"] == "drive_r.tau"


@pytest.mark.parametrize("bad, message", [({"electrics": "full"}, "electrics = 'full'; valid: quasi_static, ideal"),
                                          ({"model": "linear"}, "model = 'linear'; valid: exact, seed")])
def test_an_unknown_fidelity_is_refused_naming_it(bad, message):
    with pytest.raises(ValueError, match=message):
        PendulumFidelity(**bad)
    with pytest.raises(ValueError, match="unknown pendulum scene 'pendulum_fly'"):
        pendulum_scene("pendulum_fly")


def _columns(n=2501, settle_at=1201):
    """5 s at 2 ms: the pitch decays from 3 degrees and stays within 0.1 degree from sample
    ``settle_at`` on; drives that draw power; the reference moving, the axle off it by an error
    growing to 3 mm and 4 mm at the last sample, the heading turning to 90 degrees there."""
    t = np.arange(n) * H
    psi_deg = np.where(np.arange(n) < settle_at, 3.0 * np.cos(5 * t), 0.05 * np.sin(40 * t))
    psi_deg[settle_at - 1] = 0.2                            # the last sample outside
    x_d, y_d, growing = 1.0 + 0.1 * t, -0.05 * t, t / t[-1]
    return {"t": t, "psi": np.radians(psi_deg), "phi": np.radians(90.0) * growing,
            "x": x_d + 0.003 * growing, "y": y_d - 0.004 * growing, "x_d": x_d, "y_d": y_d,
            "v_l": 2.0 + np.sin(t), "i_l": 0.3 + 0.1 * np.cos(t), "v_r": np.full(n, -1.5), "i_r": np.full(n, -0.2)}


def test_pendulum_metrics_at_2ms_are_their_definitions():
    """Catches the energy's sum not weighted by the 2 ms step (or a side's v i left out), the
    settling time taken at the last sample outside instead of the next, the last second's
    window, the position error's axes or a sample other than the last, degrees and radians mixed."""
    c = _columns()
    m = pendulum_metrics(c, H)
    psi = [math.degrees(p) for p in c["psi"]]
    assert m["peak_pitch_deg"] == pytest.approx(max(abs(p) for p in psi), rel=1e-12) and m["peak_pitch_deg"] > 2.9
    assert m["settling_time_s"] == pytest.approx(1201 * H, abs=1e-12)
    assert m["last_second_pitch_deg"] == pytest.approx(max(abs(p) for p in psi[2001:]), rel=1e-12)
    assert m["last_second_pitch_deg"] < BALANCED_DEG
    energy = sum(H * (c["v_l"][k] * c["i_l"][k] + c["v_r"][k] * c["i_r"][k]) for k in range(len(c["t"])))
    assert m["energy_J"] == pytest.approx(energy, rel=1e-12) and m["energy_J"] > 0.0
    assert m["final_position_error_mm"] == pytest.approx(5.0, rel=1e-9)
    assert m["final_yaw_deg"] == pytest.approx(90.0, rel=1e-14)
    assert pendulum_line(m) == (f"pitch peak {m['peak_pitch_deg']:.3g} deg, last second "
                                f"{m['last_second_pitch_deg']:.3g} deg (settled within 0.1 deg at 2.40 s), "
                                "final position error 5 mm")


def test_a_pendulum_that_never_settles_or_never_leaves_the_band_and_one_without_drives():
    """Outside the band at the last sample: NaN and the line says so; never outside: 0 s;
    no currents recorded (ideal electrics): energy NaN."""
    c = _columns()
    c["psi"][-1] = math.radians(0.5)
    m = pendulum_metrics(c, H)
    assert math.isnan(m["settling_time_s"]) and "not within 0.1 deg at the end" in pendulum_line(m)
    c = _columns()
    c["psi"] = np.radians(np.full(len(c["t"]), 0.05))
    assert pendulum_metrics(c, H)["settling_time_s"] == 0.0
    del c["i_l"], c["i_r"]
    assert math.isnan(pendulum_metrics(c, H)["energy_J"])
    assert pendulum_metrics({k: v[:0] for k, v in c.items()}, H) == {}
