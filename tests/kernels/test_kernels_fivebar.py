"""The 5R's C kernel (kernels/src/fivebar.c) against oracles: energy conservation, the loop
closure, refusals that change nothing, and the C structs' layout as Python packs them.
(tests/plant/test_plant_dynamics.py holds it against the general algorithm, state by state.)"""
from __future__ import annotations

import ctypes
import math
from dataclasses import replace

import numpy as np
import pytest

import kernels
from plant import IntegratorSettings, PlantSimulator, fast5r, fivebar, get_preset
from plant.simulator import MEASURES, SINGULAR_STOP, PlantError

GRAVITY = (0.0, -9.81, 0.0)
DT = 1e-3


def potential_energy(params, q) -> float:
    """-g . (sum of mass times centre of mass) of the links and the end effector, from the
    world link angles of the thesis' q (bench preset: no counter-masses)."""
    g = np.array(params.gravity[:2])
    phi11, phi12 = q[3], q[3] + q[4]
    phi21, phi22 = math.pi - q[5], math.pi - (q[5] + q[6])
    energy = -params.m0 * float(g @ q[:2])
    for c, base, a, b in ((params.chain1, params.l0, phi11, phi12), (params.chain2, -params.l0, phi21, phi22)):
        elbow = np.array([base + c.l1 * math.cos(a), c.l1 * math.sin(a)])
        com1 = np.array([base + c.lg1 * math.cos(a), c.lg1 * math.sin(a)])
        com2 = elbow + c.lg2 * np.array([math.cos(b), math.sin(b)])
        energy -= c.m1 * float(g @ com1) + c.m2 * float(g @ com2)
    return energy


#: Distance from a chain's serial singularity (|sin theta_k2|) where the energy check stops.
SERIAL_MARGIN = 0.05


@pytest.mark.parametrize("gravity", [(0.0, 0.0, 0.0), GRAVITY, (9.81, 0.0, 0.0)])
def test_unactuated_frictionless_5r_keeps_its_energy_under_rk4(gravity):
    """No torque, no friction: kinetic (the general model's M', with the rotors) plus potential
    energy stays constant to RK4's truncation (1.8e-10 of the kinetic energy at most here, and
    16 substeps give 256 times less) while the mechanism swings through a good part of its
    workspace; the loop stays closed.  A wrong inertia, Coriolis or gravity term, or a wrong
    elimination of the constraints, makes energy drift by far more.

    The run stops where a chain comes within SERIAL_MARGIN of its serial singularity
    (sin theta_k2 = 0, after 165-343 steps): the elimination divides by det(E_k J_k), and the
    energy across the crossing jumps by an amount set by rounding (2e-8 to 3e-6 of the kinetic
    energy with libm's or the kernels' sin and cos, 2e-7 with libm and 16 substeps)."""
    params = replace(get_preset("bench"), gravity=gravity)
    sim = PlantSimulator(params, 0.0, 0.15, IntegratorSettings(substeps=4), dx0=0.4, dy0=0.3)
    energy = lambda: sim.kinetic_energy() + potential_energy(params, sim.q)   # noqa: E731
    e0, scale, start = energy(), sim.kinetic_energy(), sim.y[:2].copy()
    steps = 0
    while steps < 400:
        sim.step(0.0, 0.0, DT)
        if min(abs(math.sin(sim.y[4])), abs(math.sin(sim.y[6]))) < SERIAL_MARGIN:
            break
        steps += 1
        assert sim.residual_norm() < 1e-9
        assert abs(energy() - e0) <= 1e-9 * scale, steps
    assert steps >= 150
    assert np.linalg.norm(sim.y[:2] - start) > 0.1          # it moved


def _plant(settings=IntegratorSettings()):
    sim = PlantSimulator(get_preset("bench"), 0.0, 0.15, settings)
    return sim, sim._fast


