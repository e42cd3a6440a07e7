"""Input checks shared by the motor modules (one readable ValueError each)."""

import math


def finite(name, value):
    """Return ``value`` as a float, or raise if it is not a finite number.

    Parameters
    ----------
    name : str
        Variable name quoted in the error message.
    value : object
        Value to check.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        ``"<name> must be a finite number, got <value>"``.
    """
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return x


def positive(name, value):
    """Return ``value`` as a float if it is finite and > 0, else raise ValueError."""
    x = finite(name, value)
    if x <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return x


def non_negative(name, value):
    """Return ``value`` as a float if it is finite and >= 0, else raise ValueError."""
    x = finite(name, value)
    if x < 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return x


def choice(name, value, options):
    """Return ``value`` if it is one of ``options``, else raise ValueError listing them."""
    if value not in options:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, options))}; got {value!r}")
    return value


def count(name, value, limit=2 ** 31):
    """Return ``value`` as an int if it is a whole number in [0, limit), else raise ValueError."""
    try:
        n = int(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a whole number >= 0, got {value!r}") from None
    if n != value or isinstance(value, bool) or not 0 <= n < limit:
        raise ValueError(f"{name} must be a whole number in [0, {limit}), got {value!r}")
    return n
