"""The coefficient of restitution r, eq. (restitution): parsing and labels.

Config gives r as a decimal (0.25) or an exact fraction string ("1/3").  The
exact value is kept as a ``Fraction`` (a decimal is read as written, so
0.3 is 3/10; a float of any precision, numpy's included, as the shortest decimal
that gives it back, so np.float32(0.1) is 1/10).  Output paths use a canonical label:
the value with 6 significant digits, trailing zeros dropped ("0.25", "0.333333").
"""

import math
import numbers
from fractions import Fraction

__all__ = [
    "EXACT_RESTITUTIONS",
    "SOLVER_RESTITUTION_RANGE",
    "DISTRIBUTION_RESTITUTION_RANGE",
    "in_range",
    "parse_restitution",
    "check_solver_range",
    "check_distribution_range",
    "restitution_value",
    "restitution_label",
    "restitution_grid",
    "shared_label_message",
    "exact_string",
]

#: The r with an exact solution, eq. (P(0,v)) (bouncing_ball.exact).
EXACT_RESTITUTIONS = (Fraction(1, 2), Fraction(1, 3))

#: The r for which the solver of eq. (inteq) (bouncing_ball.solver) meets its 1e-8 accuracy
#: target: below 0.02 P(0, v) ~ exp(-v / (2r)) leaves the range of doubles within the speeds that
#: matter (tests/unit/test_solver.py holds the solver to it); above 0.9999 the dense grid,
#: ~ (1 - r)^(-1/2) nodes, outgrows a job.  The bounds are exact decimals: 0.02 is 1/50.
SOLVER_RESTITUTION_RANGE = (0.02, 0.9999)
#: The r for which the whole distribution from P(0, v) (bouncing_ball.distribution: w(F), P(x),
#: P(x, v)) meets the same target, and so every table of rule solve: the r of a run.  Above,
#: int P dx and the moments of P(x) miss their Ito values by more than 1e-8: w(F) is taken on the
#: ray arg v = RAY_ANGLE of bouncing_ball.distribution, along which the integrand of A(F) is
#: largest at v = 0 only for q >= q(0.999).
DISTRIBUTION_RESTITUTION_RANGE = (0.02, 0.999)


def in_range(exact, bounds) -> bool:
    """Whether an exact r lies in a range whose bounds are decimals read as written.

    ``low <= exact <= high`` in exact arithmetic (so that r = 1/50 is inside a range that
    starts at 0.02, whose float is a little above 1/50).

    Parameters
    ----------
    exact : fractions.Fraction or int
        The exact r.
    bounds : tuple of float
        (low, high), such as ``SOLVER_RESTITUTION_RANGE``; each read as its decimal string.

    Returns
    -------
    bool

    Examples
    --------
    >>> from fractions import Fraction
    >>> from bouncing_ball.restitution import in_range
    >>> print(in_range(Fraction(1, 50), (0.02, 0.9)), Fraction(0.02) > Fraction(1, 50))
    True True
    >>> in_range(Fraction(91, 100), (0.02, 0.9))
    False
    """
    low, high = (Fraction(str(bound)) for bound in bounds)
    return low <= Fraction(exact) <= high


def parse_restitution(value, where: str = "restitution") -> Fraction:
    """The exact value of r, eq. (restitution), from a config entry or a label.

    A decimal is read as written (0.3 is 3/10, not the binary float nearest 0.3).  A float
    of any precision (Python's, numpy's float16/32/64 and longdouble) is read the same way, as
    the shortest decimal that gives it back at its own precision: np.float32(0.1) is 1/10, as
    0.1 is, not the float32 nearest 0.1 (1/10 + 1.5e-9).  A whole number (Python's or
    numpy's) is itself.

    Parameters
    ----------
    value : float, int, str or fractions.Fraction
        r as a decimal (0.25; a numpy float or integer scalar too), a fraction string
        ("1/3") or a ``Fraction``.  Not a bool, a complex number, NaN or an infinity.
    where : str, optional
        What ``value`` is (a config key, an argument), named in errors.

    Returns
    -------
    fractions.Fraction
        r, 0 < r < 1.

    Raises
    ------
    ValueError
        If ``value`` is not a finite real number, not in (0, 1), or has a label
        (``restitution_label``) outside (0, 1); the message names ``where``.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.restitution import parse_restitution
    >>> parse_restitution(0.3), parse_restitution("1/3"), parse_restitution(np.float32(0.1))
    (Fraction(3, 10), Fraction(1, 3), Fraction(1, 10))
    >>> parse_restitution(1.5, "r")
    Traceback (most recent call last):
    ...
    ValueError: r: r = 1.5 is outside the allowed range 0 < r < 1
    """
    exact = _exact_number(value, where)
    if not 0 < exact < 1:
        raise ValueError(f"{where}: r = {value!r} is outside the allowed range 0 < r < 1")
    label = restitution_label(exact)
    if not 0 < float(label) < 1:
        raise ValueError(
            f"{where}: r = {value!r} rounds to {label} at the 6 significant digits of the "
            "labels its outputs are filed under, which is not an r in (0, 1); give an r whose "
            + ("label stays below 1 (at most 0.9999994)" if exact > 0.5 else "label is not 0")
        )
    return exact


