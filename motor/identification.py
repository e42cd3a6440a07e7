"""Motor parameter identification from steady-state data (thesis appendix D).

Steady state of the armature circuit (B.1 with di/dt = 0), linear in (ke, R)::

    u = R i + ke omega                                   (D.1)

solved by least squares through its normal equations (D.2). kt follows from
the datasheet ratio kt'/ke' (D.6). The mechanical steady state (B.2 with
d omega/dt = 0, omega > 0), linear in (mu, b)::

    b omega + mu = kt i                                  (D.10)

is solved by least squares the same way (D.11). Finally the settling time
t_98% = 4 / sigma of the speed step response (D.15) gives the dominant pole
p = -sigma, and J follows from the characteristic equation of (B.10)::

    (L p + R)(J p + b) + kt ke = 0                       (D.16)

which is linear in J: J = -(b + kt ke / (L p + R)) / p.
"""

import csv

import numpy as np

from motor import _checks

#: Datasheet constants k't = 0.0467188 N m/A (D.7) and k'e = 0.0428786 V s/rad (D.8).
DATASHEET_KT = 0.0467188
DATASHEET_KE = 0.0428786
#: Ratio kt'/ke' used in (D.6) for both thesis motors.
DATASHEET_KT_OVER_KE = DATASHEET_KT / DATASHEET_KE
#: Inductance measured with a multimeter (Tables 16, 18) [H].
MEASURED_L = 0.667e-3
#: Settling times read from the speed step responses (figures 108, 109) [s].
THESIS_SETTLING_TIMES = {"motor1": 0.207, "motor2": 0.198}


