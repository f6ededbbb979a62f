"""The validation table (results/tables/validation.{csv,md}): P(0, v), P(x), <v^2>_x and the
fits held against the exact solutions and the solver, one row per r and check."""

from fractions import Fraction

import numpy as np
import pandas as pd

from ..restitution import EXACT_RESTITUTIONS
from ..tallies import RATE_CONTROLS, SHARDS_PER_CONTROL
from .moments import _number, value_with_error
from .sign_flip import SIGN_FLIPS, order_free_mean, ratio_deviations, sign_flip_test

__all__ = [
    "MINIMUM_BIN_COUNT",
    "outgoing_speed_residuals",
    "exact_outgoing_speed_residuals",
    "outgoing_speed_checks",
    "position_checks",
    "fit_checks",
    "validation_rows",
    "validation_table",
    "validation_markdown",
    "POSITION_RANGE",
    "QUALITY_SCALED_SPEEDS",
    "quality_speeds",
    "VALIDATION_CHECKS",
    "VALIDATION_COLUMNS",
]

# exact, fits and histograms (scipy, numba) are imported by the functions that use them: the
# moments and position tables need none of them


#: The fewest collisions a bin of P(0, v) needs to enter a z-score: below, its counts come from
#: a few excursions of a few shards, so its shard-scatter error is no standard error and most
#: shards' deviations share a sign (the sign-flip null fails).  The bins that follow r reach
#: about 1e-6 of the collisions at each end: their outermost bins hold a handful in any run.
MINIMUM_BIN_COUNT = 50


def outgoing_speed_residuals(simulated: pd.DataFrame, solver_curve: pd.DataFrame) -> pd.DataFrame:
    """(simulation - solver) / sigma for every bin of the simulated P(0, v), Fig. 7.

    The solver's P(0, v) of eq. (inteq) enters as its average over each bin (eq. (collrate)),
    like the data.  Bins without an error (no collisions, the under- and overflow bins) and
    bins beyond the solver's grid (or beyond where its P(0, v) underflows) are left out.

    Parameters
    ----------
    simulated : pandas.DataFrame
        A merged p0v table (columns v, v_lo, v_hi, p0v, p0v_err, count).
    solver_curve : pandas.DataFrame
        The solver's grid (columns v, p0v).

    Returns
    -------
    pandas.DataFrame
        Columns v, v_lo, v_hi, residual, count, reference (the solver's bin average) and bin
        (the bin's position in ``simulated``).
    """
    from ..fits import bin_averages_of_curve, usable_curve

    speeds, density = usable_curve(solver_curve.v.to_numpy(), solver_curve.p0v.to_numpy())
    inside = (
        (simulated.v_lo >= speeds[0])
        & (simulated.v_hi <= speeds[-1])
        & np.isfinite(simulated.p0v_err)
        & (simulated.p0v_err > 0)
        & (simulated["count"] >= MINIMUM_BIN_COUNT)
    )
    bins = simulated[inside]
    reference = bin_averages_of_curve(speeds, density, bins.v_lo.to_numpy(), bins.v_hi.to_numpy())
    return pd.DataFrame(
        {
            "v": bins.v.to_numpy(),
            "v_lo": bins.v_lo.to_numpy(),
            "v_hi": bins.v_hi.to_numpy(),
            "residual": (bins.p0v.to_numpy() - reference) / bins.p0v_err.to_numpy(),
            "count": bins["count"].to_numpy(),
            "reference": reference,
            "bin": np.flatnonzero(inside.to_numpy()),
        }
    )


