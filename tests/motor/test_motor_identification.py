"""Motor identification (appendix D) on the thesis data (Tables 15, 17) and synthetic data."""

import json
import math

import numpy as np
import pytest

from motor import (DATASHEET_KT_OVER_KE, THESIS_SETTLING_TIMES, current_transfer_function, identify,
                   inertia_from_pole, motor1, motor2, normal_equations_electrical,
                   normal_equations_friction, read_motor_csv)
from motor.cli import identify_main
from tests.support.paths import ROOT

DATA = ROOT / "motor" / "data"


def thesis_data(name):
    return read_motor_csv(DATA / f"{name}.csv")


@pytest.mark.parametrize("name, n", [("motor1", 9), ("motor2", 8)])
def test_identification_is_the_exact_least_squares_fit(name, n):
    """Catches an identification that is not the least-squares fit of appendix D (or reads rpm for rad/s)."""
    u, i, omega = thesis_data(name)
    assert len(u) == n and omega.min() > 10 and omega.max() < 170   # rad/s, not rpm
    r = identify(u, i, omega)
    ke, R = np.linalg.lstsq(np.column_stack([omega, i]), u, rcond=None)[0]
    kt = DATASHEET_KT_OVER_KE * ke
    mu, b = np.linalg.lstsq(np.column_stack([np.ones(n), omega]), kt * i, rcond=None)[0]
    np.testing.assert_allclose([r["R"], r["ke"], r["kt"], r["mu"], r["b"]], [R, ke, kt, mu, b], rtol=1e-10)
    assert r["rms_u"] == pytest.approx(np.sqrt(np.mean((u - R * i - ke * omega) ** 2)), rel=1e-9)


def test_thesis_normal_equations_use_u1_1_52_not_1_524():
    """(D.3) as printed is the Gram system of Table 15 with u1 = 1.52 V, not the 1.524 V
    printed in the table; with 1.52 the thesis numbers D.3-D.5, D.9, D.12-D.14 all follow."""
    u, i, omega = thesis_data("motor1")
    G, rhs = normal_equations_electrical(u, i, omega)
    np.testing.assert_allclose(G, [[87991.6, 799.092], [799.092, 8.5289]], rtol=1e-6)
    assert rhs[0] == pytest.approx(5401.04, abs=0.005)       # printed: 5400.99
    assert rhs[1] == pytest.approx(50.4525, abs=5e-5)        # printed: 50.4493
    u = u.copy()
    u[0] = 1.52
    G, rhs = normal_equations_electrical(u, i, omega)
    np.testing.assert_allclose(rhs, [5400.99, 50.4493], rtol=1e-6)
    r = identify(u, i, omega)
    assert r["R"] == pytest.approx(1.10098, abs=5e-6)          # (D.4)
    assert r["ke"] == pytest.approx(0.0513822, abs=5e-8)       # (D.5)
    assert r["kt"] == pytest.approx(0.055984, abs=5e-7)        # (D.9)
    G, rhs = normal_equations_friction(i, omega, r["kt"])
    np.testing.assert_allclose(G, [[9, 779.272], [779.272, 87991.6]], rtol=1e-6)
    np.testing.assert_allclose(rhs, [0.487621, 44.7364], rtol=2e-6)
    assert r["mu"] == pytest.approx(0.0435651, abs=5e-8)       # (D.13)
    assert r["b"] == pytest.approx(0.000122595, abs=5e-10)     # (D.14)


