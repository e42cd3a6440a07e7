"""Sampled components stepped at h = T / n sample once per period, on sub-step ``sample_phase``
(issue 26, item 1; :mod:`fmus.slave.sampling`, the drive's counter in kernels/src/drive.c).

The reference of each check is the component itself at h = T (the behaviour the default keeps)
or, for the drive's electrics, the exact solution of 4.162 written here.  Inputs are functions
of the period m and the sub-step j: the sampled sub-step gets the h = T run's input, the other
sub-steps other values, which a component that reads them between samples would show.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fmus.cosim.backends import InProcessInstance
from motor import get_motor_preset
from tests.fmus.slave.test_extremes import GOOD, set_variables, slave_class

T = 1e-3

#: Model -> (parameters, {input: (base, amplitude)}, outputs compared).
SAMPLED = {
    "Derivator": ({}, {"q1": (0.5, 0.01), "q2": (2.0, 0.02)}, ("dq1", "dq2", "ddq1", "ddq2")),
    "PositionController": (
        GOOD["PositionController"][0],
        {**{name: (value, 1e-3) for name, value in GOOD["PositionController"][1].items()},
         "dq1": (0.0, 0.05), "dq2": (0.0, 0.05), "dx_d": (0.0, 0.01)},
        ("tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2")),
    "BalanceController": ({}, {"enc_l": (0.01, 0.01), "enc_r": (0.02, 0.01), "gyro": (0.1, 0.05)},
                          ("v_l", "v_r", "tau_l", "tau_r")),
    "CurrentObserver": ({}, {"v": (1.0, 2.0), "omega": (2.0, 5.0)}, ("i_hat",)),
}


def input_value(base, amplitude, m, j, k):
    """The input of period m, sub-step j (k: the input's index): the h = T run's at j = 0,
    other values on the other sub-steps."""
    if j == 0:
        return base + amplitude * math.sin(0.7 * m + k + 1.0)
    return base + amplitude * math.cos(1.3 * m + 0.9 * j + k)


def new_slave(model, parameters=None, t0=0.0):
    slave = slave_class(model)(instance_name=model.lower())
    slave.setup_experiment(t0, None, None)
    slave.enter_initialization_mode()
    set_variables(slave, {**SAMPLED[model][0], **(parameters or {})}, initialise=False)
    slave.exit_initialization_mode()
    assert slave.error == ""
    return slave


def run(model, n, periods, phase=0, delay=0, parameters=None):
    """Outputs after each step of h = T / n over ``periods``; the inputs of step k are those
    of step k - ``delay`` (before: those of step 0)."""
    _, inputs, outputs = SAMPLED[model]
    slave = new_slave(model, {"sample_phase": phase, **(parameters or {})})
    h, rows = T / n, []
    for k in range(periods * n):
        m, j = divmod(max(k - delay, 0), n)
        for index, (name, (base, amplitude)) in enumerate(inputs.items()):
            setattr(slave, name, input_value(base, amplitude, m, j, index))
        assert slave.do_step(k * h, h), slave.error
        assert slave.error == ""
        rows.append([getattr(slave, name) for name in outputs])
    return np.array(rows)


@pytest.mark.parametrize("model", SAMPLED)
@pytest.mark.parametrize("n", [2, 4, 10])
def test_sub_steps_sample_as_h_equal_T_at_the_period_start_and_hold(model, n):
    """Catches a sampled component that samples at every sub-step instead of once per period."""
    periods = 12
    reference = run(model, 1, periods)
    sub = run(model, n, periods)
    assert np.all(np.isfinite(reference)) and np.ptp(reference, axis=0).max() > 0.0   # the outputs move
    np.testing.assert_array_equal(sub, np.repeat(reference, n, axis=0))


@pytest.mark.parametrize("model", SAMPLED)
def test_a_phase_shifts_the_sample_by_phase_steps(model):
    """Phase p on inputs delayed by p steps = phase 0 on the inputs, p steps later."""
    n, p, periods = 4, 3, 8
    base = run(model, n, periods)
    shifted = run(model, n, periods, phase=p, delay=p)
    np.testing.assert_array_equal(shifted[p:], base[:-p])
    start = new_slave(model)
    initial = [getattr(start, name) for name in SAMPLED[model][2]]
    np.testing.assert_array_equal(shifted[:p], [initial] * p)     # no sample before sub-step p


def test_the_dynamic_observer_integrates_every_sub_step():
    """Its state moves on every sub-step (as the drive's electrics do); its output, once per
    period, is the exact current of 4.162 with the held inputs."""
    motor = get_motor_preset("motor1")
    n, v, omega = 4, 3.0, 20.0
    slave = new_slave("CurrentObserver", {"kind": "dynamic", "sample_phase": n - 1, "omega0": omega})
    h = T / n
    published = []
    for k in range(3 * n):
        slave.v, slave.omega = v, omega
        assert slave.do_step(k * h, h), slave.error
        published.append(slave.i_hat)
    a = math.exp(-motor.R * T / motor.L)
    steady = (v - motor.ke * omega) / motor.R
    expected, i = [], 0.0
    for _ in range(3):
        expected += [i] * (n - 1)
        i = a * i + (1.0 - a) * steady
        expected.append(i)
    np.testing.assert_allclose(published, expected, rtol=1e-12, atol=1e-15)


# --- refusals ---------------------------------------------------------------------------------

@pytest.mark.parametrize("model", [*SAMPLED, "DCMotorDrive"])
def test_a_step_not_dividing_T_is_refused_naming_h_T_and_t(model):
    slave = new_drive() if model == "DCMotorDrive" else new_slave(model)
    assert slave.do_step(0.0, T / 4)
    assert not slave.do_step(T / 4, 0.3e-3)
    assert "h = 0.0003 s" in slave.error and "T = 0.001 s" in slave.error and "t = 0.00025 s" in slave.error
    assert "does not divide the sample time" in slave.error


@pytest.mark.parametrize("model", [*SAMPLED, "DCMotorDrive"])
@pytest.mark.parametrize("phase", [4, 7, -1])
def test_a_phase_outside_the_period_is_refused_at_the_first_step(model, phase):
    if model == "DCMotorDrive" and phase < 0:      # the drive's own check, at initialisation
        slave = slave_class(model)(instance_name="drive")
        set_variables(slave, {"sample_phase": phase})
        assert slave.error.startswith("initialisation refused: sample_phase must be a whole number")
        return
    slave = new_drive({"sample_phase": phase}) if model == "DCMotorDrive" else new_slave(model, {"sample_phase": phase})
    assert not slave.do_step(0.0, T / 4)
    assert f"sample_phase = {phase}" in slave.error and "[0, 4)" in slave.error and "t = 0.0 s" in slave.error
    accepted = new_drive({"sample_phase": 3}) if model == "DCMotorDrive" else new_slave(model, {"sample_phase": 3})
    assert accepted.do_step(0.0, T / 4) and accepted.error == ""


@pytest.mark.parametrize("model", [*SAMPLED, "DCMotorDrive"])
def test_the_step_changes_only_at_a_period_start(model):
    """Catches a sampled component accepting a new step size in mid-period."""
    slave = new_drive() if model == "DCMotorDrive" else new_slave(model)
    t = 0.0
    for h in (T / 2, T / 2, T / 4):          # a period of T / 2, then T / 4 from its start
        assert slave.do_step(t, h), slave.error
        t += h
    assert not slave.do_step(t, T / 2)       # one sub-step of T / 4 into the period
    assert "changes the step within a sample period" in slave.error or "within a controller period" in slave.error
    assert "h = 0.0005 s" in slave.error and "T = 0.001 s" in slave.error


def test_the_actuated_plant_samples_its_drives_on_its_phase():
    """ActuatedFiveBarPlant's two current loops share its sample_phase (the drive kernel counts)."""
    parameters, inputs = GOOD["ActuatedFiveBarPlant"]
    slave = slave_class("ActuatedFiveBarPlant")(instance_name="plant")
    set_variables(slave, {**parameters, "sample_phase": 3})
    set_variables(slave, inputs, initialise=False)
    voltages = []
    for k in range(8):
        assert slave.do_step(k * T / 4, T / 4), slave.error
        voltages.append(slave.v1)
    assert voltages[:3] == [0.0] * 3 and voltages[3] != 0.0 and voltages[3:7] == [voltages[3]] * 4
    late = slave_class("ActuatedFiveBarPlant")(instance_name="plant")
    set_variables(late, {**parameters, "sample_phase": 4})
    assert not late.do_step(0.0, T / 4) and "sample_phase = 4" in late.error


# --- the drive: only the voltage is sampled ----------------------------------------------------

def new_drive(parameters=None):
    slave = slave_class("DCMotorDrive")(instance_name="drive")
    set_variables(slave, parameters or {})
    assert slave.error == ""
    return slave


def drive_run(n, periods, phase=0, delay=0, omega_of=lambda m: 0.0):
    """(v, i, tau) after each step h = T / n; i_ref and i_hat as :func:`input_value`, the speed
    held over each period (``omega_of(m)``), inputs delayed by ``delay`` steps."""
    slave = new_drive({"sample_phase": phase})
    h, rows = T / n, []
    for k in range(periods * n):
        m, j = divmod(max(k - delay, 0), n)
        slave.i_ref = input_value(1.0, 0.5, m, j, 0)
        slave.i_hat = input_value(0.0, 0.3, m, j, 1)
        slave.omega = omega_of(k // n)
        assert slave.do_step(k * h, h), slave.error
        rows.append((slave.v, slave.i, slave.tau))
    return np.array(rows)


@pytest.mark.parametrize("n", [2, 4, 10])
def test_the_drive_holds_its_voltage_and_its_electrics_advance_every_sub_step(n):
    """Catches a drive that recomputes its voltage per sub-step or skips its electrics."""
    motor = get_motor_preset("motor1")
    periods = 10
    omega_of = lambda m: 5.0 + 3.0 * m               # noqa: E731 - the speed of period m
    reference = drive_run(1, periods, omega_of=omega_of)
    sub = drive_run(n, periods, omega_of=omega_of)
    np.testing.assert_array_equal(sub[:, 0], np.repeat(reference[:, 0], n))      # v: sampled, held
    # i at the period's ends: the same current as h = T (the exact electrics compose).
    np.testing.assert_allclose(sub[n - 1::n, 1], reference[:, 1], rtol=1e-9, atol=1e-12)
    # i within a period: 4.162 solved exactly over j h with the held v and omega.
    i_start = np.concatenate([[0.0], reference[:-1, 1]])
    j = np.arange(1, n + 1)
    for m in range(periods):
        u = reference[m, 0] - motor.ke * omega_of(m)
        decay = np.exp(-motor.R * j * (T / n) / motor.L)
        exact = i_start[m] * decay + u / motor.R * (1.0 - decay)
        np.testing.assert_allclose(sub[m * n:(m + 1) * n, 1], exact, rtol=1e-9, atol=1e-12)
    assert np.ptp(sub[:n, 1]) > 0.0                       # the current moves within a period


def test_the_drive_phase_shifts_its_sample_by_phase_steps():
    """Catches a drive's sample_phase that shifts its sampling by another number of sub-steps, or lets it
    act before its first sample."""
    n, p = 4, 2
    base = drive_run(n, 6)
    shifted = drive_run(n, 6, phase=p, delay=p)
    np.testing.assert_array_equal(shifted[p:], base[:-p])
    np.testing.assert_array_equal(shifted[:p, :2], 0.0)     # at rest until its first sample


# --- FMU state mid-period, and sample instants over 1e5 accumulated steps ----------------------

@pytest.mark.parametrize("model", ["Derivator", "CurrentObserver", "DCMotorDrive"])
def test_a_state_restored_mid_period_continues_bit_for_bit(model):
    """Catches a sampled slave's state that misses its position within the period (or its phase): restored
    mid-period, in place or serialised into another instance, it samples at other sub-steps."""
    inst = InProcessInstance(model, "x")
    inst.initialize({"sample_phase": 2}, 0.0)
    n, h = 4, T / 4
    name = {"Derivator": "q1", "CurrentObserver": "v", "DCMotorDrive": "i_ref"}[model]
    output = {"Derivator": "dq1", "CurrentObserver": "i_hat", "DCMotorDrive": "v"}[model]

    def advance(k0, k1, inst=inst):
        values = []
        for k in range(k0, k1):
            setattr(inst.slave, name, 0.3 + 0.1 * math.sin(k))
            inst.do_step(k * h, h)
            values.append(getattr(inst.slave, output))
        return values

    advance(0, n + 1)                       # mid-period: sub-step 1 of the second period
    state = inst.get_state()
    first = advance(n + 1, 4 * n)
    inst.set_state(state)
    assert advance(n + 1, 4 * n) == first
    assert len(set(first)) > 2              # samples taken after the restore
    fresh = InProcessInstance(model, "x")   # serialised, into another instance
    fresh.initialize({"sample_phase": 2}, 0.0)
    fresh.set_state(fresh.deserialize_state(inst.serialize_state(state)))
    assert advance(n + 1, 4 * n, fresh) == first


@pytest.mark.parametrize("model", ["CurrentObserver", "DCMotorDrive"])
def test_accumulated_time_does_not_move_the_sample_instants(model):
    """10^5 steps of T / 10 at t += h (as a tool accumulates it): a sample every 10th step,
    on sub-step 3, never one missed or doubled."""
    n, phase, steps = 10, 3, 100_000
    slave = new_drive({"sample_phase": phase}) if model == "DCMotorDrive" else new_slave(model, {"sample_phase": phase})
    name, output = ("i_ref", "v") if model == "DCMotorDrive" else ("v", "i_hat")
    h, t, last, changed = T / n, 0.0, getattr(slave, output), []
    for k in range(steps):
        setattr(slave, name, 1.0 + 0.5 * math.sin(0.37 * k))   # a new input every step
        if model == "DCMotorDrive":
            slave.i_hat = slave.i                               # the current loop closed: no windup
        assert slave.do_step(t, h), slave.error
        t += h
        value = getattr(slave, output)
        if value != last:
            changed.append(k)
        last = value
    assert abs(t - steps * h) > 0.0                             # the sum did drift from k h
    assert changed == list(range(phase, steps, n))


# --- the built FMUs in the three tools -------------------------------------------------------

@pytest.fixture(scope="module")
def sampled_fmus(built_fmus):
    """The FMUs of ``parcosim build`` (the session's, built once into a temporary directory)."""
    return built_fmus


@pytest.mark.parametrize("model", ["Derivator", "DCMotorDrive"])
def test_the_fmus_declare_their_period_and_fmpy_steps_by_it(model, sampled_fmus):
    """DefaultExperiment stepSize T, no variable steps: fmpy's simulate_fmu without a step
    size runs its default second at T (with a longer stop time it doubles its step: the
    docs tell users to pass output_interval)."""
    from fmpy import read_model_description, simulate_fmu

    md = read_model_description(str(sampled_fmus[model]))
    assert float(md.defaultExperiment.stepSize) == T
    assert md.coSimulation.canHandleVariableCommunicationStepSize is False
    phase = next(v for v in md.modelVariables if v.name == "sample_phase")
    assert (phase.type, phase.causality, phase.variability, phase.start) == ("Integer", "parameter", "fixed", "0")
    result = simulate_fmu(str(sampled_fmus[model]))
    np.testing.assert_allclose(np.diff(result["time"]), T, rtol=1e-9)
    assert result["time"][-1] == pytest.approx(1.0)


def test_the_derivator_fmu_in_fmpy_samples_on_its_phase(sampled_fmus):
    """Through fmpy, h = T / 4, phase 1, inputs delayed one step: the h = T run (in process)
    repeated four times, one step later."""
    from tests.support.fmi_support import FmuInstance

    n, p, periods = 4, 1, 6
    _, inputs, outputs = SAMPLED["Derivator"]
    fmu = FmuInstance(sampled_fmus["Derivator"], {"sample_phase": p})
    rows = []
    for k in range(periods * n):
        m, j = divmod(max(k - p, 0), n)
        fmu.step(T / n, **{name: input_value(base, amplitude, m, j, index)
                           for index, (name, (base, amplitude)) in enumerate(inputs.items())})
        rows.append([fmu.get(name) for name in outputs])
    assert fmu.get("error") == ""
    refused = FmuInstance(sampled_fmus["Derivator"], {"sample_phase": n})
    assert "sample_phase = 4" in refused.refused_step(T / n, q1=0.1)
    refused.close()
    fmu.close()
    np.testing.assert_array_equal(np.array(rows)[p:], np.repeat(run("Derivator", 1, periods), n, axis=0)[:-p])


def test_the_drive_fmu_state_taken_mid_period_continues_exactly(sampled_fmus):
    """fmi2GetFMUstate one sub-step into a period (fmpy), then the same steps twice."""
    from tests.support.fmi_support import FmuInstance

    fmu = FmuInstance(sampled_fmus["DCMotorDrive"], {"sample_phase": 2})
    h = T / 4

    def advance(k0, k1):
        rows = []
        for k in range(k0, k1):
            fmu.time = k * h
            fmu.step(h, i_ref=1.0 + 0.5 * math.sin(k), i_hat=fmu.get("i"), omega=3.0)
            rows.append((fmu.get("v"), fmu.get("i"), fmu.get("tau")))
        return rows

    advance(0, 5)
    state = fmu.fmu.getFMUstate()
    first = advance(5, 16)
    fmu.fmu.setFMUstate(state)
    again = advance(5, 16)
    fmu.fmu.freeFMUstate(state)
    fmu.close()
    assert again == first
    assert [k for k in range(1, 11) if first[k][0] != first[k - 1][0]] == [1, 5, 9]   # sub-step 2 of 4


def _phase_changes(values) -> list:
    return [k for k in range(1, len(values)) if values[k] != values[k - 1]]


def test_libcosim_and_ecos_step_a_sub_stepped_derivator(sampled_fmus):
    """A Trajectory feeding a Derivator (sample_phase 2) at a plain 0.25 ms step in libcosim
    and in Ecos: the estimate changes on sub-step 2 of every period, no refusal.  The first
    sample (k = 2) starts the derivator at rest at its angle, where the estimate is exactly 0,
    the value before it: the first change is on the second period's sample."""
    from fmpy import read_model_description

    from fmus.ssp.libcosim import libcosim_available
    from fmus.ssp.run import ecos_available

    refs = {m: {v.name: v.valueReference for v in read_model_description(str(sampled_fmus[m])).modelVariables}
            for m in ("Derivator", "Trajectory")}
    h, steps, expected = T / 4, 24, list(range(6, 24, 4))
    ran = 0
    if libcosim_available() is None:
        from libcosimpy.CosimExecution import CosimExecution
        from libcosimpy.CosimObserver import CosimObserver
        from libcosimpy.CosimSlave import CosimLocalSlave

        execution = CosimExecution.from_step_size(step_size=int(round(h * 1e9)))
        traj = execution.add_local_slave(CosimLocalSlave(str(sampled_fmus["Trajectory"]), "traj"))
        deriv = execution.add_local_slave(CosimLocalSlave(str(sampled_fmus["Derivator"]), "deriv"))
        execution.connect_real_variables(traj, refs["Trajectory"]["x_d"], deriv, refs["Derivator"]["q1"])
        execution.integer_initial_value(deriv, refs["Derivator"]["sample_phase"], 2)
        last = CosimObserver.create_last_value()
        execution.add_observer(last)
        values = []
        for _ in range(steps):
            assert execution.step()
            values.append(last.last_real_values(deriv, [refs["Derivator"]["dq1"]])[0])
        assert _phase_changes(values) == expected
        assert last.last_string_values(deriv, [refs["Derivator"]["error"]]) == [b""]
        ran += 1
    if ecos_available() is None:
        from ecospy import EcosSimulation, EcosSimulationStructure

        structure = EcosSimulationStructure()
        structure.add_model("traj", str(sampled_fmus["Trajectory"]))
        structure.add_model("deriv", str(sampled_fmus["Derivator"]))
        structure.make_real_connection("traj::x_d", "deriv::q1")
        structure.add_parameter_set("init", {"deriv::sample_phase": 2})
        sim = EcosSimulation(structure=structure, step_size=h)
        try:
            assert sim.init(0.0, "init")
            values = []
            for _ in range(steps):
                sim.step(1)
                values.append(sim.get_real("deriv::dq1"))
            assert _phase_changes(values) == expected and sim.get_string("deriv::error") == ""
        finally:
            sim.terminate()
            sim.free()
        ran += 1
    if not ran:
        pytest.skip("neither libcosim nor Ecos loads")
