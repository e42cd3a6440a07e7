"""Linear stability limits of the bench twin's joint loops, rigid or with a drive-link spring.

    python benchmarks/twin_linear_margin.py [--inertia-error E] [--freqs 200 250 300 400 500]
    python benchmarks/twin_linear_margin.py --path [--inertia-error E] [--delays 1 2 3 4 6]
    python benchmarks/twin_linear_margin.py --identify [--inertia-error 0]

At the circle's start point (where the thesis, 7.2.12, places the TC laws' λ limit), each
strategy family's loop linearised about rest: the plant's joint-space inertia (Tables 4-5,
links times 1 + E, the rotors of Tables 16 and 18), torque held over each 1 ms sample and
applied one sample late (the twin's delay), the derivator's velocity chain (backward
difference (7.19) and the 100 Hz Bessel low-pass, controller.derivators), and the law
τ = G (λ² e + 2λ ė) with G = m* (PDq), M̂ = Jᵀ Λ̂ J (TCq, TCx: the controller's model) or
Jᵀ m*ₓ J (PDx).  Friction, quantisation and the sliding-mode terms are left out.  It prints
the smallest λ whose closed loop has a pole on or outside the unit circle, rigid and with a
spring of natural frequency f between each rotor and its link (encoder on the rotor, damping
ratio ζ), beside the bench's limits (λ of Tables 6-8 plus 5 rad/s), and each family's
velocity gain kv/J = 2 (λ+5) G / J at the bench's limit.  ``--path``: the smallest rigid limit
along each trajectory, with extra delays.  ``--identify``: the end-effector mass and velocity
cut-off whose start-point limits best match the bench's edges (docs/twin.md: tried as a twin, rejected by the circle).
Figures: docs/twin.md.
"""
from __future__ import annotations

import argparse
import math
from dataclasses import replace

import numpy as np
from scipy.linalg import expm

from controller.derivators import Derivator, _differentiator_ss
from controller.kinematics import Kinematics
from controller.model import ExactModel
from controller.strategies import get_strategy
from controller.trajectories import get_trajectory
from plant import get_preset
from scenarios.scenes.twin import LINK_INERTIAS

T = 1e-3


def joint_inertia(params, x, y, J):
    """Jᵀ Λ J: the joint-space inertia at (x, y) at rest (Λ from the inverse dynamics (5.74))."""
    H00, H01, H11, *_ = ExactModel(params).terms(x, y, 0.0, 0.0)
    return J.T @ np.array([[H00, H01], [H01, H11]]) @ J


def scaled_links(params, inertia_error: float):
    """``params`` without rotors, its links' masses and inertias times 1 + ``inertia_error``."""
    links = params.with_rotors(0.0, 0.0)
    return replace(links, **{c: replace(getattr(links, c), **{f: getattr(getattr(links, c), f) * (1 + inertia_error)
                                                               for f in LINK_INERTIAS}) for c in ("chain1", "chain2")})


def rotor_inertias(params):
    """The rotors of Tables 16 and 18 as a diagonal matrix [kg m²]."""
    return np.diag([params.chain1.J_rotor, params.chain2.J_rotor])


def velocity_chain(fc_vel: float | None = None):
    """The derivator's velocity chain ((7.19) and the Bessel low-pass) as a state-space model,
    at cut-off ``fc_vel`` [Hz] (default: the derivator's)."""
    return _differentiator_ss((Derivator() if fc_vel is None else Derivator(fc_vel=fc_vel)).velocity_sos, T)


def loop_at(params, links, x, y):
    """(the real joint inertia of the links, {family: (G, λ of Tables 6-8)}) at (x, y)."""
    kin = Kinematics(params)
    angles = kin.inverse(x, y)
    J = np.array(kin.jacobian(x, y, angles[0], angles[2])).reshape(2, 2)
    families = {"PDq": (get_strategy("PDq").m_star * np.eye(2), get_strategy("PDq").lam),
                "TCq/TCx": (joint_inertia(params, x, y, J), get_strategy("TCq").lam),
                "PDx": (J.T @ (get_strategy("PDx").m_star * np.eye(2)) @ J, get_strategy("PDx").lam)}
    return joint_inertia(links, x, y, J), families


def setup(inertia_error: float):
    params = get_preset("bench")
    x, y = get_trajectory("circle").start_point
    Ml, families = loop_at(params, scaled_links(params, inertia_error), x, y)
    Jr = rotor_inertias(params)
    return (x, y), Ml, Jr, families


