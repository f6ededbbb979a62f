"""The coefficient of restitution r, eq. (restitution): parsing and labels.

Config gives r as a decimal (0.25) or an exact fraction string ("1/3").  The
exact value is kept as a ``Fraction`` (a decimal is read as written, so
0.3 is 3/10).  Output paths use a canonical label: the value with 6
significant digits, trailing zeros dropped ("0.25", "0.333333").
"""

from fractions import Fraction

# the r with an exact solution, eq. (P(0,v)) (bouncing_ball.exact)
EXACT_RESTITUTIONS = (Fraction(1, 2), Fraction(1, 3))

# the r for which the solver of eq. (inteq) (bouncing_ball.solver) meets its 1e-8 accuracy
# target: below 0.02 P(0, v) ~ exp(-v / (2r)) leaves the range of doubles within the speeds that
# matter (the answer is wrong by 2% at 0.015, by 50% at 0.01); above 0.9999 the dense grid,
# ~ (1 - r)^(-1/2) nodes, outgrows a job.  The bounds are exact decimals: 0.02 is 1/50.
SOLVER_RESTITUTION_RANGE = (0.02, 0.9999)
# the r for which the whole distribution from P(0, v) (bouncing_ball.distribution: w(F), P(x),
# P(x, v)) meets the same target, and so every table of rule solve: the r of a run.  Above, int
# P dx drifts from 1 (by 5e-8 at r = 0.93, 3e-6 at 0.95, 1e-4 at 0.99): the weight of P(x)
# moves to forces F where w(F) is not computed accurately
DISTRIBUTION_RESTITUTION_RANGE = (0.02, 0.9)


def in_range(exact, bounds) -> bool:
    """``low <= exact <= high`` for the exact r and the decimal bounds read as written (so that
    r = 1/50 is inside a range that starts at 0.02, whose float is a little above 1/50)."""
    low, high = (Fraction(str(bound)) for bound in bounds)
    return low <= Fraction(exact) <= high


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
    label = restitution_label(exact)
    if not 0 < float(label) < 1:
        raise ValueError(
            f"{where}: r = {value!r} rounds to {label} at the 6 significant digits of the "
            "labels its outputs are filed under, which is not an r in (0, 1); give an r whose "
            + ("label stays below 1 (at most 0.9999994)" if exact > 0.5 else "label is not 0")
        )
    return exact


def check_solver_restitution(value, where: str = "restitution") -> Fraction:
    """``value`` parsed, if rule solve answers it to its accuracy target (P(0, v) and the whole
    distribution: ``DISTRIBUTION_RESTITUTION_RANGE``); ValueError naming ``where`` and the range
    otherwise."""
    exact = parse_restitution(value, where)
    low, high = DISTRIBUTION_RESTITUTION_RANGE
    if not in_range(exact, DISTRIBUTION_RESTITUTION_RANGE):
        solver_low, solver_high = SOLVER_RESTITUTION_RANGE
        raise ValueError(
            f"{where}: r = {value!r} is outside the solver's range {low} <= r <= {high}, "
            "where its P(0, v), P(x) and P(x, v) meet the 1e-8 accuracy target "
            f"(P(0, v) alone, solver.restitution_grid: {solver_low} <= r <= {solver_high}; "
            "docs/distribution.md#where-it-degrades)"
        )
    return exact


def restitution_value(value, where: str = "restitution") -> float:
    """r as a float from a float, an int, a ``Fraction`` or a fraction string ("1/3"), as the
    pipeline reads it (``parse_restitution``); the library's public entry points take r so."""
    return float(parse_restitution(value, where))


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
    """Why two different r cannot both be asked for: their outputs would share a folder."""
    return (
        f"{where}: r = {value} and r = {other} share the label {restitution_label(value)} "
        "(6 significant digits) under which outputs are filed; keep one of them"
    )


def exact_string(value: Fraction) -> str:
    """The exact value as a string that ``parse_restitution`` reads back ("1/3", "1/4")."""
    return str(value)
