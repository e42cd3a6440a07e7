"""Tables 3-8 and 15-18 of the thesis (seed 003), as printed, against our presets.

Every number below is copied from the thesis' text (7.1.5.1, 7.2.7, 7.2.10, appendix D),
not from our code.  Where a preset differs from the printed value, the test asserts the
documented relation instead:

* Tables 16/18 print the viscous coefficient b in "Ns"; (D.10) b ω + μ = k_t i and (D.14)
  "b = 0.000122595 Nms/rad" make it N m s/rad: the same number, the unit label is wrong.
* Table 16's R and k_e are (D.4)-(D.5), which solve the Gram system (D.3) as printed; (D.3)
  is the least-squares system of Table 15 with u_1 = 1.52 V, not the 1.524 V of the table
  (the least squares on 1.524 gives R = 1.1031 Ω).
* Motor 1's J = 1.469e-4 kg m² does not follow from (D.15)-(D.16) with the printed settling
  time 0.207 s (1.4316e-4, 2.6 % lower); motor 2's does (0.198 s → 1.8885e-4 vs 1.887e-4).
"""
import math
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest

from controller.position import PositionController
from controller.strategies import STRATEGY_NAMES, get_strategy
from motor import identification
from motor.presets import get_motor_preset
from plant import get_preset

# --- Table 3 (7.1.5.1): the simulated mechanism, both chains equal ------------------------
TABLE_3 = dict(l0=0.050, l1=0.120, l2=0.150, lg1=0.060, lg2=0.075, m0=0.000, m1=0.143, m2=0.171,
               Jz1=1.716e-4, Jz2=3.206e-4)
# --- Tables 4 and 5 (7.2.7): the bench's chains ------------------------------------------
TABLE_4 = dict(l0=0.050, l1=0.120, l2=0.160, lg1=0.060, lg2=0.078, m1=0.062, m2=0.124,
               Jz1=1.073e-4, Jz2=4.380e-4)
TABLE_5 = dict(l0=0.050, l1=0.120, l2=0.160, lg1=0.060, lg2=0.058, m1=0.062, m2=0.097,
               Jz1=2.960e-4, Jz2=9.800e-4)
# --- Tables 6-8 (7.2.10): lambda, m*, phi, k1, k2; None where the table prints "-" --------
TABLE_6 = {"PDq": (35, 3.58e-3, None, None, None), "PDMDq": (35, 3.58e-3, 20, 200, 200),
           "TCq": (60, None, None, None, None), "TCMDq": (60, None, 20, 363, 363)}
TABLE_7 = {"PDq": (25, 3.58e-3, None, None, None), "PDMDq": (25, 3.58e-3, 90, 200, 200),
           "TCq": (60, None, None, None, None), "TCMDq": (60, None, 20, 363, 363)}
TABLE_8 = {"PDx": (70, 0.207, None, None, None), "PDMDx": (70, 0.207, 6, 70, 0),
           "TCx": (60, None, None, None, None), "TCMDx": (60, None, 6, 103, 0)}
# --- Tables 15 and 17 (appendix D): u (V), i (A), omega (rad/s) in steady state ----------
TABLE_15 = [(1.524, 0.79, 12.272), (2.52, 0.84, 31.390), (3.51, 0.89, 49.755), (4.6, 0.94, 68.079),
            (5.49, 0.98, 86.322), (6.51, 1.02, 105.736), (7.49, 1.05, 123.683), (8.5, 1.09, 140.924),
            (9.49, 1.11, 161.111)]
TABLE_17 = [(1.49, 0.92, 13.696), (2.48, 0.99, 31.747), (3.47, 1.06, 49.909), (4.47, 1.14, 67.889),
            (5.46, 1.20, 86.067), (6.47, 1.27, 104.681), (7.47, 1.32, 122.742), (8.48, 1.37, 140.553)]