def plant(Ml, Jr, k=None, zeta=0.0):
    """ZOH discretisation (Ad, Bd) and the rotor-angle output Cm; rigid if k is None."""
    Z, I = np.zeros((2, 2)), np.eye(2)
    if k is None:
        A = np.block([[Z, I], [Z, Z]])
        B = np.vstack([Z, np.linalg.inv(Ml + Jr)])
        Cm = np.hstack([I, Z])
    else:
        reduced = np.diag(Jr) * np.diag(Ml) / (np.diag(Jr) + np.diag(Ml))
        K, C = k * I, np.diag(2 * zeta * np.sqrt(k * reduced))
        iJ, iM = np.linalg.inv(Jr), np.linalg.inv(Ml)
        A = np.block([[Z, Z, I, Z], [Z, Z, Z, I], [-iJ @ K, iJ @ K, -iJ @ C, iJ @ C],
                      [iM @ K, -iM @ K, iM @ C, -iM @ C]])
        B = np.vstack([Z, Z, iJ, Z])
        Cm = np.hstack([I, Z, Z, Z])
    n = A.shape[0]
    big = expm(np.block([[A, B], [np.zeros((2, n + 2))]]) * T)
    return big[:n, :n], big[:n, n:], Cm


def spectral_radius(Ad, Bd, Cm, G, lam, derivator):
    """Closed loop on the state [plant, derivator, pending command]."""
    va, vb, vc, vd = (np.kron(np.eye(2), m) for m in derivator)
    n, nv = Ad.shape[0], va.shape[0]
    M = np.zeros((n + nv + 2, n + nv + 2))
    M[:n, :n], M[:n, n + nv:] = Ad, Bd
    M[n:n + nv, :n], M[n:n + nv, n:n + nv] = vb @ Cm, va
    M[n + nv:, :n] = -G @ (lam ** 2 * Cm + 2 * lam * vd @ Cm)
    M[n + nv:, n:n + nv] = -G @ (2 * lam * vc)
    return max(abs(np.linalg.eigvals(M)))


def lambda_limit(Ad, Bd, Cm, G, derivator, lams=np.arange(5.0, 400.0, 1.0)):
    """The smallest λ of ``lams`` with a closed-loop pole on or outside the unit circle."""
    for lam in lams:
        if spectral_radius(Ad, Bd, Cm, G, lam, derivator) >= 1.0:
            return float(lam)
    return math.inf


def delayed(Ad, Bd, Cm, delay: int):
    """The plant with its input ``delay`` samples late in all (the twin's 1 is in the loop
    already: ``delay - 1`` more held samples, a shift register on the state)."""
    extra = 2 * (delay - 1)
    if extra <= 0:
        return Ad, Bd, Cm
    n = Ad.shape[0]
    A = np.zeros((n + extra, n + extra))
    A[:n, :n], A[:n, n + extra - 2:] = Ad, Bd
    for i in range(delay - 2):
        A[n + 2 * (i + 1):n + 2 * (i + 2), n + 2 * i:n + 2 * (i + 1)] = np.eye(2)
    B = np.zeros((n + extra, 2))
    B[n:n + 2] = np.eye(2)
    return A, B, np.hstack([Cm, np.zeros((2, extra))])


def path_limits(kind: str, inertia_error: float, delay: int = 1, points: int = 24, fc_vel: float | None = None):
    """{family: (smallest rigid λ limit over ``points`` points of trajectory ``kind``, where)}
    with ``delay`` samples of computation delay in all and the derivator's velocity cut-off
    ``fc_vel`` [Hz] (default: the derivator's)."""
    params = get_preset("bench")
    links = scaled_links(params, inertia_error)
    Jr = rotor_inertias(params)
    derivator = velocity_chain(fc_vel)
    trajectory = get_trajectory(kind)
    best = {}
    for t in np.linspace(0.0, trajectory.duration, points, endpoint=False):
        x, y = trajectory(t).x, trajectory(t).y
        Ml, families = loop_at(params, links, x, y)
        system = delayed(*plant(Ml, Jr), delay)
        for name, (G, _lam) in families.items():
            limit = lambda_limit(*system, G, derivator)
            if name not in best or limit < best[name][0]:
                best[name] = (limit, (round(float(x), 3), round(float(y), 3)))
    return best


#: The bench's edges (7.2.12: λ of Tables 6 and 8 plus 5 rad/s compromised stability).
BENCH_EDGES = {"PDq": 40.0, "TCq/TCx": 65.0, "PDx": 75.0}


