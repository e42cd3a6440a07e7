"""motor/identification.py's refusals at their edges (issue 31, training sweep s44: compare
mutants at identification.py:56, :95 and :199).

Appendix D identifies two pairs of unknowns by least squares, so two operating points are the
fewest that determine them (exactly, with zero residual); a CSV of a header and one data row
is one point (read, then refused by ``identify``), a header alone is no data.  The normal
equations are refused as singular when their condition number exceeds 1e12.
"""
from __future__ import annotations

import numpy as np
import pytest

from motor import identification


def test_exactly_two_operating_points_determine_r_ke_mu_and_b_exactly():
    """u = R i + ke omega (D.1) and kt i = mu + b omega (D.10) through two points: the values
    chosen here come back (two equations, two unknowns each), with zero residuals."""
    R, ke, ratio, mu, b = 1.3, 0.04, 1.1, 0.02, 1e-4
    kt = ratio * ke
    omega = np.array([100.0, 250.0])
    i = (mu + b * omega) / kt
    u = R * i + ke * omega
    got = identification.identify(u, i, omega, kt_over_ke=ratio)
    assert got["n"] == 2
    for name, value in (("R", R), ("ke", ke), ("kt", kt), ("mu", mu), ("b", b)):
        assert got[name] == pytest.approx(value, rel=1e-9), name
    assert got["rms_u"] == pytest.approx(0.0, abs=1e-12) and got["rms_torque"] == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ValueError, match=r"^need at least 2 data points, got 1$"):
        identification.identify(u[:1], i[:1], omega[:1], kt_over_ke=ratio)


def test_a_csv_with_one_data_row_is_read_and_one_with_a_header_only_is_refused(tmp_path):
    """One data row under the header is data (the row's numbers, read back exactly); the header
    alone is refused naming the file and saying there are no data rows."""
    one = tmp_path / "one.csv"
    one.write_text("u,i,omega\n12.5,0.75,280.0\n")
    u, i, omega = identification.read_motor_csv(one)
    assert (u.tolist(), i.tolist(), omega.tolist()) == ([12.5], [0.75], [280.0])
    header = tmp_path / "header.csv"
    header.write_text("u,i,omega\n\n")
    with pytest.raises(ValueError, match=rf"^{header}: no data rows$"):
        identification.read_motor_csv(header)


def test_normal_equations_of_condition_exactly_1e12_are_solved_and_beyond_it_refused():
    """cond(diag(1e12, 1)) is 1e12 exactly (its singular values' ratio): solved, the exact
    solution; diag(2e12, 1) is beyond the bound: refused naming what the data do not determine."""
    G = np.diag([1e12, 1.0])
    assert np.linalg.cond(G) == 1e12
    np.testing.assert_array_equal(identification._solve(G, np.array([2e12, 3.0]), "x"), [2.0, 3.0])
    with pytest.raises(ValueError, match=r"^data do not determine x: the normal equations are singular"):
        identification._solve(np.diag([2e12, 1.0]), np.array([1.0, 1.0]), "x")