def _exact_number(value, where: str) -> Fraction:
    """``value`` as a Fraction, as ``parse_restitution`` reads it (no range check)."""
    advice = 'give a decimal such as 0.25 or a fraction such as "1/3"'
    if isinstance(value, Fraction):
        return value
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return Fraction(int(value))  # numpy's integers too
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise ValueError(f"{where}: {value!r} is not a finite number; {advice}")
        return Fraction(str(value))  # the shortest decimal of the float at its own precision
    if not isinstance(value, str):  # bool, numpy.bool_, complex, None, a list, ...
        raise ValueError(f"{where}: {value!r} is not a number; {advice}")
    try:
        return Fraction(value.strip())
    except ZeroDivisionError:
        raise ValueError(f"{where}: {value!r} divides by zero; r must lie in (0, 1)") from None
    except ValueError:
        raise ValueError(f"{where}: {value!r} is not a number; {advice}") from None


def _range_text(bounds) -> str:
    low, high = bounds
    return f"{low} <= r <= {high}"


def check_solver_range(value, where: str = "restitution") -> Fraction:
    """r parsed (``parse_restitution``), if it lies in the solver's range of r.

    The solver's range, ``SOLVER_RESTITUTION_RANGE``, is where P(0, v) of eq. (inteq), the time
    averages, the flight times and the bounce chain's relaxation meet the 1e-8 accuracy target
    (``bouncing_ball.solver``).  The one check of it: every entry point that solves eq. (inteq)
    calls it.

    Parameters
    ----------
    value : float, int, str or fractions.Fraction
        r as a decimal, a fraction string or a ``Fraction``.
    where : str, optional
        What ``value`` is, named in errors.

    Returns
    -------
    fractions.Fraction
        r.

    Raises
    ------
    ValueError
        If ``value`` is not an r (``parse_restitution``), or lies outside
        ``SOLVER_RESTITUTION_RANGE``; the message names ``where``, "the solver's range of r" and
        its bounds either way.

    Examples
    --------
    >>> from bouncing_ball.restitution import check_solver_range
    >>> check_solver_range("1/50")
    Fraction(1, 50)
    >>> check_solver_range(0.99995, "r")
    Traceback (most recent call last):
    ...
    ValueError: r: r = 0.99995 is outside the solver's range of r, 0.02 <= r <= 0.9999, ...
    """
    try:
        exact = parse_restitution(value, where)
    except ValueError as error:
        raise ValueError(
            f"{error}; the solver's range of r is {_range_text(SOLVER_RESTITUTION_RANGE)}"
        ) from None
    if not in_range(exact, SOLVER_RESTITUTION_RANGE):
        why = (
            "below it P(0, v) ~ exp(-v / (2r)) leaves the range of doubles"
            if exact < Fraction(str(SOLVER_RESTITUTION_RANGE[0]))
            else "above it the solver's dense grid of ~(1 - r)^(-1/2) nodes outgrows a job"
        )
        raise ValueError(
            f"{where}: r = {value!r} is outside the solver's range of r, "
            f"{_range_text(SOLVER_RESTITUTION_RANGE)}, where P(0, v) of eq. (inteq) meets its "
            f"1e-8 accuracy target (restitution.SOLVER_RESTITUTION_RANGE): {why}"
        )
    return exact


def check_distribution_range(value, where: str = "restitution") -> Fraction:
    """r parsed (``parse_restitution``), if it lies in the range of r where P(x, v) is verified.

    That range, ``DISTRIBUTION_RESTITUTION_RANGE``, is where the whole distribution from
    P(0, v) (w(F), P(x), <v^2>_x, P(x, v): ``bouncing_ball.distribution``) meets the 1e-8
    accuracy target, and so every table of rule solve: the r of a run.  The one check of it:
    every entry point that builds w(F) calls it.

    Parameters
    ----------
    value : float, int, str or fractions.Fraction
        r as a decimal, a fraction string or a ``Fraction``.
    where : str, optional
        What ``value`` is, named in errors.

    Returns
    -------
    fractions.Fraction
        r.

    Raises
    ------
    ValueError
        If ``value`` is not an r (``parse_restitution``), or lies outside
        ``DISTRIBUTION_RESTITUTION_RANGE``; the message names ``where``, "the range of r where
        P(x, v) is verified", its bounds and the solver's range of r (P(0, v) alone).

    Examples
    --------
    >>> from bouncing_ball.restitution import check_distribution_range
    >>> check_distribution_range("1/2")
    Fraction(1, 2)
    >>> check_distribution_range(0.9995, "r")
    Traceback (most recent call last):
    ...
    ValueError: r: r = 0.9995 is outside the range of r where P(x, v) is verified, ...
    """
    try:
        exact = parse_restitution(value, where)
    except ValueError as error:
        raise ValueError(
            f"{error}; the range of r where P(x, v) is verified is "
            f"{_range_text(DISTRIBUTION_RESTITUTION_RANGE)}"
        ) from None
    if not in_range(exact, DISTRIBUTION_RESTITUTION_RANGE):
        raise ValueError(
            f"{where}: r = {value!r} is outside the range of r where P(x, v) is verified, "
            f"{_range_text(DISTRIBUTION_RESTITUTION_RANGE)}, where w(F), P(x) and P(x, v) meet "
            "the 1e-8 accuracy target (restitution.DISTRIBUTION_RESTITUTION_RANGE, "
            "docs/distribution.md#where-it-degrades); P(0, v) alone is solved over the solver's "
            f"range of r, {_range_text(SOLVER_RESTITUTION_RANGE)}"
        )
    return exact