def exact_outgoing_speed_residuals(simulated: pd.DataFrame, restitution) -> pd.DataFrame:
    """(simulation - exact) / sigma for every bin of the simulated P(0, v) at r = 1/2 or 1/3.

    The exact bin averages of eq. (P(0,v)) are in closed form
    (``exact.outgoing_speed_bin_average``).

    Parameters
    ----------
    simulated : pandas.DataFrame
        A merged p0v table; its finite bins with an error and at least ``MINIMUM_BIN_COUNT``
        collisions are compared.
    restitution : float or fractions.Fraction
        1/2 or 1/3.

    Returns
    -------
    pandas.DataFrame
        Columns v, residual, reference (the exact bin average) and bin (the bin's position in
        ``simulated``).
    """
    from .. import exact

    usable = (
        (simulated.v_lo > 0.0)
        & np.isfinite(simulated.v_hi)
        & np.isfinite(simulated.p0v_err)
        & (simulated.p0v_err > 0.0)
        & (simulated["count"] >= MINIMUM_BIN_COUNT)
    )
    bins = simulated[usable]
    truth = exact.outgoing_speed_bin_average(
        bins.v_lo.to_numpy(), bins.v_hi.to_numpy(), restitution
    )
    return pd.DataFrame(
        {
            "v": bins.v.to_numpy(),
            "residual": (bins.p0v.to_numpy() - truth) / bins.p0v_err.to_numpy(),
            "reference": truth,
            "bin": np.flatnonzero(usable.to_numpy()),
        }
    )


# results/tables/validation.{csv,md}: one row per r and check (long format)
VALIDATION_COLUMNS = (
    "r_label",
    "r",
    "check",
    "reference",
    "bins",
    "value",
    "bin_centre",
    "p_sign_flip",
    "detail",
)

# the checks, in the order of the table, and how the Markdown names them
VALIDATION_CHECKS = {
    "p0v_chi2_per_bin": "P(0,v): chi^2/n",
    "p0v_worst_bin": "P(0,v): worst bin, z",
    "p0v_largest_relative_error": "P(0,v): largest relative error, 0.01 <= q v <= 5",
    "p0v_martingale_chi2_per_bin": "P(0,v) martingale-controlled: chi^2/n",
    "p0v_martingale_worst_bin": "P(0,v) martingale-controlled: worst bin, z",
    "p0v_martingale_largest_relative_error": (
        "P(0,v) martingale-controlled: largest relative error, 0.01 <= q v <= 5"
    ),
    "p0v_controlled_chi2_per_bin": "P(0,v) controlled with eq. (kernel3): chi^2/n",
    "p0v_controlled_worst_bin": "P(0,v) controlled with eq. (kernel3): worst bin, z",
    "p0v_controlled_largest_relative_error": (
        "P(0,v) controlled with eq. (kernel3): largest relative error, 0.01 <= q v <= 5"
    ),
    "px_chi2_per_bin": "P(x): chi^2/n",
    "px_worst_bin": "P(x): worst bin, z",
    "v2_given_x_chi2_per_bin": "<v^2>_x: chi^2/n",
    "v2_given_x_worst_bin": "<v^2>_x: worst bin, z",
    "small_speed_fit_joint_p_value": "small-v fit: joint p-value of the theory's exponents",
    "small_speed_fit_chi2_per_dof": "small-v fit: chi^2/dof",
    "large_speed_fit_joint_p_value": "large-v fit: joint p-value of the theory's exponents",
    "large_speed_fit_chi2_per_dof": "large-v fit: chi^2/dof",
    "simulated_outside": "simulated tables: largest fraction outside their bins",
    "solved_outside": "solver's tables: largest fraction outside their range",
}

#: The fraction of a distribution a table may leave outside its range and still count as
#: whole (the automatic ranges of ``scales`` leave about 1e-6 at each end).
COMPLETE_TABLE = 1.0e-4

# "paper quality": the speeds over which the relative error of P(0, v) is reported, in units
# of 1/q(r), the large-v decay length of eqs. (asym3)-(asym6): 0.01 <= v <= 5 at r = 1/2
# (q = 1); the speeds scale like 1/q, ~ 1/(1 - r) near r = 1
QUALITY_SCALED_SPEEDS = (0.01, 5.0)


def quality_speeds(restitution) -> tuple:
    """The speeds over which the validation table reports the largest relative error of P(0, v).

    ``QUALITY_SCALED_SPEEDS`` in units of 1/q(r), q the large-speed decay rate of eqs.
    (asym3)-(asym6): the window follows the speeds of r (which grow like 1/(1 - r) near
    r = 1) and is 0.01 <= v <= 5 at r = 1/2.

    Parameters
    ----------
    restitution : float or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    tuple of float
        (lowest, highest) v.

    Examples
    --------
    >>> from bouncing_ball.validation import quality_speeds
    >>> print([round(v, 4) for v in quality_speeds(0.5)], [round(v, 4) for v in quality_speeds(0.25)])
    [0.01, 5.0] [0.005, 2.5]
    """
    from ..asymptotics import large_speed_decay_rate

    q = large_speed_decay_rate(float(restitution))
    low, high = QUALITY_SCALED_SPEEDS
    return low / q, high / q