def test_plant_io_steps_as_the_simulator_and_publishes_its_outputs():
    """Catches a plant I/O step that differs from the simulator or publishes stale outputs."""
    sim, kernel = _plant()
    state = sim.y.copy()
    context = kernel.context(state)
    refusal = kernels.Refusal()
    for k in range(5):
        x = np.array([0.01 * k, -0.02] + [0.0] * 11)
        assert fast5r.plant_io_c(ctypes.addressof(context), kernels.address(x), 0.0, DT, ctypes.byref(refusal)) == 0
        sim.step(0.01 * k, -0.02, DT)
        assert np.array_equal(state, sim.y)
        outputs = sim.outputs()
        assert x[2:].tolist() == [outputs[name] for name in ("q1", "q2", "dq1", "dq2", "x", "y", "dx", "dy",
                                                             "q1_enc", "q2_enc", "residual")]


def test_the_trigonometry_kept_for_the_next_step_gives_the_bits_of_a_fresh_scratch():
    """pc_fivebar_step keeps the trial state's sines and cosines in its scratch for the next
    step's first evaluation: a run through one scratch (kept, and stale after a state put back
    or moved) is bit for bit a run whose every step starts from a zeroed one."""
    sim, kernel = _plant()
    kept, fresh = sim.y.copy(), sim.y.copy()
    kept_context, fresh_context = kernel.context(kept), kernel.context(fresh)
    fresh_scratch = fresh_context.buffers[-1]
    refusal = kernels.Refusal()
    earlier = None
    for k in range(120):
        x = np.array([0.02 * math.cos(0.1 * k), -0.01 * math.sin(0.07 * k)] + [0.0] * 11)
        y = x.copy()
        fresh_scratch[:] = 0.0
        status = fast5r.plant_io_c(ctypes.addressof(kept_context), kernels.address(x), 0.0, DT, ctypes.byref(refusal))
        assert status == fast5r.plant_io_c(ctypes.addressof(fresh_context), kernels.address(y), 0.0, DT,
                                           ctypes.byref(refusal)) == 0
        assert kept.tobytes() == fresh.tobytes() and x.tobytes() == y.tobytes()
        if k == 40:
            earlier = kept.copy()
        if k == 80:       # a restored state: the kept trigonometry is another state's
            kept[:], fresh[:] = earlier, earlier
        if k == 100:      # a nudged angle (the same within 1 ulp): not the kept one
            kept[3] = fresh[3] = np.nextafter(kept[3], 1.0)


def _rk4_fresh(kernel, z, u_star, baumgarte, dt, substeps):
    """Classic RK4 of the kernel's derivative (its trigonometry computed at every evaluation)."""
    h, y = dt / substeps, z.copy()
    for _ in range(substeps):
        k1 = kernel.derivative(y, u_star, baumgarte)
        k2 = kernel.derivative(y + 0.5 * h * k1, u_star, baumgarte)
        k3 = kernel.derivative(y + 0.5 * h * k2, u_star, baumgarte)
        k4 = kernel.derivative(y + h * k3, u_star, baumgarte)
        y = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return y


@pytest.mark.parametrize("dt, steps", [(1e-3, 200), (2e-2, 12)])
def test_the_rk4_stages_turned_sines_are_the_fresh_ones_within_rounding(dt, steps):
    """pc_fivebar_step turns the step's start sines and cosines by each RK4 stage's angle
    increment (series in the increment, up to 2^-5 rad; beyond, computed afresh).  Catches a
    wrong turn (a sign, a series coefficient, another angle's increment) or a wrong fresh path: each
    trial state equals RK4 of pc_fivebar_derivative (fresh sines and cosines at every stage, the
    RK4 written here: pc_fivebar_advance turns them as the step does) within 1e-14 of max(1, |entry|) (2.4e-16 seen), in 1 ms steps (every
    stage turned) and in 20 ms steps of the same motion (angles move up to 0.09 rad a step:
    stages past 2^-5 rad computed afresh)."""
    sim = PlantSimulator(get_preset("bench"), 0.0, 0.15, dx0=0.4, dy0=0.3)
    kernel = sim._fast
    baumgarte, substeps = kernel.s[0], int(kernel.s[1])
    z, moved = sim.y.copy(), 0.0
    for k in range(steps):
        u1, u2 = 0.02 * math.cos(0.3 * k), -0.01
        assert kernel.step(z, u1, u2, dt) == 0, k
        trial = kernel.scratch[:z.size].copy()
        fresh = _rk4_fresh(kernel, z, (u1, u2), baumgarte, dt, substeps)
        assert np.all(np.abs(trial - fresh) <= 1e-14 * np.maximum(np.abs(fresh), 1.0)), k
        moved = max(moved, float(np.abs(trial[3:7] - z[3:7]).max()))
        z = trial
    assert moved > (0.05 if dt > 1e-2 else 0.003)