# --- Tables 16 and 18: R (Ω), L (H), b (printed "Ns"), kt (N m/A), mu (N m), ke (V s/rad), J (kg m²)
TABLE_16 = dict(R=1.101, L=0.667e-3, b=1.226e-4, kt=5.598e-2, mu=4.357e-2, ke=5.138e-2, J=1.469e-4)
TABLE_18 = dict(R=0.829, L=0.667e-3, b=2.039e-4, kt=5.666e-2, mu=4.992e-2, ke=5.200e-2, J=1.887e-4)
#: (D.7)-(D.8): the datasheet's k't and k'e, and the settling times of D.15 (motor 1, 2).
KT_DATASHEET, KE_DATASHEET = 0.0467188, 0.0428786
SETTLING = {"motor1": 0.207, "motor2": 0.198}


def _chain_dict(params, chain):
    c = getattr(params, chain)
    return dict(l0=params.l0, l1=c.l1, l2=c.l2, lg1=c.lg1, lg2=c.lg2, m1=c.m1, m2=c.m2, Jz1=c.Jz1, Jz2=c.Jz2)


def test_thesis_sim_is_table_3():
    """Catches the simulation preset drifting from Table 3 or given motor inertia (the thesis' simulation
    has no motors)."""
    p = get_preset("thesis_sim")
    for chain in ("chain1", "chain2"):
        assert _chain_dict(p, chain) == {k: v for k, v in TABLE_3.items() if k != "m0"}
        assert getattr(p, chain).J_rotor == 0.0       # 7.1.5: the simulation has no motors
    assert p.m0 == TABLE_3["m0"]


def test_bench_is_tables_4_and_5_with_the_rotors_of_16_and_18():
    """Catches the bench preset's links drifting from Tables 4-5, an end-effector mass, or rotors not those
    of Tables 16 and 18."""
    p = get_preset("bench")
    assert _chain_dict(p, "chain1") == TABLE_4
    assert _chain_dict(p, "chain2") == TABLE_5
    assert p.m0 == 0.0                                 # 7.2.7: "A massa do efetuador é considerada nula"
    assert (p.chain1.J_rotor, p.chain2.J_rotor) == (TABLE_16["J"], TABLE_18["J"])


@pytest.mark.parametrize("table, trajectory", [(TABLE_6, "circle"), (TABLE_7, "triangle"), (TABLE_8, "circle"),
                                               (TABLE_8, "triangle")])
def test_strategies_are_tables_6_to_8(table, trajectory):
    """'-' in the tables: no m* (TC: Ĥ, ĥ from the model) or no sliding term (k = 0)."""
    for name, (lam, m_star, phi, k1, k2) in table.items():
        st = get_strategy(name, trajectory)
        assert st.lam == lam
        assert st.model_based == (m_star is None)
        if m_star is not None:
            assert st.m_star == m_star
        assert st.k == ((0.0, 0.0) if k1 is None else (k1, k2))
        if phi is not None:
            assert st.phi == phi
        assert st.space == name[-1]


def test_the_eight_strategies_of_7_2():
    """Catches a strategy added to or missing from Tables 6 and 8 (section 7.2's eight)."""
    assert sorted(STRATEGY_NAMES) == sorted([*TABLE_6, *TABLE_8])


@pytest.mark.parametrize("name", ["PDq", "TCMDx"])
def test_gains_are_critically_damped_7_29_7_30(name):
    """Catches controller gains that are not kp = lambda^2, kv = 2 lambda (an under- or over-damped error
    dynamics)."""
    ctrl = PositionController(get_preset("bench"), get_strategy(name), model="exact")
    lam = get_strategy(name).lam
    assert (ctrl.kp, ctrl.kv) == (lam ** 2, 2 * lam)


@pytest.mark.parametrize("motor, table", [("motor1", TABLE_16), ("motor2", TABLE_18)])
def test_motor_presets_are_tables_16_and_18(motor, table):
    """b: the printed number in N m s/rad ((D.14) prints the unit; the table's 'Ns' is a slip)."""
    m = get_motor_preset(motor)
    assert (m.R, m.L, m.kt, m.mu, m.ke, m.J_rotor, m.b) == (
        table["R"], table["L"], table["kt"], table["mu"], table["ke"], table["J"], table["b"])


@pytest.mark.parametrize("motor, table", [("motor1", TABLE_15), ("motor2", TABLE_17)])
def test_shipped_measurements_are_tables_15_and_17(motor, table):
    """Catches the shipped motor data drifting from Tables 15 and 17 (the identification's input)."""
    u, i, omega = identification.read_motor_csv(Path(identification.__file__).parent / "data" / f"{motor}.csv")
    assert np.column_stack([u, i, omega]).tolist() == [list(r) for r in table]