# the heights over which P(x) and <v^2>_x are held against eqs. (P(x)2), (moment2)
POSITION_RANGE = (1.0e-3, 50.0)


def _largest(values, where):
    """The position of the largest of ``values`` (NaN: the first NaN), of equal ones the one at
    the smallest ``where``: the same bin whatever the order of the bins (``numpy.argmax``
    takes the first, e.g. of two empty bins' infinite relative errors, or of z = +-2)."""
    values, where = np.asarray(values, dtype=float), np.asarray(where, dtype=float)
    top = np.max(values)
    if np.isnan(top):
        return int(np.argmax(values))
    tied = np.flatnonzero(values == top)
    return int(tied[np.argmin(where[tied])])


def _z_rows(quantity, reference, where, z, shards, symbol, deviations=None):
    """The chi^2/n and worst-bin rows of one set of residuals ``z`` at bin centres ``where``;
    the chi^2/n row's p_sign_flip from ``sign_flip_test`` of ``deviations`` (shards x the
    bins of ``z``; None: no p)."""
    n = len(z)
    if n == 0:
        worst, at, chi2 = np.nan, np.nan, np.nan
    else:
        k = _largest(np.abs(z), where)
        worst, at, chi2 = float(z[k]), float(where[k]), float(order_free_mean(np.square(z)))
    if deviations is None or n == 0:
        p_value = np.nan
        note = f"{shards} shards; no sign-flip p without the shards' tallies"
    else:
        _, p_value, _ = sign_flip_test(deviations)
        note = f"p_sign_flip from {SIGN_FLIPS} sign flips of the {shards} shards' deviations"
        if 2.0 ** (1 - shards) > 1.0 / (1 + SIGN_FLIPS):
            note += f" (with {shards} shards p is never below about {2.0 ** (1 - shards):.2g})"
    return [
        {
            "check": f"{quantity}_chi2_per_bin",
            "reference": reference,
            "bins": n,
            "value": chi2,
            "bin_centre": np.nan,
            "p_sign_flip": p_value,
            "detail": f"mean of z^2, z = (simulation - {reference}) / error; the bins are "
            f"correlated, so it need not be near 1; {note}",
        },
        {
            "check": f"{quantity}_worst_bin",
            "reference": reference,
            "bins": n,
            "value": worst,
            "bin_centre": at,
            "p_sign_flip": np.nan,
            "detail": f"z of the bin with the largest abs(z), at {symbol} = {_number(at, 3)}",
        },
    ]


def _shard_deviations(per_shard, quantity, bins, reference, count):
    """``ratio_deviations`` of ``per_shard[quantity]`` (``shard_ratios``) in the merged
    table's bins at positions ``bins``; None without ``per_shard``."""
    if per_shard is None:
        return None
    numerators, denominators = per_shard[quantity]
    if numerators.shape[0] != count:
        raise ValueError(
            f"{quantity}: tallies of {numerators.shape[0]} shards for a table of {count} shards"
        )
    return ratio_deviations(numerators[:, bins], denominators[:, bins], reference)