@pytest.mark.parametrize("start, rate", [(0.5, -48.0), (-0.5, 48.0), (0.3, -29.0)])
def test_stages_far_from_the_start_near_stretched_elbows_are_computed_afresh(start, rate):
    """Both elbow angles (theta_12, theta_22) start at ``start`` and sweep through about 0 within
    one 20 ms RK4 step: the later stages are 0.3-0.5 rad from the step's start, far beyond the
    2^-5 rad the turning series holds for.  Catches a turn-or-fresh choice that looks at a
    stage's angle instead of its distance from the start (it would turn these stages by the
    series and lose 1e-8): the trial equals RK4 of fresh derivatives to 1e-14."""
    z, trial, fresh = _swept_step([4, 6], start, rate)
    assert np.all(np.abs(trial - fresh) <= 1e-14 * np.maximum(np.abs(fresh), 1.0))
    assert np.abs(trial[[4, 6]] - z[[4, 6]]).min() > 0.25      # the stages did move that far


def _swept_step(angles, start, rate, dt=2e-2):
    """(z, trial, fresh): the bench's state with the ``angles`` (state indices) at ``start`` and their
    rates at ``rate``, the kernel's step of ``dt`` from it and RK4 of fresh derivatives over the same."""
    sim = PlantSimulator(get_preset("bench"), 0.0, 0.15)
    kernel = sim._fast
    baumgarte, substeps = kernel.s[0], int(kernel.s[1])
    z = sim.y.copy()
    z[angles], z[[k + 7 for k in angles]] = start, rate
    trial = kernel.advance(z, 0.0, 0.0, baumgarte, dt, substeps)
    return z, trial, _rk4_fresh(kernel, z, (0.0, 0.0), baumgarte, dt, substeps)


@pytest.mark.parametrize("index", [0, 1])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_a_non_finite_input_is_refused_with_its_code_and_changes_nothing(index, value):
    """Catches a plant kernel that steps on a non-finite torque or changes its state or scratch."""
    sim, kernel = _plant()
    state = sim.y.copy()
    context = kernel.context(state)
    scratch = context.buffers[-1]
    scratch[:] = 0.5
    before, scratch_before = state.copy(), scratch.copy()
    x = np.full(13, 7.0)
    x[index] = value
    refusal = kernels.Refusal()
    status = fast5r.plant_io_c(ctypes.addressof(context), kernels.address(x), 0.0, DT, ctypes.byref(refusal))
    assert (status, refusal.code, refusal.index) == (fast5r.NONFINITE_INPUT, fast5r.NONFINITE_INPUT, index)
    assert refusal.value == value or (math.isnan(value) and math.isnan(refusal.value))
    assert np.array_equal(state, before) and np.array_equal(scratch, scratch_before)
    assert x[2:].tolist() == [7.0] * 11 and x[1 - index] == 7.0


def test_a_non_finite_voltage_or_state_is_refused_and_changes_nothing():
    """Catches the actuated kernel stepping on a non-finite voltage or state."""
    sim, kernel = _plant()
    a_motors = np.array([[0, 1.0, 1e-3, 0.05, 0.05, 1e-5, 0.0, 0.1], [1, 1.0, 1e-3, 0.05, 0.05, 1e-5, 0.0, 0.1]])
    state = np.concatenate([sim.y, [0.1, -0.2]])
    before = state.copy()
    x = np.zeros(6 + 13)
    refusal = kernels.Refusal()
    voltages = np.array([1.0, math.nan])
    context = kernel.context(state, a_motors, voltages, first=6)
    status = fast5r.actuated_io_c(ctypes.addressof(context), kernels.address(x), 0.0, DT, ctypes.byref(refusal))
    assert (status, refusal.index) == (fast5r.NONFINITE_INPUT, 3)        # voltage 1: u1, u2, then the voltages
    assert np.array_equal(state, before) and not x.any()
    voltages[1] = 2.0
    state[8] = math.nan                                                  # dy
    before = state.copy()
    status = fast5r.actuated_io_c(ctypes.addressof(context), kernels.address(x), 0.0, DT, ctypes.byref(refusal))
    assert (status, refusal.index) == (fast5r.NONFINITE_STATE, 14)       # the currents are checked first
    assert np.array_equal(state, before, equal_nan=True) and not x.any()