def restitution_value(value, where: str = "restitution") -> float:
    """r as a float, read as the pipeline reads it (``parse_restitution``).

    The library's public entry points take r so.

    Parameters
    ----------
    value : float, int, str or fractions.Fraction
        r as a decimal, a fraction string ("1/3") or a ``Fraction``.
    where : str, optional
        What ``value`` is, named in errors.

    Returns
    -------
    float
        r, 0 < r < 1.

    Raises
    ------
    ValueError
        As ``parse_restitution``.

    Examples
    --------
    >>> from bouncing_ball.restitution import restitution_value
    >>> restitution_value("1/4")
    0.25
    """
    return float(parse_restitution(value, where))


def restitution_label(value) -> str:
    """The canonical label of r that outputs are filed under.

    Parameters
    ----------
    value : float or fractions.Fraction
        r.

    Returns
    -------
    str
        r to 6 significant digits, trailing zeros dropped.

    Examples
    --------
    >>> from fractions import Fraction
    >>> from bouncing_ball.restitution import restitution_label
    >>> restitution_label(Fraction(1, 3)), restitution_label(0.250)
    ('0.333333', '0.25')
    """
    return f"{float(value):.6g}"


def restitution_grid(values, where: str = "restitution") -> dict[str, Fraction]:
    """Parse the config list of r values into {label: exact value}.

    Refuses an empty list and repeated values (also 0.5 together with "1/2",
    or two values that share a label).

    Parameters
    ----------
    values : list or tuple
        The r, each as ``parse_restitution`` takes it.
    where : str, optional
        The config key of the list, named in errors (with the index of the entry).

    Returns
    -------
    dict of str to fractions.Fraction
        Each r's label (``restitution_label``) and exact value, in the order given.

    Raises
    ------
    ValueError
        If the list is empty or not a list, an entry is not an r, or two entries are equal
        or share a label.

    Examples
    --------
    >>> from bouncing_ball.restitution import restitution_grid
    >>> restitution_grid([0.25, "1/3"])
    {'0.25': Fraction(1, 4), '0.333333': Fraction(1, 3)}
    >>> restitution_grid([0.5, "1/2"], "r")
    Traceback (most recent call last):
    ...
    ValueError: r[1]: r = '1/2' repeats r = 1/2 (label 0.5); each r may appear once
    """
    if not isinstance(values, (list, tuple)) or len(values) == 0:
        raise ValueError(f"{where}: give a non-empty list of r values in (0, 1), got {values!r}")
    grid: dict[str, Fraction] = {}
    for index, value in enumerate(values):
        exact = parse_restitution(value, f"{where}[{index}]")
        label = restitution_label(exact)
        if label in grid and grid[label] == exact:
            raise ValueError(
                f"{where}[{index}]: r = {value!r} repeats r = {grid[label]} (label {label}); "
                "each r may appear once"
            )
        if label in grid:
            raise ValueError(shared_label_message(f"{where}[{index}]", exact, grid[label]))
        grid[label] = exact
    return grid


def shared_label_message(where: str, value: Fraction, other: Fraction) -> str:
    """Why two different r cannot both be asked for: their outputs would share a folder.

    Parameters
    ----------
    where : str
        The config entry that asks for ``value``.
    value, other : fractions.Fraction
        Two different r with the same label (``restitution_label``).

    Returns
    -------
    str
        The error message.

    Examples
    --------
    >>> from fractions import Fraction
    >>> from bouncing_ball.restitution import shared_label_message
    >>> print(shared_label_message("r[1]", Fraction(1, 3), Fraction(333333, 1000000)))
    r[1]: r = 1/3 and r = 333333/1000000 share the label 0.333333 (6 significant digits)
    under which outputs are filed; keep one of them
    """
    return (
        f"{where}: r = {value} and r = {other} share the label {restitution_label(value)} "
        "(6 significant digits) under which outputs are filed; keep one of them"
    )


def exact_string(value: Fraction) -> str:
    """The exact value as a string that ``parse_restitution`` reads back.

    Parameters
    ----------
    value : fractions.Fraction
        r.

    Returns
    -------
    str
        "p/q" ("1/3", "1/4").

    Examples
    --------
    >>> from fractions import Fraction
    >>> from bouncing_ball.restitution import exact_string, parse_restitution
    >>> exact_string(Fraction(1, 3)), parse_restitution(exact_string(Fraction(1, 3)))
    ('1/3', Fraction(1, 3))
    """
    return str(value)