def outgoing_speed_checks(simulated, restitution, shards, solver_curve=None, per_shard=None):
    """The simulated P(0, v) against eq. (P(0,v)) at r = 1/2 and 1/3, else the solver's.

    At r = 1/2 and 1/3 the reference is the exact bin averages in closed form
    (``exact.outgoing_speed_bin_average``), else the solver's P(0, v) of eq. (inteq)
    averaged over each bin like the data (eq. (collrate), ``outgoing_speed_residuals``, as
    in Fig. 7).

    Parameters
    ----------
    simulated : pandas.DataFrame
        A merged p0v table.
    restitution : float or fractions.Fraction
        r.
    shards : int
        The number of shards the errors come from.
    solver_curve : pandas.DataFrame, optional
        The solver's grid (columns v, p0v); needed where r is not 1/2 or 1/3.
    per_shard : dict, optional
        ``shard_ratios`` of the shards: gives chi^2/n its p_sign_flip (``sign_flip_test``).

    Returns
    -------
    list of dict
        Rows of ``VALIDATION_COLUMNS`` without r: chi^2/n and the worst z of
        z = (simulation - reference) / p0v_err over the bins with an error (not the under-
        and overflow bins, nor bins beyond the solver's grid), and the largest relative error
        p0v_err / p0v over the bins of ``quality_speeds(restitution)`` (0.01 <= q v <= 5;
        an empty bin there counts as an
        infinite relative error, and the row says so): these ``p0v_*`` rows of the plain counts, with the
        p_sign_flip of chi^2/n, judge agreement.  The same three of ``p0v_martingale``
        (``p0v_martingale_*``, the martingale controls: still independent of the theory)
        and of ``p0v_controlled`` (``p0v_controlled_*``, the return-law control of
        eq. (kernel3): leans on the theory under test, shown beside the independent rows),
        with no p_sign_flip, where the table has them, else those rows empty (NaN).

    Raises
    ------
    ValueError
        Where r is not 1/2 or 1/3 and no solver curve is given, or ``per_shard`` holds
        another number of shards.
    """
    rows = _outgoing_speed_rows("p0v", simulated, restitution, shards, solver_curve, per_shard)
    for estimate, absent in (
        ("p0v_martingale", f"fewer than {SHARDS_PER_CONTROL * len(RATE_CONTROLS)} shards"),
        ("p0v_controlled", "fewer than 4 shards, or r outside the solver's range"),
    ):
        if estimate in simulated and np.isfinite(simulated[estimate]).any():
            corrected = simulated.assign(
                p0v=simulated[estimate], p0v_err=simulated[f"{estimate}_err"]
            )
            rows += _outgoing_speed_rows(
                estimate, corrected, restitution, shards, solver_curve, None
            )
        else:  # every check in every r's rows: these empty
            rows += [
                {
                    "check": check,
                    "reference": "none",
                    "bins": 0,
                    "value": np.nan,
                    "bin_centre": np.nan,
                    "p_sign_flip": np.nan,
                    "detail": f"no {estimate}: {absent}",
                }
                for check in VALIDATION_CHECKS
                if check.startswith(f"{estimate}_")
            ]
    return rows


def _outgoing_speed_rows(quantity, simulated, restitution, shards, solver_curve, per_shard):
    """The rows of ``outgoing_speed_checks`` of the table's p0v, p0v_err, named ``quantity``."""
    if Fraction(restitution) in EXACT_RESTITUTIONS:
        reference = "exact"
        residuals = exact_outgoing_speed_residuals(simulated, restitution)
    else:
        if solver_curve is None:
            raise ValueError(f"r = {restitution}: no exact P(0, v), and no solver curve given")
        reference = "solver"
        residuals = outgoing_speed_residuals(simulated, solver_curve)
    where, z = residuals.v.to_numpy(), residuals.residual.to_numpy()
    deviations = _shard_deviations(
        per_shard, "p0v", residuals.bin.to_numpy(), residuals.reference.to_numpy(), shards
    )
    rows = _z_rows(quantity, reference, where, z, shards, "v", deviations)
    rows.append(_relative_error_row(quantity, simulated, restitution))
    return rows