def test_a_singular_pose_is_refused_naming_the_measure():
    """Driven into the distal links' alignment, the step that gets there is refused with the
    parallel measure (index 2) below SINGULAR_STOP; the state is the last accepted one."""
    sim, kernel = _plant()
    state = sim.y.copy()
    context = kernel.context(state)
    refusal = kernels.Refusal()
    x = np.zeros(13)
    for _ in range(5000):
        last = state.copy()
        x[:2] = (0.05, 0.0)
        status = fast5r.plant_io_c(ctypes.addressof(context), kernels.address(x), 0.0, DT, ctypes.byref(refusal))
        if status:
            break
    assert status == fast5r.SINGULAR and abs(refusal.value) < SINGULAR_STOP
    assert np.array_equal(state, last)
    measures = fivebar.singularity(get_preset("bench"), *context.buffers[-1][:2])   # the refused trial state
    assert refusal.value == pytest.approx((measures.serial1, measures.serial2, measures.parallel)[refusal.index],
                                          abs=1e-5)   # IK near the singularity: ill-conditioned


def test_c_layouts_are_the_python_packing():
    """Every named parameter lands where the C struct has it, the fields tile each buffer,
    and the ctypes mirrors of the pointer structs have the C sizes."""
    params = get_preset("thesis_sim")
    p = fast5r.pack_params(params)
    assert p[fast5r.PARAMS["l0"]][0] == params.l0 and p[fast5r.PARAMS["m0"]][0] == params.m0
    assert p[fast5r.PARAMS["gravity"]].tolist() == list(params.gravity[:2])
    chains = p[fast5r.PARAMS["chain"]].reshape(2, fast5r.CHAIN_SIZE)
    for row, c in zip(chains, (params.chain1, params.chain2)):
        assert [row[fast5r.CHAIN[n]][0] for n in ("l1", "l2", "J_rotor")] == [c.l1, c.l2, c.J_rotor]
    for layout in (fast5r.PARAMS, fast5r.CHAIN, fast5r.MOTOR, fast5r.SETTINGS, fast5r.REPORT, fast5r.INVERSE):
        places = sorted((s.start, s.stop) for s in layout.values())
        assert places[0][0] == 0 and all(a[1] == b[0] for a, b in zip(places, places[1:]))
    assert fast5r.PARAMS_SIZE == 4 + 2 * 9 and fast5r.MOTOR_COLUMNS == 8 and fast5r.PLANT_STATES == 14
    assert ctypes.sizeof(fast5r.Context) == fast5r.CONTEXT_SIZE
    scratch_words = kernels.function("pc_fivebar_scratch_words", ctypes.c_int, ctypes.c_int)
    assert fast5r.SCRATCH_WORDS == scratch_words(fast5r.PLANT_STATES + fast5r.MAX_MOTORS)


def test_the_simulator_refuses_with_one_record_and_its_message():
    """A refused step is one kernels.Refused (and a PlantError): variable, value, unit and time
    of the record are those its message names; the state is kept."""
    sim, _ = _plant()
    with pytest.raises(PlantError) as refused:
        sim.step(0.0, math.inf, DT)
    assert isinstance(refused.value, kernels.Refused)
    assert refused.value.record() | {"message": None} == {
        "instance": None, "time": 0.0, "variable": "tau2", "value": math.inf, "unit": "N m",
        "code": fast5r.NONFINITE_INPUT, "reason": "nonfinite_input", "message": None}
    with pytest.raises(PlantError) as refused:
        for _ in range(5000):
            y = sim.y
            sim.step(0.05, 0.0, DT)
    record = refused.value.record()
    assert record["variable"] in MEASURES and record["code"] == fast5r.SINGULAR
    assert f"{record['variable']} measure {record['value']:.3g}" in record["message"]
    assert abs(record["value"]) < SINGULAR_STOP
    assert f"at t = {record['time']:.6g} s" in record["message"] and record["time"] == pytest.approx(sim.time + DT)
    assert sim.y is y


