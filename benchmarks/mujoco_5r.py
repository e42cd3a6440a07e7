"""MuJoCo model of the 5R parallel robot, for speed and accuracy comparisons.

The mechanism is built as two planar serial chains of hinge joints about z,
closed at the tip by a ``connect`` equality between a site on each distal
link. Bodies, parameters and world frame follow the brief ../shared/spec/SYSTEM.md and the independent
reference ``tests/support/lagrange5r.py``, whose parameter dictionaries this
module takes. MuJoCo enforces the closure as a soft constraint; the
``CLOSURE_SOLREF``/``CLOSURE_SOLIMP`` defaults were tuned against the
reference (run ``python benchmarks/mujoco_5r.py`` for the sweep).

Functions
---------
mjcf_5r(params, integrator="RK4", timestep=1e-3, solref=CLOSURE_SOLREF, solimp=CLOSURE_SOLIMP) -> str
mujoco_initial_state(params, x0, y0) -> qpos
mujoco_trajectory(params, x0, y0, tau_fn, t_end, ...) -> (t, x, y, closure_gap)
mujoco_step_time_us(params, n_steps=5000, integrator="RK4") -> float
reference_zoh_trajectory(params, x0, y0, tau_fn, t_end, timestep=1e-3) -> (t, x, y)
"""

import sys
import time
from pathlib import Path

import mujoco
import numpy as np

# Repository root on the path so that the reference model imports when run as a script.
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.support import lagrange5r as ref  # noqa: E402

#: Closure time constant and damping ratio. A time constant of 2 timesteps is
#: the stiffest MuJoCo accepts without disabling its safety clamp (stiffer
#: settings with the clamp off were less accurate, then unstable); of the
#: settings swept, (0.002, 2) gave the smallest worst-case tip error over the
#: scenes of :func:`main`.
CLOSURE_SOLREF = (0.002, 2.0)
#: Closure impedance: close to 1 makes the constraint nearly hard (0.9999 and
#: 0.999999 gave identical trajectories; 0.99 and 0.9 a worst-case tip error
#: 46 and 460 times larger).
CLOSURE_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
#: Start point and constant torques of the timing run.
TIMING_START = (0.0, 0.17)
TIMING_TORQUES = (0.03, -0.02)
#: Steps between restarts of the timing run from rest (0.2 s: the constant
#: torques would otherwise drive the robot into a singularity).
TIMING_STEPS_PER_RUN = 200


def _number(value):
    """Round-trip exact text of a number for the MJCF."""
    return f"{float(value):.17g}"


def _numbers(values):
    return " ".join(_number(v) for v in values)


def _distal_with_tip_mass(chain, tip_mass):
    """Mass, centre-of-mass distance and Jz of a distal link carrying the tip point mass.

    Folding the point mass into the link's inertial avoids a separate body,
    which MuJoCo would require to have a (fictitious) positive inertia.
    """
    mass = chain["m2"] + tip_mass
    com = (chain["m2"] * chain["lg2"] + tip_mass * chain["l2"]) / mass
    jz = (chain["Jz2"] + chain["m2"] * (chain["lg2"] - com) ** 2
          + tip_mass * (chain["l2"] - com) ** 2)
    return mass, com, jz


def mjcf_5r(params, integrator="RK4", timestep=1e-3, solref=CLOSURE_SOLREF,
            solimp=CLOSURE_SOLIMP):
    """Generate the MJCF of the 5R.

    Parameters
    ----------
    params : dict
        Robot parameters in the format of ``tests/support/lagrange5r.py``.
    integrator : str
        MuJoCo integrator ("RK4", "Euler", "implicit", "implicitfast").
    timestep : float
        Integration step [s].
    solref, solimp : sequence of float
        Softness of the tip closure (MuJoCo ``connect`` equality).

    Returns
    -------
    str
        The MJCF document. Joints, in qpos order: ``q1``, ``elbow1``, ``q2``,
        ``elbow2`` (the elbows' qpos are relative angles); actuators ``tau1``,
        ``tau2`` (motors, gear 1, unlimited); sites ``tip1``, ``tip2``.
    """
    chains = []
    for index, chain in enumerate(params["chains"]):
        number = index + 1
        base_x = params["l0"] if index == 0 else -params["l0"]
        tip_mass = params["m0"] if index == 0 else 0.0
        distal_mass, distal_com, distal_jz = _distal_with_tip_mass(chain, tip_mass)
        chains.append(f"""
    <body name="link{number}1" pos="{_number(base_x)} 0 0">
      <joint name="q{number}" armature="{_number(chain["J_rotor"])}"/>
      <inertial pos="{_number(chain["lg1"])} 0 0" mass="{_number(chain["m1"])}"
                diaginertia="{_numbers([chain["Jz1"]] * 3)}"/>
      <geom fromto="0 0 0 {_number(chain["l1"])} 0 0"/>
      <body name="link{number}2" pos="{_number(chain["l1"])} 0 0">
        <joint name="elbow{number}"/>
        <inertial pos="{_number(distal_com)} 0 0" mass="{_number(distal_mass)}"
                  diaginertia="{_numbers([distal_jz] * 3)}"/>
        <geom fromto="0 0 0 {_number(chain["l2"])} 0 0"/>
        <site name="tip{number}" pos="{_number(chain["l2"])} 0 0"/>
      </body>
    </body>""")
    return f"""<mujoco model="five_bar_5r">
  <option timestep="{_number(timestep)}" integrator="{integrator}" gravity="{_numbers(params["g"])}"
          solver="Newton" tolerance="1e-12" iterations="50">
    <flag contact="disable"/>
  </option>
  <default>
    <joint type="hinge" axis="0 0 1" damping="0" frictionloss="0"/>
    <!-- Visual only: the inertial elements carry the mass properties. -->
    <geom type="capsule" size="0.004" contype="0" conaffinity="0"/>
  </default>
  <worldbody>{"".join(chains)}
  </worldbody>
  <equality>
    <connect site1="tip1" site2="tip2" solref="{_numbers(solref)}" solimp="{_numbers(solimp)}"/>
  </equality>
  <actuator>
    <motor name="tau1" joint="q1" gear="1" ctrllimited="false"/>
    <motor name="tau2" joint="q2" gear="1" ctrllimited="false"/>
  </actuator>
</mujoco>
"""