def _relative_error_row(quantity, simulated, restitution):
    """The largest relative error of the table's p0v over ``quality_speeds(restitution)``,
    with the reason of an inf (bins without a collision) or a NaN (no bin there)."""
    from ..asymptotics import large_speed_decay_rate

    low, high = quality_speeds(restitution)
    scaled_low, scaled_high = QUALITY_SCALED_SPEEDS
    window = (
        f"{_number(low, 3)} <= v <= {_number(high, 3)} ({scaled_low:g} <= q v <= {scaled_high:g}, "
        f"q = {large_speed_decay_rate(float(restitution)):.4g} of eqs. (asym4), (asym6))"
    )
    finite = np.isfinite(simulated.v_hi) & (simulated.v_lo > 0.0)
    quality = simulated[finite & (simulated.v >= low) & (simulated.v <= high)]
    empty = (quality.p0v <= 0.0) | ~np.isfinite(quality.p0v_err)
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.where(empty, np.inf, quality.p0v_err / quality.p0v)
    covered = simulated[finite]
    if len(relative):
        k = _largest(relative, quality.v.to_numpy())
        largest, at = float(relative[k]), float(quality.v.iloc[k])
        detail = f"max of p0v_err / p0v over the bins with {window}, at v = {_number(at, 3)}"
        if count := int(np.sum(empty)):
            detail += (
                f"; {count} of them without a collision or an error (an infinite relative "
                "error: the run is too short there)"
            )
    else:
        largest, at = np.nan, np.nan
        detail = f"no bin with its centre in {window}" + (
            f": the bins span {_number(covered.v_lo.min(), 3)} <= v <= "
            f"{_number(covered.v_hi.max(), 3)}"
            if len(covered)
            else ": the table has no finite bins"
        )
    if len(relative) and len(covered) and (covered.v_lo.min() > low or covered.v_hi.max() < high):
        detail += (
            f"; the bins cover only {_number(max(low, covered.v_lo.min()), 3)} <= v <= "
            f"{_number(min(high, covered.v_hi.max()), 3)} of it"
        )
    return {
        "check": f"{quantity}_largest_relative_error",
        "reference": "none",
        "bins": len(relative),
        "value": largest,
        "bin_centre": at,
        "p_sign_flip": np.nan,
        "detail": detail,
    }


def position_checks(position, restitution, shards, per_shard=None):
    """The simulated P(x) and <v^2>_x against eqs. (P(x)2) and (moment2) at r = 1/2 and 1/3.

    The references are the exact bin averages (``exact.position_bin_average``,
    ``exact.speed_squared_given_position_bin_average``).

    Parameters
    ----------
    position : pandas.DataFrame
        A merged position table (columns x, x_lo, x_hi, px, px_err, v2_given_x,
        v2_given_x_err).
    restitution : float or fractions.Fraction
        r.
    shards : int
        The number of shards the errors come from.
    per_shard : dict, optional
        ``shard_ratios`` of the shards, as in ``outgoing_speed_checks``.

    Returns
    -------
    list of dict
        Rows without r: chi^2/n (with its p_sign_flip where ``per_shard`` is given) and the
        worst z over the bins inside 1e-3 <= x <= 50 that have an error, for P(x) and for
        <v^2>_x; no rows for another r (no exact P(x) there).
    """
    if Fraction(restitution) not in EXACT_RESTITUTIONS:
        return []
    from .. import exact

    low, high = POSITION_RANGE
    inside = (
        (position.x_lo >= low * (1.0 - 1e-9))
        & (position.x_hi <= high * (1.0 + 1e-9))
        & np.isfinite(position.x_hi)
    )
    rows = []
    for quantity, bin_average in (
        ("px", exact.position_bin_average),
        ("v2_given_x", exact.speed_squared_given_position_bin_average),
    ):
        error = position[f"{quantity}_err"]
        compared = inside & np.isfinite(error) & (error > 0.0)
        bins = position[compared]
        truth = np.asarray(
            bin_average(bins.x_lo.to_numpy(), bins.x_hi.to_numpy(), restitution), dtype=float
        )
        z = (bins[quantity].to_numpy() - truth) / bins[f"{quantity}_err"].to_numpy()
        deviations = _shard_deviations(
            per_shard, quantity, np.flatnonzero(compared.to_numpy()), truth, shards
        )
        for row in _z_rows(quantity, "exact", bins.x.to_numpy(), z, shards, "x", deviations):
            row["detail"] += f"; bins in {low:g} <= x <= {high:g}"
            rows.append(row)
    return rows