def test_the_terms_function_is_the_inverse_terms():
    """pc_fivebar_terms_of (the position law's terms function, fmus/cosim/compiled_adapters.py) reads its model
    as the parameter buffer and fills the inverse terms (held to the general algorithm in
    tests/controller/test_controller_fast.py): argument order and layout."""
    sim, kernel = _plant()
    q, dq = sim.y[:7].copy(), sim.y[7:].copy() + 0.3
    expected, got = np.empty(fast5r.INVERSE_SIZE), np.full(fast5r.INVERSE_SIZE, np.nan)
    fast5r.inverse_terms(kernel.p, q, dq, expected)
    terms_of = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)(
        fast5r.TERMS_OF)
    terms_of(kernels.address(kernel.p), kernels.address(q), kernels.address(dq), kernels.address(got))
    assert np.array_equal(got, expected) and np.any(expected[fast5r.INVERSE_V:fast5r.INVERSE_V + 2] != 0.0)


def _actuated_lugre():
    """The bench plant with both drives inside, LuGre friction, prepared for DT steps, moving
    (joint speeds and bristle deflections non-zero, so the bristle torque matters)."""
    from motor import Drive, get_motor_preset
    from plant.actuated import ActuatedPlant

    sim = PlantSimulator(get_preset("bench"), -0.002, 0.108, IntegratorSettings())
    sim.y = sim.y.copy()
    sim.y[7:14] = [0.01, -0.02, 0.0, 0.4, -0.3, -0.5, 0.2]   # off the loop's velocity constraint: no matter here
    drives = [(j, Drive(get_motor_preset(f"motor{j}"), friction="lugre")) for j in (1, 2)]
    for n, (_, d) in enumerate(drives):
        d.prepare_step(DT)
        d.i, d.z = 0.3 - 0.5 * n, 1e-4 * (1 - 2 * n)
    return ActuatedPlant(sim, drives)


_ACTUATED_X = [0.5, 0.45, 0.0, -0.4, -0.35, 0.0]   # i_ref1, i_hat1, v_ref1, i_ref2, i_hat2, v_ref2


def test_pc_actuated_io_is_the_actuated_plants_step():
    """One step of pc_actuated_io, and of the in-process ActuatedPlant.step (one
    pc_actuated_step), equals the same kernels composed step by step in Python (each drive's
    sample_voltage, then ActuatedPlant.advance: the bristles, the plant's RK4, the drives kept):
    state, currents, voltages, bristles and the torques minus the bristles'.  Catches a wrong
    input order, bristle sign, the bristle torque at the wrong speed, or a binding that reads
    its state or inputs from the wrong place."""
    from plant.actuated import kernel_context

    a, b, c = _actuated_lugre(), _actuated_lugre(), _actuated_lugre()
    state = a.state()
    context = kernel_context(a, state, 6)
    x = np.array(_ACTUATED_X + [0.0] * 17)
    refusal = kernels.Refusal()
    assert kernels.library().pc_actuated_io(ctypes.c_void_p(ctypes.addressof(context)),
                                            ctypes.c_void_p(kernels.address(x)), ctypes.c_double(0.0),
                                            ctypes.c_double(DT), ctypes.byref(refusal)) == 0
    voltages = [d.sample_voltage(_ACTUATED_X[3 * n], _ACTUATED_X[3 * n + 2], _ACTUATED_X[3 * n + 1], DT)
                for n, (_, d) in enumerate(b.drives)]
    b.advance(voltages, DT)
    assert c._one_call
    c.step(_ACTUATED_X[0::3], _ACTUATED_X[1::3], _ACTUATED_X[2::3], DT)
    assert np.array_equal(state, b.state()) and np.array_equal(c.state(), b.state())
    for one in (a, c):
        for (_, da), (_, db) in zip(one.drives, b.drives):
            assert np.array_equal(da.buf, db.buf) and np.array_equal(da._controller_buf, db._controller_buf)
            assert np.array_equal(da.lugre, db.lugre) and da.z != 0.0
    assert c.plant.time == b.plant.time == DT and c.plant.outputs() == b.plant.outputs()
    assert x[6 + 11:6 + 13].tolist() == b.shaft_torques() == c.shaft_torques()
    assert x[6 + 13:].tolist() == [d.v for _, d in b.drives] + b.currents