def mujoco_initial_state(params, x0, y0):
    """qpos of the robot with its tip at (x0, y0) in the working mode.

    Parameters
    ----------
    params : dict
        Robot parameters.
    x0, y0 : float
        End-effector position [m].

    Returns
    -------
    numpy.ndarray, shape (4,)
        ``(q1, elbow1, q2, elbow2)`` with relative elbow angles [rad].
    """
    phi11, phi12, phi21, phi22 = ref.ik(params, x0, y0)
    return np.array([phi11, phi12 - phi11, phi21, phi22 - phi21])


def mujoco_trajectory(params, x0, y0, tau_fn, t_end, integrator="RK4", timestep=1e-3,
                      solref=CLOSURE_SOLREF, solimp=CLOSURE_SOLIMP):
    """Simulate the MuJoCo model from rest at (x0, y0).

    The torques are held over each step at ``tau_fn(t_k)`` (zero-order hold,
    the project's convention for a communication step).

    Parameters
    ----------
    params : dict
        Robot parameters.
    x0, y0 : float
        Initial end-effector position [m].
    tau_fn : callable
        ``tau_fn(t) -> (tau1, tau2)`` [N m].
    t_end : float
        Final time [s].
    integrator, timestep, solref, solimp
        Passed to :func:`mjcf_5r`.

    Returns
    -------
    t, x, y : numpy.ndarray, shape (n + 1,)
        Time [s] and chain 1's tip position [m] at every step, from t = 0.
    closure_gap : numpy.ndarray, shape (n + 1,)
        Distance between the two chains' tips [m] (zero for a hard closure).
    """
    model = mujoco.MjModel.from_xml_string(
        mjcf_5r(params, integrator=integrator, timestep=timestep, solref=solref, solimp=solimp))
    data = mujoco.MjData(model)
    data.qpos[:] = mujoco_initial_state(params, x0, y0)
    mujoco.mj_forward(model, data)
    tip1 = model.site("tip1").id
    tip2 = model.site("tip2").id
    n_steps = int(round(t_end / timestep))
    # k * timestep rather than MuJoCo's accumulated data.time: no round-off drift.
    t = np.arange(n_steps + 1) * timestep
    samples = np.empty((n_steps + 1, 3))
    for k in range(n_steps + 1):
        samples[k] = (*data.site_xpos[tip1, :2],
                      np.linalg.norm(data.site_xpos[tip1] - data.site_xpos[tip2]))
        if k < n_steps:
            data.ctrl[:] = tau_fn(t[k])
            mujoco.mj_step(model, data)
    return t, samples[:, 0], samples[:, 1], samples[:, 2]


def mujoco_step_time_us(params, n_steps=5000, integrator="RK4"):
    """Wall-clock time of one ``mj_step`` [µs], Python call overhead included.

    Every run starts at rest at ``TIMING_START`` with ``TIMING_TORQUES``
    applied and lasts ``TIMING_STEPS_PER_RUN`` steps; only the steps are timed.

    Parameters
    ----------
    params : dict
        Robot parameters.
    n_steps : int
        Number of steps timed.
    integrator : str
        MuJoCo integrator.

    Returns
    -------
    float
        Mean time per step [µs].
    """
    model = mujoco.MjModel.from_xml_string(mjcf_5r(params, integrator=integrator))
    data = mujoco.MjData(model)
    initial_qpos = mujoco_initial_state(params, *TIMING_START)
    elapsed = 0.0
    remaining = n_steps
    while remaining > 0:
        mujoco.mj_resetData(model, data)
        data.qpos[:] = initial_qpos
        data.ctrl[:] = TIMING_TORQUES
        run_steps = min(TIMING_STEPS_PER_RUN, remaining)
        start = time.perf_counter()
        for _ in range(run_steps):
            mujoco.mj_step(model, data)
        elapsed += time.perf_counter() - start
        remaining -= run_steps
    return elapsed / n_steps * 1e6