def _fit_problems(fits, side, shards, max_bias):
    """Why the free-exponent fit of one window tests nothing: [] where it is a check.

    The window must lie where the form holds on the solver's curve (its free fit there within
    ``max_bias`` of the data's error of the theory's exponents, the rule of
    ``fits.asymptotic_window``), the small-v window below the large-v one, and the fit must
    have power: an exponent of the theory beyond the 95% half-width of its fitted value
    (t(0.975, shards - 1) times its jackknife error), else no fit of these data could tell
    it from 0, a wrong exponent.  Returns the problems and, apart, the exponents without
    power where another has it (the joint test then tests the others)."""
    from ..fits import EXPONENT_NAMES, LARGE_SPEED, SMALL_SPEED, interval_factor

    free = fits[fits.fit == "free_exponents"]
    simulated = free[(free.source == "simulation") & (free.window == side)].set_index("parameter")
    solved = free[(free.source == "solver") & (free.window == side)].set_index("parameter")
    names = list(EXPONENT_NAMES[side])
    first = simulated.iloc[0]
    if not np.all(np.isfinite(simulated.loc[names, "value"])):
        return [
            f"the fit of free exponents finds no optimum over v in [{_number(first.v_min, 3)}, "
            f"{_number(first.v_max, 3)}] (the fit's log says why)"
        ], []
    problems = []
    if side == SMALL_SPEED:
        large = free[(free.source == "simulation") & (free.window == LARGE_SPEED)]
        if (
            len(large)
            and np.isfinite(large.iloc[0].v_min)
            and first.v_max > large.iloc[0].v_min * (1.0 + 1e-9)
        ):
            problems.append(
                f"its window [{_number(first.v_min, 3)}, {_number(first.v_max, 3)}] is not "
                f"below the large-v window [{_number(large.iloc[0].v_min, 3)}, "
                f"{_number(large.iloc[0].v_max, 3)}]"
            )
    factor, unresolved = interval_factor(shards), []
    for name in names:
        theory, error = float(simulated.loc[name, "theory"]), float(simulated.loc[name, "error"])
        curve = float(solved.loc[name, "value"]) if name in solved.index else np.nan
        if not np.isfinite(curve):
            problems.append(f"the free fit to the solver's curve gives no {name} over this window")
        elif not abs(curve - theory) <= max_bias * error:
            problems.append(
                f"the form does not hold over this window: on the solver's curve the free fit "
                f"gives {name} = {_number(curve, 3)} against the theory's {_number(theory, 3)}, "
                f"more than {max_bias:g} of the data's error {_number(error, 2)}"
            )
        if not factor * error < abs(theory):
            unresolved.append(
                f"the theory's {name} = {_number(theory, 3)} lies within the 95% half-width "
                f"{_number(factor * error, 2)} of 0, so the fit could not reject {name} = 0"
            )
    if len(unresolved) == len(names):
        problems.append("no power: " + "; ".join(unresolved))
    return problems, unresolved