def test_comparison_with_tables_16_and_18():
    """Shipped data vs the tables; differences documented in docs/motor_identification.md."""
    r1 = identify(*thesis_data("motor1"), settling_time=THESIS_SETTLING_TIMES["motor1"])
    r2 = identify(*thesis_data("motor2"), settling_time=THESIS_SETTLING_TIMES["motor2"])
    for r, m, rtol in ((r1, motor1, 2.5e-3), (r2, motor2, 5e-4)):
        for k in ("R", "ke", "kt", "mu", "b"):
            assert r[k] == pytest.approx(getattr(m, k), rel=rtol), k
    assert r2["J"] == pytest.approx(motor2.J_rotor, rel=1e-3)
    # Motor 1's J of Table 16 does not follow from D.15-D.16 with t = 0.207 s: 2.8 % lower here
    # (2.5 % lower even with the thesis' own R, ke, kt, b); Table 16 needs t_98 ~ 0.2125 s.
    assert r1["J"] == pytest.approx(1.428e-4, rel=1e-3)
    j_thesis = inertia_from_pole(-4 / 0.207, 1.10098, 0.667e-3, 0.055984, 0.0513822, 0.000122595)
    assert j_thesis == pytest.approx(1.4316e-4, rel=1e-4)
    assert inertia_from_pole(-4 / 0.2125, 1.10098, 0.667e-3, 0.055984, 0.0513822,
                             0.000122595) == pytest.approx(motor1.J_rotor, rel=2e-3)


def test_recovers_known_parameters_from_noisy_synthetic_data():
    """Catches an identification that misses known R, ke, kt, mu, b, J exactly, or is not robust to small noise."""
    true = motor2.with_(R=0.95, ke=0.048, kt=0.048 * DATASHEET_KT_OVER_KE, mu=0.03, b=3e-4, J_rotor=2.5e-4)
    rng = np.random.default_rng(7)
    omega = np.linspace(10.0, 200.0, 60)
    i = (true.b * omega + true.mu) / true.kt
    u = true.R * i + true.ke * omega
    slow = max(np.roots(np.squeeze(current_transfer_function(true).den[0][0])).real)
    t98 = 4.0 / -slow
    exact = identify(u, i, omega, settling_time=t98, L=true.L)
    for k in ("R", "ke", "kt", "mu", "b"):
        assert exact[k] == pytest.approx(getattr(true, k), rel=1e-9)
    assert exact["J"] == pytest.approx(true.J_rotor, rel=1e-9)
    noisy = identify(u + rng.normal(0, 0.01, u.size), i + rng.normal(0, 0.002, i.size),
                     omega + rng.normal(0, 0.2, omega.size), settling_time=t98, L=true.L)
    for k, rtol in (("R", 0.02), ("ke", 0.005), ("kt", 0.005), ("mu", 0.05), ("b", 0.05), ("J", 0.02)):
        assert noisy[k] == pytest.approx(exact[k], rel=rtol), k


@pytest.mark.parametrize("kwargs, message", [
    (dict(u=[1, math.nan, math.inf], i=[1, 1, 1], omega=[1, 2, 3]), r"u\[1\] must be a finite number, got nan"),
    (dict(u=[1, 2, 3], i=[1, 1], omega=[1, 2, 3]), "same length"),
    (dict(u=[1, 2, 3], i=[1, 1, 1], omega=[1, 0, 3]), r"omega\[1\] must be > 0"),
    (dict(u=[1, 2, 3], i=[1, 1, 1], omega=[1, 2, -3]), r"omega\[2\] must be > 0"),    # (D.3): speeds > 0
    (dict(u=[1, 1, 1], i=[1, 1, 1], omega=[2, 2, 2]), "normal equations are singular"),
    (dict(u=[1, 2], i=[1, 1.1], omega=[1, 2], kt_over_ke=-1), "kt_over_ke must be > 0, got -1"),
    (dict(u=[1, 2], i=[1, 1.1], omega=[1, 2], settling_time=0), "settling_time must be > 0, got 0"),
])
def test_bad_identification_input(kwargs, message):
    """Catches identification input checks that are missing or whose message does not say what is wrong."""
    with pytest.raises(ValueError, match=message):
        identify(**kwargs)