def reference_zoh_trajectory(params, x0, y0, tau_fn, t_end, timestep=1e-3):
    """Lagrange reference driven by the same zero-order-hold torques as MuJoCo.

    Each step is integrated separately so that the torque jumps fall on
    integration boundaries and cost no accuracy.

    Parameters
    ----------
    params : dict
        Robot parameters.
    x0, y0 : float
        Initial end-effector position [m], at rest.
    tau_fn : callable
        ``tau_fn(t) -> (tau1, tau2)`` [N m], sampled at the start of each step.
    t_end : float
        Final time [s].
    timestep : float
        Hold interval [s].

    Returns
    -------
    t, x, y : numpy.ndarray, shape (n + 1,)
        Time [s] and tip position [m] at every step, from t = 0.
    """
    phi = ref.ik(params, x0, y0)
    q = np.array([phi[0], phi[2]])
    dq = np.zeros(2)
    n_steps = int(round(t_end / timestep))
    tips = [(x0, y0)]
    for k in range(n_steps):
        held = tuple(tau_fn(k * timestep))
        _, q_run, dq_run = ref.integrate(params, q, dq, lambda t, held=held: held, timestep)
        q, dq = q_run[-1], dq_run[-1]
        tips.append(ref.tip(params, ref.full_state(params, q, dq)[0]))
    tips = np.array(tips)
    return np.arange(n_steps + 1) * timestep, tips[:, 0], tips[:, 1]


def _tip_error_and_gap(params, x0, y0, tau_fn, t_end, reference, **mujoco_options):
    """Largest MuJoCo-reference tip distance and largest closure gap over the run [m]."""
    _, x_ref, y_ref = reference
    _, x, y, gap = mujoco_trajectory(params, x0, y0, tau_fn, t_end, **mujoco_options)
    return float(np.max(np.hypot(x - x_ref, y - y_ref))), float(np.max(gap))


def main():
    """Print MuJoCo's accuracy against the reference, a closure-softness sweep and the step time."""
    presets = {"thesis_sim": ref.params_thesis_sim(), "bench": ref.params_bench()}
    scenes = [
        ("bench, constant torques", presets["bench"], 0.0, 0.17, lambda t: (0.03, -0.02)),
        ("thesis_sim, constant torques", presets["thesis_sim"], 0.07, 0.17,
         lambda t: (-0.01, 0.008)),
        ("bench, sinusoidal torques (held 1 ms)", presets["bench"], 0.0, 0.17,
         lambda t: (0.05 * np.sin(2 * np.pi * t) + 0.02, -0.03 * np.cos(3 * t))),
    ]
    t_end = 0.4
    references = [reference_zoh_trajectory(params, x0, y0, tau_fn, t_end)
                  for _, params, x0, y0, tau_fn in scenes]
    print(f"MuJoCo {mujoco.__version__}: RK4, dt = 1 ms, {t_end} s from rest, vs Lagrange reference")
    print(f"closure solref {CLOSURE_SOLREF}, solimp {CLOSURE_SOLIMP}")
    for (label, params, x0, y0, tau_fn), reference in zip(scenes, references):
        error, gap = _tip_error_and_gap(params, x0, y0, tau_fn, t_end, reference)
        print(f"  {label:40s} max tip error {error:.2e} m, max closure gap {gap:.2e} m")

    print("closure softness sweep (worst case over the scenes above):")
    for solref in [(0.02, 1.0), (0.002, 1.0), (0.002, 2.0)]:
        for impedance in (0.9, 0.99, 0.9999):
            solimp = (impedance, impedance, 0.001, 0.5, 2.0)
            results = [_tip_error_and_gap(params, x0, y0, tau_fn, t_end, reference,
                                          solref=solref, solimp=solimp)
                       for (_, params, x0, y0, tau_fn), reference in zip(scenes, references)]
            error, gap = np.max(results, axis=0)
            print(f"  solref {solref}, solimp d = {impedance}: "
                  f"max tip error {error:.2e} m, max closure gap {gap:.2e} m")

    print("time per mj_step (5000 steps, Python loop):")
    for preset, params in presets.items():
        for integrator in ("RK4", "Euler", "implicitfast"):
            print(f"  {preset:10s} {integrator:12s} "
                  f"{mujoco_step_time_us(params, integrator=integrator):6.2f} us")


if __name__ == "__main__":
    main()