def fit_checks(fits, shards, max_bias=0.5):
    """The free-exponent fits of the asymptotic forms to the simulated P(0, v), as checks.

    Per window (small v, eqs. (asym1), (asym2); large v, eqs. (asym3)-(asym6)) the joint
    p-value of the theory's exponents (Hotelling's T^2 on the jackknife covariance) and the
    fit's chi^2 per degree of freedom (per-bin errors only: indicative, it ignores the
    correlations between bins).  A fit that tests nothing is not counted: where the window
    lies outside the form's regime (on the solver's curve the free exponents drift from the
    theory's by more than ``max_bias`` of the data's errors, or the small-v window is not
    below the large-v one) or the fit has no power (every theory's exponent within the 95%
    half-width of 0), both rows have the value NaN and a detail "not checked: <why>", with
    what the fit gave; an exponent without power beside one with it is named as not tested.

    Parameters
    ----------
    fits : pandas.DataFrame
        A fits table (``fits.asymptotic_fits``).
    shards : int
        The number of shards of the simulation's jackknife (the t factor of the intervals).
    max_bias : float, optional
        The drift of the form allowed on the solver's curve, in units of the data's error
        (config ``fits.max_bias``, the rule the auto windows are chosen by).

    Returns
    -------
    list of dict
        Two rows per window, without r; a window without a usable fit gives NaN values.
    """
    from ..fits import LARGE_SPEED, SMALL_SPEED

    chosen = fits[(fits.source == "simulation") & (fits.fit == "free_exponents")]
    rows = []
    for side in (SMALL_SPEED, LARGE_SPEED):
        window = chosen[chosen.window == side]
        if window.empty:
            continue
        first = window.iloc[0]
        exponents = window[window.parameter != "prefactor"]
        fitted = ", ".join(
            f"{row.parameter} = {value_with_error(row.value, row.error)} "
            f"(theory {_number(row.theory, 4)})"
            if np.isfinite(row.value)
            else f"theory {row.parameter} = {_number(row.theory, 4)}"
            for row in exponents.itertuples()
        )
        dof = int(first.dof) if np.isfinite(first.dof) else 0
        bins = dof + len(window) if dof > 0 else 0
        where = (
            f"v in [{_number(first.v_min, 3)}, {_number(first.v_max, 3)}]"
            if np.isfinite(first.v_min)
            else "no usable window (the fit's log says why)"
        )
        joint, chi2 = float(first.joint_p_value), float(first.chi2_per_dof)
        problems, unresolved = (
            _fit_problems(fits, side, shards, max_bias) if np.isfinite(first.v_min) else ([], [])
        )
        if unresolved and not problems:
            fitted += "; not tested: " + "; ".join(unresolved)
        if problems:
            lead = "not checked: " + "; ".join(problems) + "; the fit: "
            fitted += f"; joint p {_number(joint, 3)}, chi^2/dof {_number(chi2, 3)}"
            joint, chi2 = np.nan, np.nan
        else:
            lead = ""
            if np.isfinite(first.v_min) and not np.isfinite(joint):
                # Hotelling's T^2 needs more shards than free exponents (fits.fit_shards)
                fitted += "; no joint test: too few shards for the exponents"
        rows += [
            {
                "check": f"{side}_fit_joint_p_value",
                "reference": "theory",
                "bins": bins,
                "value": joint,
                "bin_centre": np.nan,
                "p_sign_flip": np.nan,
                "detail": f"{lead}{where}; {fitted}",
            },
            {
                "check": f"{side}_fit_chi2_per_dof",
                "reference": "fit",
                "bins": bins,
                "value": chi2,
                "bin_centre": np.nan,
                "p_sign_flip": np.nan,
                "detail": f"{lead}{where}; {dof} degrees of freedom; indicative: the bins are "
                "correlated (the joint p-value is the test)",
            },
        ]
    return rows


def coverage_checks(simulated_outside=None, solved_outside=None) -> list[dict]:
    """How much of its distribution each table of one r leaves outside its range.

    Parameters
    ----------
    simulated_outside, solved_outside : dict, optional
        The ``outside`` provenance of rule merge_shards' and rule solve's tables ({table:
        {"below", "above", "outside", "counts"}}; None where unbounded).

    Returns
    -------
    list of dict
        One row for each given: the largest fraction outside, with each table's in the
        detail, and whether every table holds all but ``COMPLETE_TABLE`` of its distribution.

    Examples
    --------
    >>> from bouncing_ball.validation.checks import coverage_checks
    >>> row, = coverage_checks({"p0v": {"below": 2e-6, "above": 0.0, "outside": 2e-6,
    ...                                  "counts": "collisions", "lo": 1e-6, "hi": 25.1}})
    >>> print(row["value"], row["detail"])
    2e-06 p0v 2.0e-06 of the collisions outside [1e-06, 25.1]; every table holds all but 0.0001 of its distribution
    """
    rows = []
    for check, outside in (
        ("simulated_outside", simulated_outside),
        ("solved_outside", solved_outside),
    ):
        if outside is None:
            continue
        parts = {name: part["outside"] for name, part in outside.items()}
        value = max((np.inf if v is None else v) for v in parts.values())
        shown = "; ".join(
            f"{name} {'an unbounded part' if v is None else f'{v:.1e}'} of the "
            f"{outside[name]['counts']}"
            + (
                f" outside [{outside[name]['lo']:.3g}, {outside[name]['hi']:.3g}]"
                if "lo" in outside[name]
                else ""
            )
            for name, v in parts.items()
        )
        verdict = (
            f"every table holds all but {COMPLETE_TABLE:g} of its distribution"
            if value <= COMPLETE_TABLE
            else f"incomplete: more than {COMPLETE_TABLE:g} outside (give the bins or grids as auto)"
        )
        rows.append(
            {
                "check": check,
                "reference": "none",
                "bins": 0,
                "value": value,
                "bin_centre": np.nan,
                "p_sign_flip": np.nan,
                "detail": f"{shown}; {verdict}",
            }
        )
    return rows


