"""The coefficient of restitution r, eq. (restitution): parsing and labels.

Config gives r as a decimal (0.25) or an exact fraction string ("1/3").  The
exact value is kept as a ``Fraction`` (a decimal is read as written, so
0.3 is 3/10).  Output paths use a canonical label: the value with 6
significant digits, trailing zeros dropped ("0.25", "0.333333").
"""

from fractions import Fraction

# the r with an exact solution, eq. (P(0,v)) (bouncing_ball.exact)
EXACT_RESTITUTIONS = (Fraction(1, 2), Fraction(1, 3))


def parse_restitution(value, where: str = "restitution") -> Fraction:
    """The exact value of r from a config entry or a label; ``where`` names it in errors."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str, Fraction)):
        raise ValueError(
            f'{where}: {value!r} is not a number; give a decimal such as 0.25 or a fraction such as "1/3"'
        )
    try:
        exact = Fraction(str(value).strip()) if not isinstance(value, Fraction) else value
    except ZeroDivisionError:
        raise ValueError(f"{where}: {value!r} divides by zero; r must lie in (0, 1)") from None
    except ValueError:
        raise ValueError(
            f'{where}: {value!r} is not a number; give a decimal such as 0.25 or a fraction such as "1/3"'
        ) from None
    if not 0 < exact < 1:
        raise ValueError(f"{where}: r = {value!r} is outside the allowed range 0 < r < 1")
    return exact


def restitution_label(value) -> str:
    """Canonical label: 6 significant digits, trailing zeros dropped."""
    return f"{float(value):.6g}"


def restitution_grid(values, where: str = "restitution") -> dict[str, Fraction]:
    """Parse the config list of r values into {label: exact value}.

    Refuses an empty list and repeated values (also 0.5 together with "1/2",
    or two values that share a label).
    """
    if not isinstance(values, (list, tuple)) or len(values) == 0:
        raise ValueError(f"{where}: give a non-empty list of r values in (0, 1), got {values!r}")
    grid: dict[str, Fraction] = {}
    for index, value in enumerate(values):
        exact = parse_restitution(value, f"{where}[{index}]")
        label = restitution_label(exact)
        if label in grid:
            raise ValueError(
                f"{where}[{index}]: r = {value!r} repeats r = {grid[label]} (label {label}); "
                "each r may appear once"
            )
        grid[label] = exact
    return grid


def exact_string(value: Fraction) -> str:
    """The exact value as a string that ``parse_restitution`` reads back ("1/3", "1/4")."""
    return str(value)