def start_limits(inertia_error: float, m0: float, fc_vel: float, delay: int = 1) -> dict:
    """{family: rigid λ limit at the circle's start} for links (1 + ``inertia_error``) times
    Tables 4-5, an effector mass ``m0`` [kg] and the derivator's velocity cut-off ``fc_vel`` [Hz]."""
    params = get_preset("bench")
    x, y = get_trajectory("circle").start_point
    Ml, families = loop_at(params, replace(scaled_links(params, inertia_error), m0=m0), x, y)
    Jr = rotor_inertias(params)
    system = delayed(*plant(Ml, Jr), delay)
    derivator = velocity_chain(fc_vel)
    return {name: lambda_limit(*system, G, derivator) for name, (G, _lam) in families.items()}


def identify_edges(inertia_error: float = 0.0, masses=np.arange(0.20, 0.501, 0.05),
                   cutoffs=np.arange(9.0, 16.01, 1.0)) -> list:
    """[(misfit, m0, fc_vel, limits)] over the grid, best first: misfit is the RMS log-ratio of
    :func:`start_limits` to :data:`BENCH_EDGES` (the effector mass sets PDx's edge against the
    others', the velocity filter's lag sets their level)."""
    rows = []
    for m0 in masses:
        for fc in cutoffs:
            limits = start_limits(inertia_error, float(m0), float(fc))
            misfit = math.sqrt(np.mean([math.log(limits[n] / BENCH_EDGES[n]) ** 2 for n in BENCH_EDGES]))
            rows.append((misfit, round(float(m0), 3), float(fc), limits))
    return sorted(rows, key=lambda row: row[0])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--inertia-error", type=float, default=0.6376, help="links / Tables 4-5 - 1 (the fit's)")
    parser.add_argument("--freqs", type=float, nargs="+", default=[200, 250, 300, 400, 500, 1000])
    parser.add_argument("--zeta", type=float, nargs="+", default=[0.02, 0.1])
    parser.add_argument("--path", action="store_true",
                        help="rigid limits along the circle and the triangle (smallest over the path), "
                             "for each --delays, instead of the springs at the start point")
    parser.add_argument("--delays", type=int, nargs="+", default=[1], help="computation delays [samples] (--path)")
    parser.add_argument("--identify", action="store_true",
                        help="the effector mass and velocity cut-off whose start-point limits best match the "
                             "bench's edges (PDq 40, TC 65, PDx 75), at --inertia-error")
    args = parser.parse_args(argv)
    if args.identify:
        for misfit, m0, fc, limits in identify_edges(args.inertia_error)[:8]:
            print(f"m0 {m0:.2f} kg, fc_vel {fc:g} Hz: misfit {misfit:.4f}, limits {limits}")
        return 0
    if args.path:
        for kind in ("circle", "triangle"):
            for delay in args.delays:
                limits = path_limits(kind, args.inertia_error, delay)
                print(f"{kind}, inertia_error {args.inertia_error:g}, delay {delay}: " +
                      ", ".join(f"{n} {lim:g} at {where}" for n, (lim, where) in limits.items()))
        print("bench: circle PDq 40, TC 65, PDx 75 (λ of Tables 6, 8 + 5); triangle PDq < 30 (Table 7: 25)")
        return 0
    point, Ml, Jr, families = setup(args.inertia_error)
    derivator = velocity_chain()
    print(f"start point {point}, real joint inertia diag {np.diag(Ml + Jr).round(5)}")
    for name, (G, lam) in families.items():
        kv = 2 * (lam + 5) * np.diag(G) / np.diag(Ml + Jr)
        print(f"{name}: G diag {np.diag(G).round(5)}, bench limit λ {lam + 5:g}, kv/J there {kv.round(1)} rad/s")
    rigid = plant(Ml, Jr)
    print("rigid:", {n: lambda_limit(*rigid, G, derivator) for n, (G, _) in families.items()})
    for zeta in args.zeta:
        for f in args.freqs:
            k = (2 * math.pi * f) ** 2 / (1 / Jr[0, 0] + 1 / Ml[0, 0])
            system = plant(Ml, Jr, k, zeta)
            print(f"spring {f:g} Hz (k {k:.0f} N m/rad), zeta {zeta:g}:",
                  {n: lambda_limit(*system, G, derivator) for n, (G, _) in families.items()})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