def test_csv_any_column_order_and_errors(tmp_path):
    """Catches a CSV reader that depends on column order, or misses a missing column or a bad number's line."""
    good = tmp_path / "m.csv"
    good.write_text("omega,note,u,i\n10,a,1.0,0.5\n20,b,2.0,0.6\n")
    u, i, omega = read_motor_csv(good)
    np.testing.assert_array_equal([u, i, omega], [[1.0, 2.0], [0.5, 0.6], [10, 20]])
    (tmp_path / "missing.csv").write_text("u,omega\n1,2\n")
    with pytest.raises(ValueError, match="missing column.*i"):
        read_motor_csv(tmp_path / "missing.csv")
    (tmp_path / "text.csv").write_text("u,i,omega\n1,2,3\n1,x,3\n")
    with pytest.raises(ValueError, match="line 3"):
        read_motor_csv(tmp_path / "text.csv")


def test_cli_prints_json(capsys):
    """Catches an identify-motor command whose JSON differs from identify() on the same data."""
    assert identify_main(["--data", str(DATA / "motor2.csv"), "--settling-time", "0.198"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out == identify(*thesis_data("motor2"), settling_time=0.198)


@pytest.mark.parametrize("argv", [["--data", "does-not-exist.csv"], ["--data", "{bad}"],
                                  [], ["--data", "{data}", "--kt-over-ke", "abc"]])
def test_cli_errors_one_line_exit_2(argv, capsys, tmp_path):
    """Catches an identify-motor error that is a traceback, more than one line, or an exit code other than 2."""
    bad = tmp_path / "bad.csv"
    bad.write_text("voltage,current\n1,2\n")
    argv = [a.format(bad=bad, data=DATA / "motor1.csv") for a in argv]
    assert identify_main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("parcosim identify-motor: error: ") and err.count("\n") == 1


@pytest.mark.parametrize("name", ["motor1", "motor2"])
def test_every_returned_value_is_its_documented_quantity(name):
    """Each key identify() returns, against its appendix-D quantity computed here independently
    (numpy's least squares, the residuals of D.1 and D.10 written out, D.15, D.16 solved for J),
    with a ratio, settling time and inductance other than the defaults; no key missing, none
    extra.  Catches a residual with a term dropped (rms_torque without b omega, b without
    omega), a key filled with another quantity, and an input echoed as another."""
    u, i, omega = thesis_data(name)
    ratio, t98, L = 1.1, 0.18, 8e-4
    r = identify(u, i, omega, kt_over_ke=ratio, settling_time=t98, L=L)
    ke, R = np.linalg.lstsq(np.column_stack([omega, i]), u, rcond=None)[0]
    kt = ratio * ke
    mu, b = np.linalg.lstsq(np.column_stack([np.ones(len(u)), omega]), kt * i, rcond=None)[0]
    residual_u = [uk - R * ik - ke * wk for uk, ik, wk in zip(u, i, omega)]
    residual_torque = [kt * ik - (mu + b * wk) for ik, wk in zip(i, omega)]
    pole = -4.0 / t98
    J = -(b + kt * ke / (L * pole + R)) / pole
    assert (L * pole + R) * (J * pole + b) + kt * ke == pytest.approx(0.0, abs=1e-12)       # D.16
    expected = {"R": R, "ke": ke, "kt": kt, "mu": mu, "b": b,
                "rms_u": math.sqrt(sum(e * e for e in residual_u) / len(u)),
                "rms_torque": math.sqrt(sum(e * e for e in residual_torque) / len(u)),
                "n": len(u), "kt_over_ke": ratio, "L": L, "settling_time": t98, "pole": pole, "J": J}
    assert set(r) == set(expected)
    for key, value in expected.items():
        assert r[key] == pytest.approx(value, rel=1e-9), key
    assert r["rms_torque"] > 0.0 and r["rms_u"] > 0.0        # the thesis points are not on one line
    assert set(identify(u, i, omega)) == set(expected) - {"L", "settling_time", "pole", "J"}
