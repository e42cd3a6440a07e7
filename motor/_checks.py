"""Input checks shared by the motor modules (one readable :class:`BadValue` each)."""

import math


class BadValue(ValueError):
    """A refused value, as fields: the message is formatted from them, so a caller that knows
    the value by another name (an FMU variable) renames it without parsing text.

    Parameters
    ----------
    name : str
        The value's name, as the refusing code knows it.
    value : object
        The refused value.
    template : str
        The message: a :meth:`str.format` template of ``name``, ``value`` and, for a rule
        that relates two values, ``other`` and ``other_value``.
    other : str, optional
        The name of the value the rule compares with.
    other_value : object, optional
        Its value.
    """

    def __init__(self, name, value, template, other=None, other_value=None):
        self.name, self.value, self.template = name, value, template
        self.other, self.other_value = other, other_value
        super().__init__(template.format(name=name, value=value, other=other, other_value=other_value))

    def renamed(self, names, prefix=""):
        """The same refusal with each name ``n`` called ``names.get(n, n)``, its message
        after the plain text ``prefix`` (e.g. ``"parameter "``)."""
        template = prefix.replace("{", "{{").replace("}", "}}") + self.template
        return BadValue(names.get(self.name, self.name), self.value, template,
                        names.get(self.other, self.other), self.other_value)


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
    BadValue
        ``"<name> must be a finite number, got <value>"``.
    """
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise BadValue(name, value, "{name} must be a finite number, got {value!r}") from None
    if not math.isfinite(x):
        raise BadValue(name, value, "{name} must be a finite number, got {value!r}")
    return x


def positive(name, value):
    """Return ``value`` as a float if it is finite and > 0, else raise :class:`BadValue`."""
    x = finite(name, value)
    if x <= 0.0:
        raise BadValue(name, value, "{name} must be > 0, got {value!r}")
    return x


def non_negative(name, value):
    """Return ``value`` as a float if it is finite and >= 0, else raise :class:`BadValue`."""
    x = finite(name, value)
    if x < 0.0:
        raise BadValue(name, value, "{name} must be >= 0, got {value!r}")
    return x


def choice(name, value, options):
    """Return ``value`` if it is one of ``options``, else raise :class:`BadValue` listing them."""
    if value not in options:
        raise BadValue(name, value, f"{{name}} must be one of {', '.join(map(repr, options))}; got {{value!r}}")
    return value


def count(name, value, limit=2 ** 31):
    """Return ``value`` as an int if it is a whole number in [0, limit), else raise :class:`BadValue`."""
    try:
        n = int(value)
    except (TypeError, ValueError, OverflowError):
        raise BadValue(name, value, "{name} must be a whole number >= 0, got {value!r}") from None
    if n != value or isinstance(value, bool) or not 0 <= n < limit:
        raise BadValue(name, value, f"{{name}} must be a whole number in [0, {limit}), got {{value!r}}")
    return n
