"""A MuJoCo model generated from a mechanism spec (:mod:`plant.spec`): an independent
formulation of the same mechanism, to check the thesis' algorithm (plant/serial.py,
plant/parallel.py) on spatial mechanisms.

MuJoCo shares no code and no formulation with plant/: it integrates the bodies' Newton-
Euler dynamics in its own generalised coordinates, with the loop closures as ``connect``
equality constraints (soft, made nearly hard as in :mod:`benchmarks.mujoco_5r`).

Each DH row (4.1) ``[1]^H_{B_{i-1}|B_i} = Rz(theta + q) Tz(d + q) Tx(a) Rx(alpha)`` becomes
a body whose frame is B_{i-1} moved by the joint (a hinge or slide along its z), carrying
link i's inertial and, as a child, the next body at ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``.
The platform is a body with three slide joints, listed first, so that MuJoCo's qpos is
the thesis' q = [q_0, q_1, ..., q_n] (5.5).

Run ``python benchmarks/mujoco_spec.py [SPEC]`` for the comparison of docs/spec.md.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks.mujoco_5r import CLOSURE_SOLIMP, CLOSURE_SOLREF, _number, _numbers  # noqa: E402
from plant import spec as plant_spec  # noqa: E402
from plant.serial import PRISMATIC, dh_transform  # noqa: E402

#: Mass and inertia MuJoCo gives a massless body (it refuses moving bodies without mass):
#: small against every link of the shipped specs.
MIN_INERTIAL = 1e-12


def _quat(R) -> np.ndarray:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return q


def _body(name, T, inner, joint):
    return (f'<body name="{name}" pos="{_numbers(T[:3, 3])}" quat="{_numbers(_quat(T[:3, :3]))}">'
            f"{joint}{inner}</body>")


def _inertial(link, T):
    """Link i's inertial in its body's frame (B_{i-1} moved by the joint); T = that frame -> B_i."""
    R = T[:3, :3]
    com = R @ np.asarray(link.com) + T[:3, 3]
    inertia = R @ np.asarray(link.inertia) @ R.T
    mass = max(link.mass, MIN_INERTIAL)
    inertia = inertia + MIN_INERTIAL * np.eye(3)
    full = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]]
    return f'<inertial pos="{_numbers(com)}" mass="{_number(mass)}" fullinertia="{_numbers(full)}"/>'


def mjcf_from_spec(spec, timestep=1e-3, integrator="RK4", solref=CLOSURE_SOLREF, solimp=CLOSURE_SOLIMP) -> str:
    """The MJCF of a parallel spec; actuators named by the spec's inputs, sites ``tip<i>``
    on each chain's last body and ``attach<i>`` on the platform."""
    if not spec.is_parallel:
        raise ValueError("only parallel specs (with a [platform]) are generated")
    chains = []
    for i, c in enumerate(spec.chains):
        fixed = [dh_transform(joint, 0.0) for joint in c.chain.joints]   # B_{j-1} moved by q_j -> B_j
        inner = f'<site name="tip{i}" pos="{_numbers(fixed[-1][:3, 3])}"/>'
        for j in range(c.chain.dof - 1, -1, -1):     # innermost body first
            joint, info = c.chain.joints[j], c.joints[j]
            if c.chain.rotor_inertia[j] and (j > 0 or c.chain.gear_ratio[j] != 1.0):
                raise ValueError(f"{info.name}: a rotor beyond the base joint or geared is not MuJoCo armature")
            kind = "slide" if joint.kind == PRISMATIC else "hinge"
            inner = (f'<joint name="{info.name}" type="{kind}" axis="0 0 1" '
                     f'armature="{_number(c.chain.rotor_inertia[j])}"/>{_inertial(c.chain.links[j], fixed[j])}'
                     + inner)
            if j > 0:
                inner = _body(f"{c.name}_link{j + 1}", fixed[j - 1], inner, "")
        base = np.eye(4)
        base[:3, :3], base[:3, 3] = np.asarray(c.rotation), c.base
        chains.append(_body(f"{c.name}_link1", base, inner, ""))
    platform_joints = "".join(f'<joint name="platform_{a}" type="slide" axis="{_numbers(np.eye(3)[k])}"/>'
                              for k, a in enumerate("xyz"))
    sites = "".join(f'<site name="attach{i}" pos="{_numbers(c.attach)}"/>' for i, c in enumerate(spec.chains))
    mass = max(spec.platform_mass, MIN_INERTIAL)
    platform = (f'<body name="platform">{platform_joints}<inertial pos="0 0 0" mass="{_number(mass)}" '
                f'diaginertia="1e-6 1e-6 1e-6"/>{sites}</body>')
    equality = "".join(f'<connect site1="tip{i}" site2="attach{i}" solref="{_numbers(solref)}" '
                       f'solimp="{_numbers(solimp)}"/>' for i in range(len(spec.chains)))
    actuators = "".join(f'<motor name="{info.input}" joint="{info.name}" gear="1" ctrllimited="false"/>'
                        for _, _, info in spec.joints() if info.actuated)
    return f"""<mujoco model="{spec.name}">
  <option timestep="{_number(timestep)}" integrator="{integrator}" gravity="{_numbers(spec.gravity)}"
          solver="Newton" tolerance="1e-12" iterations="50"><flag contact="disable"/></option>
  <default><joint damping="0" frictionloss="0"/></default>
  <worldbody>{platform}{"".join(chains)}</worldbody>
  <equality>{equality}</equality>
  <actuator>{actuators}</actuator>
</mujoco>
"""