def _rounds_to(value, printed):
    """value rounds to printed at printed's last digit (0.829: 3 decimals; 5.598e-2: 5)."""
    half_unit = 0.5 * 10.0 ** Decimal(repr(printed)).as_tuple().exponent
    return abs(value - printed) <= half_unit * (1 + 1e-9)


def _appendix_d(table, u1=None):
    """(D.1)-(D.14) by plain least squares: R, ke, kt, mu, b."""
    u, i, w = np.array(table, dtype=float).T
    if u1 is not None:
        u[0] = u1
    (ke, R), *_ = np.linalg.lstsq(np.column_stack([w, i]), u, rcond=None)       # (D.1)-(D.2)
    kt = KT_DATASHEET / KE_DATASHEET * ke                                       # (D.6)
    (mu, b), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(w), w]), kt * i, rcond=None)   # (D.10)
    return dict(R=R, ke=ke, kt=kt, mu=mu, b=b)


def _inertia(p, R, L, kt, ke, b):
    """(D.16): (L p + R)(J p + b) + kt ke = 0 solved for J."""
    return (-kt * ke / (L * p + R) - b) / p


def test_table_16_is_appendix_d_on_table_15_with_u1_as_in_d3():
    """(D.3) prints the Gram matrix of Table 15; its right-hand side 5400.99 is <ω, u> with
    u1 = 1.52 V (with 1.524 V it would be 5401.04).  With that u1 the least squares gives
    (D.4) R = 1.10098, (D.5) ke = 0.0513822, (D.9) kt = 0.055984, (D.13) mu = 0.0435651,
    (D.14) b = 0.000122595, and Table 16 rounds them to 4 digits."""
    u, i, w = np.array(TABLE_15).T
    assert w @ w == pytest.approx(87991.6, abs=0.05) and w @ i == pytest.approx(799.092, abs=5e-4)
    assert w @ u == pytest.approx(5401.04, abs=0.005)                  # the table's 1.524 V
    assert (w @ u) - 0.004 * w[0] == pytest.approx(5400.99, abs=0.005)  # (D.3) with 1.52 V
    d = _appendix_d(TABLE_15, u1=1.52)
    for key, printed, digits in (("R", 1.10098, 6), ("ke", 0.0513822, 6), ("kt", 0.055984, 5),
                                 ("mu", 0.0435651, 6), ("b", 0.000122595, 6)):
        assert float(f"{d[key]:.{digits}g}") == printed
        assert _rounds_to(d[key], TABLE_16[key])
    J_207 = _inertia(-4 / SETTLING["motor1"], d["R"], TABLE_16["L"], d["kt"], d["ke"], d["b"])
    assert J_207 == pytest.approx(1.4316e-4, rel=1e-4)                  # not Table 16's 1.469e-4
    assert TABLE_16["J"] / J_207 == pytest.approx(1.026, abs=1e-3)


def test_table_18_is_appendix_d_on_table_17():
    """Motor 2 follows from Table 17 and t = 0.198 s without correction (4 printed digits;
    J 1.8885e-4 against 1.887e-4: 0.08 %, the printed L's 3 digits move J by more)."""
    d = _appendix_d(TABLE_17)
    for key in ("R", "ke", "kt", "mu", "b"):
        assert _rounds_to(d[key], TABLE_18[key]), key
    J = _inertia(-4 / SETTLING["motor2"], d["R"], TABLE_18["L"], d["kt"], d["ke"], d["b"])
    assert J == pytest.approx(TABLE_18["J"], rel=1e-3)


def test_torque_constants_follow_d6():
    """kt = k't / k'e · ke (D.6) for both motors, to the 4 printed digits."""
    for table in (TABLE_16, TABLE_18):
        assert table["kt"] == pytest.approx(KT_DATASHEET / KE_DATASHEET * table["ke"], rel=5e-4)
    assert math.isclose(KT_DATASHEET / KE_DATASHEET * 0.0513822, 0.055984, rel_tol=1e-5)   # (D.9)