def _as_data(u, i, omega):
    """Validate the (u, i, omega) columns and return them as float arrays."""
    cols = {}
    for name, x in (("u", u), ("i", i), ("omega", omega)):
        try:
            a = np.asarray(x, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a sequence of numbers, got {x!r}") from None
        if a.ndim != 1:
            raise ValueError(f"{name} must be one-dimensional, got shape {a.shape}")
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise ValueError(f"{name}[{bad[0]}] must be a finite number, got {float(a[bad[0]])!r}")
        cols[name] = a
    n = {k: len(v) for k, v in cols.items()}
    if len(set(n.values())) != 1:
        raise ValueError(f"u, i and omega must have the same length, got {n}")
    if n["u"] < 2:
        raise ValueError(f"need at least 2 data points, got {n['u']}")
    nonpositive = np.flatnonzero(cols["omega"] <= 0)
    if nonpositive.size:
        k = nonpositive[0]
        raise ValueError(f"omega[{k}] must be > 0 (D.10 holds for omega > 0), "
                         f"got {float(cols['omega'][k])!r}")
    return cols["u"], cols["i"], cols["omega"]


def normal_equations_electrical(u, i, omega):
    """Normal equations (D.2) for x = (ke, R) of u = R i + ke omega (D.1).

    Returns
    -------
    G : numpy.ndarray, shape (2, 2)
        [[<omega, omega>, <omega, i>], [<omega, i>, <i, i>]].
    rhs : numpy.ndarray, shape (2,)
        [<omega, u>, <i, u>].
    """
    A = np.column_stack([omega, i])
    return A.T @ A, A.T @ u


def normal_equations_friction(i, omega, kt):
    """Normal equations (D.11) for x = (mu, b) of b omega + mu = kt i (D.10).

    Returns
    -------
    G : numpy.ndarray, shape (2, 2)
        [[<1, 1>, <omega, 1>], [<omega, 1>, <omega, omega>]].
    rhs : numpy.ndarray, shape (2,)
        [<1, kt i>, <omega, kt i>].
    """
    A = np.column_stack([np.ones_like(omega), omega])
    return A.T @ A, A.T @ (kt * i)


def _solve(G, rhs, what):
    if np.linalg.cond(G) > 1e12:
        raise ValueError(f"data do not determine {what}: the normal equations are singular "
                         f"(need at least two distinct operating points)")
    return np.linalg.solve(G, rhs)


def pole_from_settling_time(settling_time):
    """Dominant real pole p = -4 / t_98% [rad/s] (D.15)."""
    return -4.0 / _checks.positive("settling_time", settling_time)


def inertia_from_pole(p, R, L, kt, ke, b):
    """Rotor inertia J solving (L p + R)(J p + b) + kt ke = 0 (D.16).

    Raises
    ------
    ValueError
        If L p + R = 0 or the resulting J is not positive (settling time
        inconsistent with the other parameters).
    """
    lp_r = L * p + R
    if lp_r == 0.0:
        raise ValueError(f"L p + R = 0 for p={p!r}: J undetermined")
    J = -(b + kt * ke / lp_r) / p
    if not J > 0.0:
        raise ValueError(f"settling time gives a non-positive inertia J={J!r} (pole p={p!r})")
    return J


def identify(u, i, omega, kt_over_ke=DATASHEET_KT_OVER_KE, settling_time=None, L=MEASURED_L):
    """Identify R, ke, kt, mu, b (and J) from steady-state data (appendix D).

    Parameters
    ----------
    u, i, omega : array_like
        Steady-state voltage [V], current [A] and speed [rad/s], omega > 0.
    kt_over_ke : float
        Datasheet ratio kt'/ke' for (D.6); default the thesis value
        0.0467188 / 0.0428786 (D.7, D.8).
    settling_time : float, optional
        t_98% [s] of the speed step response (D.15); if given, J is returned.
    L : float
        Armature inductance [H] for (D.16) (measured separately in the thesis).

    Returns
    -------
    dict
        ``R`` [ohm], ``ke`` [V s/rad] (D.2), ``kt`` [N m/A] (D.6), ``mu`` [N m],
        ``b`` [N m s/rad] (D.11), ``rms_u`` [V] and ``rms_torque`` [N m]
        (residuals of D.1 and D.10), ``n``, ``kt_over_ke``; with a
        settling time also ``L``, ``settling_time``, ``pole`` [rad/s] (D.15)
        and ``J`` [kg m^2] (D.16).

    Raises
    ------
    ValueError
        Naming the offending input (NaN, unequal lengths, omega <= 0, too few
        or degenerate points, non-positive ratio or settling time).
    """
    u, i, omega = _as_data(u, i, omega)
    ratio = _checks.positive("kt_over_ke", kt_over_ke)
    ke, R = _solve(*normal_equations_electrical(u, i, omega), "R and ke")
    kt = ratio * ke                                                   # (D.6)
    mu, b = _solve(*normal_equations_friction(i, omega, kt), "mu and b")
    result = {
        "R": float(R), "ke": float(ke), "kt": float(kt), "mu": float(mu), "b": float(b),
        "rms_u": float(np.sqrt(np.mean((u - R * i - ke * omega) ** 2))),
        "rms_torque": float(np.sqrt(np.mean((kt * i - mu - b * omega) ** 2))),
        "n": len(u), "kt_over_ke": ratio,
    }
    if settling_time is not None:
        L = _checks.non_negative("L", L)
        p = pole_from_settling_time(settling_time)
        result.update(L=L, settling_time=float(settling_time), pole=float(p),
                      J=float(inertia_from_pole(p, R, L, kt, ke, b)))
    return result


def read_motor_csv(path):
    """Read a CSV with a header naming columns ``u``, ``i``, ``omega`` (others ignored).

    Returns
    -------
    tuple of numpy.ndarray
        (u, i, omega).

    Raises
    ------
    ValueError
        Unreadable file, missing column, empty data or a non-numeric cell
        (with its line number).
    """
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"cannot read {path}: {exc}") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise ValueError(f"{path}: empty file, expected a header with columns u,i,omega")
    header = [c.strip() for c in rows[0]]
    missing = [c for c in ("u", "i", "omega") if c not in header]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}; header is {','.join(header)}")
    if len(rows) < 2:
        raise ValueError(f"{path}: no data rows")
    index = [header.index(c) for c in ("u", "i", "omega")]
    data = []
    for line, row in enumerate(rows[1:], start=2):
        try:
            data.append([float(row[k]) for k in index])
        except (IndexError, ValueError):
            raise ValueError(f"{path}: line {line}: expected numbers in columns u,i,omega, "
                             f"got {','.join(row)}") from None
    u, i, omega = np.array(data).T
    return u, i, omega