def mujoco_run(spec, q0, torque_fn, t_end, timestep=1e-3):
    """Platform positions (n+1, 3) from rest at q0 (the thesis' q), torques held over each step."""
    model = mujoco.MjModel.from_xml_string(mjcf_from_spec(spec, timestep=timestep))
    data = mujoco.MjData(model)
    data.qpos[:] = q0
    mujoco.mj_forward(model, data)
    n = int(round(t_end / timestep))
    out = np.empty((n + 1, 3))
    for k in range(n + 1):
        out[k] = data.qpos[:3]
        if k < n:
            data.ctrl[:] = torque_fn(k * timestep)
            mujoco.mj_step(model, data)
    return out


def spec_run(spec, torque_fn, t_end, timestep=1e-3, settings=None):
    """The same with :class:`plant.specsim.SpecSimulator` (general algorithm)."""
    from plant import IntegratorSettings
    from plant.specsim import SpecSimulator

    sim = SpecSimulator(spec, settings=settings or IntegratorSettings(kernel="general"))
    n = int(round(t_end / timestep))
    out = np.empty((n + 1, 3))
    q0 = sim.y[:sim.y.size // 2].copy()
    for k in range(n + 1):
        out[k] = sim.y[:3]
        if k < n:
            sim.step(torque_fn(k * timestep), timestep)
    return q0, out


def holding_torques(spec, q):
    """The actuator torques that hold the mechanism at rest at q (5.74 with ddq# = 0, dq = 0)."""
    from plant.parallel import inverse_dynamics

    mech = spec.mechanism
    return inverse_dynamics(mech, q, np.zeros_like(q), np.zeros(len(mech.independent)))


def delta_torques(hold):
    """The comparison's torques: hold the start pose, plus slow sinusoids that move it by centimetres."""
    def fn(t):
        return hold + np.array([0.01 * np.sin(2 * np.pi * t), -0.008 * np.sin(3 * np.pi * t),
                                0.006 * np.cos(2 * np.pi * t) - 0.006])
    return fn


def main(name="delta3", t_end=1.0):
    spec = plant_spec.load(name)
    from plant.specsim import assemble

    q0 = assemble(spec, spec.start)
    fn = delta_torques(holding_torques(spec, q0))
    t0 = time.perf_counter()
    _, ours = spec_run(spec, fn, t_end)
    t1 = time.perf_counter()
    theirs = mujoco_run(spec, q0, fn, t_end)
    t2 = time.perf_counter()
    gap = np.linalg.norm(ours - theirs, axis=1)
    print(f"{name}, {t_end:g} s, RK4 1 ms both: max |platform difference| {gap.max():.3g} m; "
          f"platform moved {np.linalg.norm(ours[-1] - ours[0]):.3g} m (max excursion "
          f"{np.linalg.norm(ours - ours[0], axis=1).max():.3g} m); wall {t1 - t0:.1f} s (plant.specsim), "
          f"{t2 - t1:.2f} s (MuJoCo)")
    return gap.max()


if __name__ == "__main__":
    main(*sys.argv[1:2])