def validation_rows(
    label,
    restitution,
    p0v,
    position,
    fits,
    shards,
    solver_curve=None,
    per_shard=None,
    max_bias=0.5,
    outside=None,
) -> list[dict]:
    """Every check of one r.

    ``outgoing_speed_checks``, ``position_checks``, ``fit_checks``, ``coverage_checks``.

    Parameters
    ----------
    label : str
        The r label.
    restitution : float or fractions.Fraction
        r.
    p0v, position, fits : pandas.DataFrame
        The merged p0v and position tables and the fits table.
    shards : int
        The number of shards the errors come from.
    solver_curve : pandas.DataFrame, optional
        The solver's P(0, v) grid (where r is not 1/2 or 1/3).
    per_shard : dict, optional
        The shards' ``shard_ratios`` (for the p_sign_flip of the chi^2/n rows).
    max_bias : float, optional
        Of ``fit_checks``: the fits' ``fits.max_bias``.
    outside : tuple of dict, optional
        The ``outside`` provenance of the simulated and the solver's tables
        (``coverage_checks``).

    Returns
    -------
    list of dict
        The rows, each with the r label and r.
    """
    rows = [
        *outgoing_speed_checks(p0v, restitution, shards, solver_curve, per_shard),
        *position_checks(position, restitution, shards, per_shard),
        *fit_checks(fits, shards, max_bias),
        *coverage_checks(*(outside or ())),
    ]
    return [{"r_label": label, "r": float(restitution), **row} for row in rows]


def validation_table(rows) -> pd.DataFrame:
    """The rows of ``validation_rows`` (of every r) as results/tables/validation.csv.

    Parameters
    ----------
    rows : list of dict
        Rows of ``validation_rows``.

    Returns
    -------
    pandas.DataFrame
        Columns ``VALIDATION_COLUMNS``.
    """
    table = pd.DataFrame(rows, columns=list(VALIDATION_COLUMNS))
    return table.astype({"bins": "int64"}) if len(table) else table


def _shown_value(check, value, detail=""):
    if detail.startswith("not checked"):
        return "not checked"
    if not np.isfinite(value):
        return "inf" if value == np.inf else ""
    if check.endswith("relative_error"):
        percent = 100.0 * value
        return f"{percent:.0f}%" if percent >= 10.0 else f"{percent:.2g}%"
    if check.endswith("worst_bin"):
        return f"{value:+.2f}"
    return f"{value:.3g}"


def _shown_check(check, restitution):
    """The check's name; a relative-error row's with its window's speeds at r."""
    name = VALIDATION_CHECKS[check]
    if check.endswith("largest_relative_error"):
        low, high = quality_speeds(restitution)
        name += f" ({_number(low, 3)} <= v <= {_number(high, 3)})"
    return name


def validation_markdown(table: pd.DataFrame) -> str:
    """The validation table for a reader, as results/tables/validation.md.

    Parameters
    ----------
    table : pandas.DataFrame
        The table of ``validation_table``.

    Returns
    -------
    str
        A Markdown table, one line per r and check, values to 2-3 digits (z to 2 decimals,
        relative errors in percent); no '|' in a cell.
    """
    shown = pd.DataFrame(
        {
            "r": table.r_label.astype(str),
            "check": [_shown_check(c, r) for c, r in zip(table.check, table.r)],
            "reference": table.reference,
            "bins": table.bins.astype(str),
            "value": [
                _shown_value(c, v, d) for c, v, d in zip(table.check, table.value, table.detail)
            ],
            "at v or x": table.bin_centre.map(lambda value: _number(value, 3)),
            "p_sign_flip": table.p_sign_flip.map(lambda value: _number(value, 2)),
            "detail": table.detail,
        }
    )
    return shown.to_markdown(index=False, disable_numparse=True) + "\n"