@pytest.mark.parametrize("where", ["i_ref2", "state"])
def test_pc_actuated_io_refuses_and_changes_nothing(where):
    """A non-finite i_ref2 (the second drive's sample, after the first peeked) or a non-finite
    current in z (the plant's step, after both drives peeked and the bristles advanced) is
    refused with its code and value; the state, both drives' buffers, the bristles and x's
    outputs stay as they were (a drive or bristle kept before the plant accepted would show)."""
    from motor import kernel as drive_kernel
    from plant.actuated import kernel_context

    a = _actuated_lugre()
    state = a.state()
    context = kernel_context(a, state, 6)
    x = np.array(_ACTUATED_X + [7.0] * 17)
    if where == "i_ref2":
        x[3] = math.nan
    else:
        state[15] = math.inf
    buffers = [state] + [b for _, d in a.drives for b in (d.buf, d._controller_buf, d.lugre)]
    before, x_before = [b.copy() for b in buffers], x.copy()
    refusal = kernels.Refusal()
    status = kernels.library().pc_actuated_io(ctypes.c_void_p(ctypes.addressof(context)),
                                              ctypes.c_void_p(kernels.address(x)), ctypes.c_double(0.0),
                                              ctypes.c_double(DT), ctypes.byref(refusal))
    if where == "i_ref2":   # the drive's inputs: omega, i_ref, v_ref, i_hat
        assert (status, refusal.code, refusal.index) == (drive_kernel.NONFINITE_INPUT,) * 2 + (1,)
    else:                   # the currents, which the step couples, are checked first
        assert (status, refusal.code) == (fast5r.NONFINITE_STATE,) * 2 and refusal.index in (14, 15)
    assert not math.isfinite(refusal.value)
    assert all(np.array_equal(b, b0, equal_nan=True) for b, b0 in zip(buffers, before))
    assert np.array_equal(x, x_before, equal_nan=True)


def test_encoder_counts_are_pythons_floor_bit_for_bit_on_both_sides_of_zero():
    """Catches an inline floor (pc_floor) that truncates towards zero for negative angles, takes
    one off a whole number (the ties, where the argument is whole) or breaks beyond 2^52: the
    report's encoder readings are ``count * math.floor((q + offset) / count + 0.5)`` to the bit,
    the sign of a zero reading included (the argument is never -0 here: x + 0.5 is +0 at -0.5)."""
    p = fast5r.pack_params(get_preset("bench"))
    count = 2.0 * math.pi / 4096.0
    y = np.zeros(fast5r.PLANT_STATES)
    out = np.zeros(fast5r.REPORT_SIZE)
    enc = fast5r.REPORT_OUTPUTS + 8
    angles = [0.0, -0.0, 0.25 * count, -0.25 * count, 0.5 * count, -0.5 * count, 1.5 * count, -1.5 * count,
              3.0 * count, -3.0 * count, 2.5 * count, -2.5 * count, 1e-300, -1e-300, 0.7, -0.7, 3.1, -3.1,
              1e17, -1e17]
    for q in angles:
        for offset in (0.0, 0.3 * count, -0.5 * count):
            y[3], y[5] = q, math.pi - q                       # q1 = theta11, q2 = pi - theta21
            fast5r.report(p, y, count, offset, offset, out)
            want = count * math.floor((q + offset) / count + 0.5)
            q2 = math.pi - y[5]
            want2 = count * math.floor((q2 + offset) / count + 0.5)
            assert (out[enc], math.copysign(1.0, out[enc])) == (want, math.copysign(1.0, want)), (q, offset)
            assert (out[enc + 1], math.copysign(1.0, out[enc + 1])) == (want2, math.copysign(1.0, want2)), (q, offset)
