"""The simulation held against the exact solutions and the solver: z-scores and residuals.

Pure functions on the tables the workflow writes; the figures (Figs. 5-7),
results/tables/moments.{csv,md} and results/tables/validation.{csv,md} are
drawn from them.
"""

import numbers
from fractions import Fraction

import numpy as np
import pandas as pd

from .restitution import EXACT_RESTITUTIONS
from .tallies import RATE_CONTROLS, SHARDS_PER_CONTROL

# exact, fits and histograms (scipy, numba) are imported by the functions that use them: the
# moments and position tables need none of them

__all__ = [
    "compare",
    "moment_rows",
    "moments_table",
    "moments_markdown",
    "value_with_error",
    "independent_estimate",
    "kernel3_estimate",
    "INDEPENDENT_ESTIMATOR",
    "outgoing_speed_residuals",
    "exact_outgoing_speed_residuals",
    "sign_flip_test",
    "order_free_mean",
    "ratio_deviations",
    "shard_ratios",
    "outgoing_speed_checks",
    "position_checks",
    "fit_checks",
    "validation_rows",
    "validation_table",
    "validation_markdown",
    "position_asymptotics_table",
    "position_asymptotics_markdown",
]

# the time averages of eq. (xandDeltax)
QUANTITIES = ("mean_x", "delta_x", "collision_rate")
SYMBOLS = {"mean_x": "<x>", "delta_x": "Delta x", "collision_rate": "I"}

# the numbers as printed in eq. (xandDeltax) (rounded there); the exact stage
# recomputes them from eqs. (P(x)2), (collrate) and (constants)
PAPER_VALUES = {
    Fraction(1, 2): {"mean_x": 6.0, "delta_x": 10.4, "collision_rate": 1.0 / 3.0},
    Fraction(1, 3): {"mean_x": 3.89, "delta_x": 7.68, "collision_rate": 3.0 / 4.0},
}

MOMENT_COLUMNS = (
    "r_label",
    "r",
    "quantity",
    "paper",
    "exact",
    "solver",
    "simulation",
    "simulation_err",
    "estimator",
    "reference",
    "z",
    "kernel3_controlled",
    "kernel3_controlled_err",
    "kernel3_z",
)

#: The estimator of each quantity in the moments table's ``simulation`` column, fixed in
#: advance and the same at every r: the summary's ``{quantity}_martingale``, corrected by the
#: martingale control variates only (their mean is 0 for the simulated process whatever it
#: is, ``histograms.position_moments_summary``), and where the shards are too few for them
#: (NaN) the plain ``{quantity}``.  Never chosen by the smaller error: a choice by a noisy
#: error picks the estimates whose errors came out low.
INDEPENDENT_ESTIMATOR = "martingale"


def independent_estimate(summary, quantity):
    """The estimate of ``quantity`` that judges agreement: independent of the theory.

    By the fixed rule of ``INDEPENDENT_ESTIMATOR``: ``{quantity}_martingale`` where the summary
    has it (finite), else the plain ``{quantity}``; estimator is "martingale" or "plain".

    Parameters
    ----------
    summary : mapping
        The merge stage's summary row.
    quantity : str
        One of ``QUANTITIES``.

    Returns
    -------
    tuple
        (value, error, estimator).

    Examples
    --------
    >>> from bouncing_ball.comparison import independent_estimate
    >>> summary = {"mean_x": 6.0, "mean_x_err": 0.2, "mean_x_martingale": 6.1,
    ...            "mean_x_martingale_err": 0.3}
    >>> independent_estimate(summary, "mean_x")
    (6.1, 0.3, 'martingale')
    """
    column = f"{quantity}_{INDEPENDENT_ESTIMATOR}"
    if column in summary and np.isfinite(float(summary[column])):
        return float(summary[column]), float(summary[f"{column}_err"]), INDEPENDENT_ESTIMATOR
    return float(summary[quantity]), float(summary[f"{quantity}_err"]), "plain"


def kernel3_estimate(summary, quantity):
    """The estimate of ``quantity`` corrected with the flight-law controls of eq. (kernel3).

    The summary's ``{quantity}_controlled`` where its ``kernel3_controls`` is true, else
    (NaN, NaN): an estimate that leans on the theory it is held against, shown beside the
    independent one, never instead of it.

    Parameters
    ----------
    summary : mapping
        The merge stage's summary row.
    quantity : str
        One of ``QUANTITIES``.

    Returns
    -------
    tuple of float
        (value, error).
    """
    column = f"{quantity}_controlled"
    if column in summary and bool(summary.get("kernel3_controls", False)):
        return float(summary[column]), float(summary[f"{column}_err"])
    return np.nan, np.nan


def _z(value, error, reference):
    if np.isfinite(value) and np.isfinite(reference) and error > 0:
        return (value - reference) / error
    return np.nan


def moment_rows(label, restitution, simulation, solver, exact=None):
    """The time averages <x>, Delta x and I of eq. (xandDeltax) of one r, with their z.

    The simulation's value is the independent estimate (``independent_estimate``: the
    martingale-controlled one, or the plain one with too few shards; ``estimator`` says
    which), z = (simulation - reference) / simulation_err, the reference being the exact
    value where there is one and the solver's otherwise.  Beside it, ``kernel3_controlled``
    with its error and ``kernel3_z`` against the same reference: the estimate corrected with
    the flight-law controls of eq. (kernel3) (``kernel3_estimate``; NaN where the summary
    has none).  It leans on the theory under test, so agreement is judged on ``z``.

    Parameters
    ----------
    label : str
        The r label.
    restitution : float or fractions.Fraction
        r.
    simulation : mapping
        The merge stage's summary: each quantity and its ``<quantity>_err``, and where the
        shards allowed them ``<quantity>_martingale``, ``<quantity>_controlled`` (with
        ``_err``) and ``kernel3_controls``.
    solver : mapping
        The solve stage's summary.
    exact : mapping, optional
        The exact stage's summary (None where r is not 1/2 or 1/3).

    Returns
    -------
    list of dict
        One row per quantity, keys ``MOMENT_COLUMNS`` (with the paper's rounded numbers at
        r = 1/2 and 1/3).

    Examples
    --------
    >>> from bouncing_ball.comparison import moment_rows
    >>> simulation = {"mean_x": 6.01, "mean_x_err": 0.01, "delta_x": 10.4,
    ...               "delta_x_err": 0.1, "collision_rate": 0.333, "collision_rate_err": 0.001}
    >>> exact = {"mean_x": 6.0, "delta_x": 10.39, "collision_rate": 1 / 3}
    >>> row = moment_rows("0.5", 0.5, simulation, exact, exact)[0]
    >>> print(row["quantity"], row["paper"], row["reference"], row["estimator"], round(row["z"], 6))
    mean_x 6.0 exact plain 1.0
    """
    paper = PAPER_VALUES.get(Fraction(restitution))
    rows = []
    for quantity in QUANTITIES:
        reference_name = "exact" if exact is not None else "solver"
        reference = float((exact if exact is not None else solver)[quantity])
        value, error, estimator = independent_estimate(simulation, quantity)
        kernel3, kernel3_err = kernel3_estimate(simulation, quantity)
        rows.append(
            {
                "r_label": label,
                "r": float(restitution),
                "quantity": quantity,
                "paper": paper[quantity] if paper else np.nan,
                "exact": float(exact[quantity]) if exact is not None else np.nan,
                "solver": float(solver[quantity]),
                "simulation": value,
                "simulation_err": error,
                "estimator": estimator,
                "reference": reference_name,
                "z": _z(value, error, reference),
                "kernel3_controlled": kernel3,
                "kernel3_controlled_err": kernel3_err,
                "kernel3_z": _z(kernel3, kernel3_err, reference),
            }
        )
    return rows


def moments_table(rows) -> pd.DataFrame:
    """The rows of ``moment_rows`` (of every r) as results/tables/moments.csv.

    Parameters
    ----------
    rows : list of dict
        Rows of ``moment_rows``.

    Returns
    -------
    pandas.DataFrame
        Columns ``MOMENT_COLUMNS``.
    """
    return pd.DataFrame(rows, columns=list(MOMENT_COLUMNS))


def _number(value, digits=6):
    return "" if not np.isfinite(value) else f"{value:.{digits}g}"


def value_with_error(value, error) -> str:
    """A value with its error, to the second significant digit of the error.

    Parameters
    ----------
    value, error : float
        The value and its standard error.

    Returns
    -------
    str
        "value ± error"; the value alone (6 significant digits) where the error is not
        finite and positive, "" where the value is not finite.

    Examples
    --------
    >>> from bouncing_ball.comparison import value_with_error
    >>> value_with_error(3.42803, 0.003)
    '3.4280 ± 0.0030'
    >>> value_with_error(1234.5, 25.0)
    '1234 ± 25'
    """
    if not (np.isfinite(value) and np.isfinite(error) and error > 0):
        return _number(value)
    decimals = max(0, 1 - int(np.floor(np.log10(error))))
    return f"{value:.{decimals}f} ± {error:.{decimals}f}"


def moments_markdown(table: pd.DataFrame) -> str:
    """The moments table for a reader, as results/tables/moments.md.

    Parameters
    ----------
    table : pandas.DataFrame
        The table of ``moments_table``.

    Returns
    -------
    str
        A Markdown table: the paper's rounded numbers, the exact and the solver's values,
        the simulation's independent estimate (value ± error, its estimator, z), and the
        estimate controlled with eq. (kernel3) with its z.
    """
    shown = pd.DataFrame(
        {
            "r": table.r_label,
            "quantity": table.quantity.map(SYMBOLS),
            "paper, eq. (xandDeltax)": table.paper.map(lambda value: _number(value, 4)),
            "exact": table.exact.map(lambda value: _number(value, 10)),
            "solver, eq. (inteq)": table.solver.map(lambda value: _number(value, 10)),
            "simulation": [
                value_with_error(value, error)
                for value, error in zip(table.simulation, table.simulation_err)
            ],
            "estimator": table.estimator,
            "z": [
                f"{z:+.2f} (vs {reference})" if np.isfinite(z) else ""
                for z, reference in zip(table.z, table.reference)
            ],
            "controlled with eq. (kernel3)": [
                value_with_error(value, error)
                for value, error in zip(table.kernel3_controlled, table.kernel3_controlled_err)
            ],
            "z, eq. (kernel3)": [f"{z:+.2f}" if np.isfinite(z) else "" for z in table.kernel3_z],
        }
    )
    return shown.to_markdown(index=False, disable_numparse=True) + "\n"


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
    from .fits import bin_averages_of_curve, usable_curve

    speeds, density = usable_curve(solver_curve.v.to_numpy(), solver_curve.p0v.to_numpy())
    inside = (
        (simulated.v_lo >= speeds[0])
        & (simulated.v_hi <= speeds[-1])
        & np.isfinite(simulated.p0v_err)
        & (simulated.p0v_err > 0)
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
        A merged p0v table; its finite bins with an error are compared.
    restitution : float or fractions.Fraction
        1/2 or 1/3.

    Returns
    -------
    pandas.DataFrame
        Columns v, residual, reference (the exact bin average) and bin (the bin's position in
        ``simulated``).
    """
    from . import exact

    usable = (
        (simulated.v_lo > 0.0)
        & np.isfinite(simulated.v_hi)
        & np.isfinite(simulated.p0v_err)
        & (simulated.p0v_err > 0.0)
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
    "p0v_largest_relative_error": "P(0,v): largest relative error, 0.01 <= v <= 5",
    "p0v_martingale_chi2_per_bin": "P(0,v) martingale-controlled: chi^2/n",
    "p0v_martingale_worst_bin": "P(0,v) martingale-controlled: worst bin, z",
    "p0v_martingale_largest_relative_error": (
        "P(0,v) martingale-controlled: largest relative error, 0.01 <= v <= 5"
    ),
    "p0v_controlled_chi2_per_bin": "P(0,v) controlled with eq. (kernel3): chi^2/n",
    "p0v_controlled_worst_bin": "P(0,v) controlled with eq. (kernel3): worst bin, z",
    "p0v_controlled_largest_relative_error": (
        "P(0,v) controlled with eq. (kernel3): largest relative error, 0.01 <= v <= 5"
    ),
    "px_chi2_per_bin": "P(x): chi^2/n",
    "px_worst_bin": "P(x): worst bin, z",
    "v2_given_x_chi2_per_bin": "<v^2>_x: chi^2/n",
    "v2_given_x_worst_bin": "<v^2>_x: worst bin, z",
    "small_speed_fit_joint_p_value": "small-v fit: joint p-value of the theory's exponents",
    "small_speed_fit_chi2_per_dof": "small-v fit: chi^2/dof",
    "large_speed_fit_joint_p_value": "large-v fit: joint p-value of the theory's exponents",
    "large_speed_fit_chi2_per_dof": "large-v fit: chi^2/dof",
}

# "paper quality": the speeds over which the relative error of P(0, v) is reported
QUALITY_SPEEDS = (0.01, 5.0)
# the heights over which P(x) and <v^2>_x are held against eqs. (P(x)2), (moment2)
POSITION_RANGE = (1.0e-3, 50.0)


# the sign-flip test of the chi^2/n rows: this many random flips, from a fixed seed, so that
# the table is the same on every machine
SIGN_FLIPS = 10_000
SIGN_FLIP_SEED = 20061121
_FLIPS_PER_BLOCK = 1000  # flips evaluated at once (memory: block x bins)
# the unit roundoff of a float64: a rounded +, -, x or / is exact times (1 + e), |e| <= u
_UNIT_ROUNDOFF = float(np.finfo(float).eps) / 2.0
# the bits of a float64's significand: every integer of magnitude <= 2^52 is exact
_SIGNIFICAND_BITS = 53


def order_free_mean(values):
    """The mean along the last axis, the same bits for any order of the values.

    The values are sorted and then added one by one in ascending order (``numpy.cumsum``
    is sequential), so neither their order nor the machine changes the rounding (numpy's
    pairwise sum depends on the order).  The sum is off by at most (m - 1) u sum abs(x)
    (u = 2^-53, m values).

    Parameters
    ----------
    values : array_like, shape (..., m), m >= 1
        The values; not NaN, and not infinities of both signs.

    Returns
    -------
    numpy.ndarray or float
        The means, shape (...).

    Raises
    ------
    ValueError
        Where there is no value along the last axis.

    Examples
    --------
    >>> from bouncing_ball.comparison import order_free_mean
    >>> print(order_free_mean([0.1, 0.2, 0.3]) == order_free_mean([0.3, 0.1, 0.2]))
    True
    """
    values = np.asarray(values, dtype=float)
    if values.ndim == 0 or values.shape[-1] == 0:
        raise ValueError(
            f"values: need at least one value along the last axis, got shape {values.shape}"
        )
    return np.cumsum(np.sort(values, axis=-1), axis=-1)[..., -1] / values.shape[-1]


def _integer_deviations(deviations):
    """Each bin's deviations as integers whose every signed sum over shards is exact.

    Bin b is scaled by a power of 2 (exactly) so that its largest |deviation| lies in
    [2^(51 - c), 2^(52 - c)), c = ceil(log2(shards)), and rounded to the nearest integer
    (half to even: -d gives -q).  A sum of the shards' integers times +-1 is then an integer
    of magnitude <= shards x 2^(52 - c) <= 2^52, exact in float64 whatever the order of the
    additions (a BLAS kernel's blocking, fused multiply-adds and threads).  z^2 of a bin does
    not change when the bin is scaled; the rounding moves each deviation by at most
    2^(c - 53) of the bin's largest, the size of the rounding of the float sum it replaces.
    """
    headroom = (deviations.shape[0] - 1).bit_length()  # ceil(log2(shards))
    _, exponents = np.frexp(np.max(np.abs(deviations), axis=0))
    return np.rint(np.ldexp(deviations, _SIGNIFICAND_BITS - 1 - headroom - exponents))


def _z_squared(signs, integers, squares):
    """z^2 of every bin under each sign pattern (rows of ``signs``), ``sign_flip_test``.

    With T = sum_k s_k q_k (exact: ``_integer_deviations``) and S = sum_k q_k^2,
    z^2 = (n - 1) n m^2 / (S - n m^2) at m = T / n is (n - 1) T^2 / (n S - T^2): a function
    of T^2, so patterns whose T agree up to sign give the same bits.  Where n S - T^2
    rounds to <= 0 (every s_k q_k equal, the exact z^2 infinite, or within rounding of it),
    z^2 is inf.
    """
    n = integers.shape[0]
    total_squared = np.square(signs @ integers)
    with np.errstate(divide="ignore"):
        return (n - 1) * total_squared / np.maximum(n * squares - total_squared, 0.0)


def _statistics(z_squared):
    """chi^2 per bin (``order_free_mean``) and the largest z^2 of each row of z^2."""
    return order_free_mean(z_squared), z_squared.max(axis=-1)


def sign_flip_test(deviations, flips=SIGN_FLIPS, seed=SIGN_FLIP_SEED):
    """The sign-flip test of shard-level deviations from a prediction.

    chi^2 per bin of the deviations, and the p-values of chi^2 and of the largest z^2 against
    their sign-flip null distributions.

    Parameters
    ----------
    deviations : array_like, shape (shards, bins)
        Each shard's deviation from the prediction: its estimate minus the prediction (shards
        of equal time) or its share of the merged estimate's deviation
        (``ratio_deviations``); finite, shards >= 2, bins >= 1, and in every bin the shards'
        deviations must differ by more than the rounding of their sum (else z has no
        scatter to be measured against).
    flips : int
        How many random sign patterns are drawn, >= 1.
    seed : int
        Seed of ``numpy.random.default_rng`` for the signs.

    Returns
    -------
    chi2_per_bin, p_chi2, p_worst : float
        z of a bin is the deviations' mean over its standard error from the scatter between
        the shards (the jackknife's, for a mean over shards); chi2_per_bin is the mean of z^2
        over the bins.  The null takes the shards as independent and each shard's deviation
        vector as symmetric about 0; then flipping the signs of whole shards leaves the joint
        distribution unchanged: the flipped statistics are the null distribution, and it
        carries the correlations between bins (shared shards, the normalisation, cascades of
        collisions filling neighbouring bins).  Independence gives a zero mean, not symmetry:
        where a shard's deviation is skewed (rare bins fed by cascades, a few shards holding
        most of a bin's content) the null is approximate, the more so the fewer the shards and
        the rarer the bin, and the worst-bin p more than the chi^2 p.

        p = (1 + the number of flipped statistics >= the observed one) / (1 + flips): a
        flipped statistic equal to the observed one counts.  Every sum over shards is exact
        (each bin's deviations are first rounded to integers of at most 52 - ceil(log2
        shards) bits, a change of the size of a float sum's rounding), so statistics whose
        z^2 agree bin by bin in exact arithmetic have the same bits and tie: flipping every
        sign leaves z^2 alone, so the all-flipped pattern ties with the observed statistic
        and counts, and so do patterns that differ only on shards with equal or zero
        deviations.  With n shards there are 2^(n - 1) distinct statistics and p is never much
        below 2^(1 - n).

        The same deviations give the same bits on every machine, for any BLAS kernel and
        thread count (the sums are exact), and for any order of the bins (the mean over bins
        is ``order_free_mean``); the signs come from the seeded PCG64.

    Raises
    ------
    ValueError
        Where ``deviations`` is not a finite (shards >= 2, bins >= 1) array, a bin's
        deviations agree to within rounding, or ``flips`` is not an integer >= 1.

    Examples
    --------
    Two bins, deviations of alternating sign over four shards: no deviation on average.

    >>> import numpy as np
    >>> from bouncing_ball.comparison import sign_flip_test
    >>> deviations = np.array([[1.0, 0.5], [-1.0, -0.5], [1.0, -0.5], [-1.0, 0.5]])
    >>> chi2, p_chi2, p_worst = sign_flip_test(deviations)
    >>> print(chi2, p_chi2, p_worst)
    0.0 1.0 1.0
    """
    deviations = np.asarray(deviations, dtype=float)
    if deviations.ndim != 2 or deviations.shape[0] < 2 or deviations.shape[1] < 1:
        raise ValueError(
            f"deviations: need a (shards, bins) array with shards >= 2 and bins >= 1, "
            f"got shape {deviations.shape}"
        )
    if not np.all(np.isfinite(deviations)):
        raise ValueError("deviations: need finite values")
    if isinstance(flips, bool) or not isinstance(flips, numbers.Integral) or flips < 1:
        raise ValueError(f"flips: need an integer >= 1, got {flips!r}")
    flips = int(flips)
    n = deviations.shape[0]
    integers = _integer_deviations(deviations)
    squares = np.zeros(integers.shape[1])
    for shard in integers:  # a fixed order: the same bits on every machine
        squares += shard * shard
    total_squared = np.square(integers.sum(axis=0))  # exact
    # n S - T^2 is exact up to (n + 2) u n S: below that z^2 is not resolved
    unresolved = np.flatnonzero(
        n * squares - total_squared <= (n + 2) * _UNIT_ROUNDOFF * n * squares
    )
    if len(unresolved):
        raise ValueError(
            f"deviations: in bin(s) {unresolved.tolist()} the shards' deviations agree to "
            "within rounding: no scatter between the shards to measure z against"
        )
    chi2, worst = _statistics(_z_squared(np.ones((1, n)), integers, squares))
    rng = np.random.default_rng(seed)
    chi2_above = worst_above = 0
    for block in range(0, flips, _FLIPS_PER_BLOCK):
        signs = rng.choice([-1.0, 1.0], size=(min(_FLIPS_PER_BLOCK, flips - block), n))
        chi2_null, worst_null = _statistics(_z_squared(signs, integers, squares))
        chi2_above += int(np.sum(chi2_null >= chi2))
        worst_above += int(np.sum(worst_null >= worst))
    return float(chi2[0]), (1 + chi2_above) / (1 + flips), (1 + worst_above) / (1 + flips)


def ratio_deviations(numerators, denominators, reference):
    """Each shard's share of the deviation of a ratio estimate from a reference.

    For the estimate sum_k numerators_k / sum_k denominators_k the share of shard k is
    (numerators_k - reference x denominators_k) / sum_k denominators_k.  The shares add up to
    the estimate minus the reference; to first order they are what the delete-one jackknife
    sees of each shard, so ``sign_flip_test`` of them gives the merged table's z to first
    order.

    Parameters
    ----------
    numerators, denominators : array_like, shape (shards, bins)
        Each shard's numerator and denominator (``shard_ratios``).
    reference : array_like, shape (bins,)
        The prediction.

    Returns
    -------
    numpy.ndarray, shape (shards, bins)

    Examples
    --------
    >>> from bouncing_ball.comparison import ratio_deviations
    >>> shares = ratio_deviations([[3.0], [5.0]], [[1.0], [3.0]], [1.5])
    >>> print(shares.ravel(), shares.sum(), 8.0 / 4.0 - 1.5)
    [0.375 0.125] 0.5 0.5
    """
    numerators = np.asarray(numerators, dtype=float)
    denominators = np.asarray(denominators, dtype=float)
    return (numerators - np.asarray(reference, dtype=float) * denominators) / denominators.sum(
        axis=0
    )


def shard_ratios(shards) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each shard's numerator and denominator of the estimates the validation checks.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards of one r (with the same bins).

    Returns
    -------
    dict
        Keyed as the merged tables' columns, each a pair of (shards x bins) arrays, bins as
        in the merged tables: ``p0v``, the collisions over the time times int_bin v dv
        (eq. (collrate), ``histograms.outgoing_speed_density``); ``px``, the time spent in
        the x bin over the time times the bin's width; ``v2_given_x``, the integral of
        v^2 dt in the bin over the time spent there (eq. (moment2)).
    """
    from .histograms import outgoing_speed_density

    speeds, heights = shards[0].speed_bins, shards[0].position_bins
    times = np.array([s.time for s in shards], dtype=float)[:, None]
    in_bin = np.stack([s.position_time for s in shards])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        per_speed = 1.0 / outgoing_speed_density(1.0, 1.0, speeds.lower, speeds.upper)
        return {
            "p0v": (np.stack([s.speed_counts for s in shards]), times * per_speed),
            "px": (in_bin, times * (heights.upper - heights.lower)),
            "v2_given_x": (np.stack([s.position_v2_time for s in shards]), in_bin),
        }


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
        p0v_err / p0v over the bins with 0.01 <= v <= 5 (an empty bin there counts as an
        infinite relative error): these ``p0v_*`` rows of the plain counts, with the
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
    low, high = QUALITY_SPEEDS
    quality = simulated[(simulated.v >= low) & (simulated.v <= high)]
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.where(
            (quality.p0v > 0.0) & np.isfinite(quality.p0v_err),
            quality.p0v_err / quality.p0v,
            np.inf,
        )
    if len(relative):
        k = _largest(relative, quality.v.to_numpy())
        largest, at = float(relative[k]), float(quality.v.iloc[k])
    else:
        largest, at = np.nan, np.nan
    rows.append(
        {
            "check": f"{quantity}_largest_relative_error",
            "reference": "none",
            "bins": len(relative),
            "value": largest,
            "bin_centre": at,
            "p_sign_flip": np.nan,
            "detail": f"max of p0v_err / p0v over the bins with {low:g} <= v <= {high:g}, "
            f"at v = {_number(at, 3)}"
            + (
                f"; {empty} of them without a collision (an infinite relative error: the run "
                "is too short there)"
                if (empty := int(np.sum(~np.isfinite(relative))))
                else ""
            ),
        }
    )
    return rows


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
    from . import exact

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


def fit_checks(fits):
    """The free-exponent fits of the asymptotic forms to the simulated P(0, v), as checks.

    Per window (small v, eqs. (asym1), (asym2); large v, eqs. (asym3)-(asym6)) the joint
    p-value of the theory's exponents (Hotelling's T^2 on the jackknife covariance) and the
    fit's chi^2 per degree of freedom (per-bin errors only: indicative, it ignores the
    correlations between bins).

    Parameters
    ----------
    fits : pandas.DataFrame
        A fits table (``fits.asymptotic_fits``).

    Returns
    -------
    list of dict
        Two rows per window, without r; a window without a usable fit gives NaN values.
    """
    from .fits import LARGE_SPEED, SMALL_SPEED

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
            for row in exponents.itertuples()
        )
        dof = int(first.dof) if np.isfinite(first.dof) else 0
        bins = dof + len(window) if dof > 0 else 0
        where = (
            f"v in [{_number(first.v_min, 3)}, {_number(first.v_max, 3)}]"
            if np.isfinite(first.v_min)
            else "no usable window"
        )
        joint = float(first.joint_p_value)
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
                "detail": f"{where}; {fitted}",
            },
            {
                "check": f"{side}_fit_chi2_per_dof",
                "reference": "fit",
                "bins": bins,
                "value": float(first.chi2_per_dof),
                "bin_centre": np.nan,
                "p_sign_flip": np.nan,
                "detail": f"{where}; {dof} degrees of freedom; indicative: the bins are "
                "correlated (the joint p-value is the test)",
            },
        ]
    return rows


def validation_rows(
    label, restitution, p0v, position, fits, shards, solver_curve=None, per_shard=None
) -> list[dict]:
    """Every check of one r: ``outgoing_speed_checks``, ``position_checks``, ``fit_checks``.

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

    Returns
    -------
    list of dict
        The rows, each with the r label and r.
    """
    rows = [
        *outgoing_speed_checks(p0v, restitution, shards, solver_curve, per_shard),
        *position_checks(position, restitution, shards, per_shard),
        *fit_checks(fits),
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


def _shown_value(check, value):
    if not np.isfinite(value):
        return "inf" if value == np.inf else ""
    if check.endswith("relative_error"):
        percent = 100.0 * value
        return f"{percent:.0f}%" if percent >= 10.0 else f"{percent:.2g}%"
    if check.endswith("worst_bin"):
        return f"{value:+.2f}"
    return f"{value:.3g}"


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
            "check": table.check.map(VALIDATION_CHECKS),
            "reference": table.reference,
            "bins": table.bins.astype(str),
            "value": [_shown_value(c, v) for c, v in zip(table.check, table.value)],
            "at v or x": table.bin_centre.map(lambda value: _number(value, 3)),
            "p_sign_flip": table.p_sign_flip.map(lambda value: _number(value, 2)),
            "detail": table.detail,
        }
    )
    return shown.to_markdown(index=False, disable_numparse=True) + "\n"


# ---- the asymptotics of P(x) for any r (results/tables/position_asymptotics) ----

POSITION_EXPONENTS = {
    "small_x_power": "P(x) - P(0) or P(x) ~ x^a, x -> 0: a = (1 - beta)/3",
    "small_x_power_at_zero_speed": "P(x, 0) ~ x^a, x -> 0: a = -beta/3",
    "large_x_rate": "P(x) ~ x^c exp(-b x^(1/2)), x -> inf: b",
    "large_x_power": "P(x) ~ x^c exp(-b x^(1/2)), x -> inf: c",
}


def position_asymptotics_table(summaries) -> pd.DataFrame:
    """The exponents of P(x) at small and large x, measured and predicted, for each r.

    Parameters
    ----------
    summaries : iterable of (str, mapping)
        The r label and the solver's summary row (with ``<exponent>_measured``, from the
        solver's P(x) of eq. (P(x)1), and ``<exponent>_predicted``, docs/distribution.md).

    Returns
    -------
    pandas.DataFrame
        One row per r and exponent of ``POSITION_EXPONENTS``: r_label, r, exponent, meaning,
        measured, predicted, difference.
    """
    rows = []
    for label, summary in summaries:
        for exponent, meaning in POSITION_EXPONENTS.items():
            measured = float(summary[f"{exponent}_measured"])
            predicted = float(summary[f"{exponent}_predicted"])
            rows.append(
                {
                    "r_label": label,
                    "r": float(summary["r"]),
                    "exponent": exponent,
                    "meaning": meaning,
                    "measured": measured,
                    "predicted": predicted,
                    "difference": measured - predicted,
                }
            )
    return pd.DataFrame(rows)


def position_asymptotics_markdown(table: pd.DataFrame) -> str:
    """The exponents of P(x) for a reader, as results/tables/position_asymptotics.md.

    Parameters
    ----------
    table : pandas.DataFrame
        The table of ``position_asymptotics_table``.

    Returns
    -------
    str
        A Markdown table and a note on how the exponents are measured.
    """
    shown = pd.DataFrame(
        {
            "r": table.r_label,
            "exponent": table.meaning,
            "measured (solver's P(x))": table.measured.map(lambda value: f"{value:.6f}"),
            "predicted": table.predicted.map(lambda value: f"{value:.6f}"),
            "difference": table.difference.map(lambda value: f"{value:+.1e}"),
        }
    )
    note = (
        "\nSmall x: local slopes at x ~ 1e-7, with corrections of relative order "
        "x^((beta - 1)/3) for 1 < beta < 2 and x^(1/3) otherwise (so the differences shrink "
        "slowly as x -> 0: x^(1/6) = 0.07 at x = 1e-7 and r = 1/3); at r = 1/2 (beta = 1) P(x) ~ -ln x, whose "
        "local slope goes to 0 only like 1/ln x. Large x: a fit of ln P(x) over the window where "
        "w(F) is computed (docs/distribution.md).\n"
    )
    return shown.to_markdown(index=False, disable_numparse=True) + "\n" + note


# ---------------------------------------------------------------------------------------------
# an equilibrium object against a simulation's result, for a notebook

#: The scalars ``compare`` holds against the equilibrium, with their symbols.
COMPARED_SCALARS = {
    "mean_x": "<x>",
    "delta_x": "Delta x",
    "collision_rate": "I",
    "mean_flight_time": "<T>",
    "flight_time_second_moment": "<T^2>",
}
#: The columns of ``compare``'s table.
COMPARE_COLUMNS = (
    "quantity",
    "estimator",
    "equilibrium",
    "simulation",
    "simulation_err",
    "z",
    "dof",
    "bins",
    "chi2_per_bin",
    "p_sign_flip",
)


def _scalar_rows(equilibrium, summary, dof):
    """The rows of ``compare`` of the scalars: plain, martingale-controlled (independent of the
    theory: the estimate that judges agreement) and controlled (with eq. (kernel3) where the
    summary's ``kernel3_controls`` says so), each where finite."""
    rows = []
    for quantity in COMPARED_SCALARS:
        reference = float(getattr(equilibrium, quantity))
        for estimator, column in (
            ("plain", quantity),
            ("martingale", f"{quantity}_martingale"),
            ("controlled", f"{quantity}_controlled"),
        ):
            if column not in summary:
                continue
            value, error = float(summary[column]), float(summary[f"{column}_err"])
            if not (np.isfinite(value) and np.isfinite(error) and error > 0.0):
                continue
            rows.append(
                {
                    "quantity": quantity,
                    "estimator": estimator,
                    "equilibrium": reference,
                    "simulation": value,
                    "simulation_err": error,
                    "z": (value - reference) / error if np.isfinite(reference) else np.nan,
                    "dof": dof,
                }
            )
    return rows


def _table_row(quantity, simulated, errors, reference, deviations):
    """The row of ``compare`` of one table: chi^2 per bin of z = (simulation - reference) /
    error (``order_free_mean``) and the sign-flip p of the shards' ``deviations``."""
    z = (simulated - reference) / errors
    return {
        "quantity": quantity,
        "estimator": "plain",
        "bins": len(z),
        "chi2_per_bin": float(order_free_mean(np.square(z))) if len(z) else np.nan,
        "p_sign_flip": sign_flip_test(deviations)[1] if len(z) else np.nan,
    }


def compare(equilibrium, result) -> pd.DataFrame:
    """A simulation held against an equilibrium object, as the validation table holds it.

    The z of every scalar, and the chi^2 per bin and sign-flip p of each table.

    The two must be in the same units (``units``, of ``Equilibrium(r, gravity=, noise=)`` and
    ``simulate(..., gravity=, noise=)``); the scalars' columns are in them.

    The scalars <x>, Delta x, I, <T>, <T^2> (eqs. (xandDeltax), (collrate), (meanT),
    (meanT2)), plain, martingale-controlled (``independent_estimate``: the one that judges
    agreement) and controlled with eq. (kernel3), each where the result has a finite estimate:
    z = (simulation - equilibrium) / simulation_err, the error the delete-one jackknife's
    over the shards, so z has a Student t law with at most ``dof`` = shards - 1 degrees of
    freedom (fewer after the control fits).

    The tables P(0, v), P(x) and <v^2>_x, each bin against the equilibrium's average over it
    (``EquilibriumBase.p0v_bin_average``, ``px_bin_average``, ``v2_given_x_bin_average``),
    over the bins the validation table uses: those with a finite error > 0, for P(0, v) not
    the under- and overflow bins, for P(x) and <v^2>_x inside ``POSITION_RANGE``.  chi^2 per
    bin is the mean of z^2 (the bins are correlated, so it need not be near 1); p_sign_flip is
    ``sign_flip_test`` of the shards' shares of the deviation (``ratio_deviations`` of
    ``shard_ratios``), which carries those correlations.  P(x) and <v^2>_x only where the
    equilibrium computes them (``distribution_available``).

    Parameters
    ----------
    equilibrium : EquilibriumBase
        ``Equilibrium(r)`` or ``ExactEquilibrium(r)``, of the result's r.
    result : SimulationResult
        ``simulate``'s result, with at least 2 shards.

    Returns
    -------
    pandas.DataFrame
        Columns ``COMPARE_COLUMNS``: one row per scalar and estimator (quantity, estimator,
        equilibrium, simulation, simulation_err, z, dof) and one per table (quantity p0v, px,
        v2_given_x; bins, chi2_per_bin, p_sign_flip); NaN where a column does not apply.

    Raises
    ------
    ValueError
        If the two are of different r or units, or the result has fewer than 2 shards.

    Examples
    --------
    >>> import bouncing_ball as bb
    >>> sim = bb.simulate(0.5, shards=4, shard_time=500.0, seed=2, progress=False)
    >>> table = bb.compare(bb.ExactEquilibrium("1/2"), sim)
    >>> table.loc[table.estimator == "plain", "quantity"].tolist()
    ['mean_x', 'delta_x', 'collision_rate', 'mean_flight_time', 'flight_time_second_moment', 'p0v', 'px', 'v2_given_x']
    >>> print(table.dof.max())
    3
    """
    if Fraction(equilibrium.restitution) != Fraction(result.restitution):
        raise ValueError(
            f"result: simulated at r = {result.restitution}, the equilibrium is at "
            f"r = {equilibrium.restitution}"
        )
    if equilibrium.units != result.units:
        raise ValueError(
            f"result: simulated in {result.units}, the equilibrium is in {equilibrium.units}; "
            "give both the same gravity and noise"
        )
    if result.shards < 2:
        raise ValueError(f"result: needs at least 2 shards for errors, got {result.shards}")
    shards = list(result.tallies)
    per_shard = shard_ratios(shards)
    rows = _scalar_rows(equilibrium, result.summary_table.iloc[0], result.shards - 1)

    # the tables in the paper's units, as the shards' tallies are (their rows have no dimension)
    equilibrium = equilibrium._paper_twin()
    p0v = result._p0v_paper
    usable = (
        (p0v.v_lo >= max(equilibrium.smallest_speed, np.finfo(float).tiny))
        & np.isfinite(p0v.v_hi)
        & np.isfinite(p0v.p0v_err)
        & (p0v.p0v_err > 0.0)
    ).to_numpy()
    bins = p0v[usable]
    reference = np.atleast_1d(
        equilibrium.p0v_bin_average(bins.v_lo.to_numpy(), bins.v_hi.to_numpy())
    )
    deviations = _shard_deviations(
        per_shard, "p0v", np.flatnonzero(usable), reference, result.shards
    )
    rows.append(
        _table_row("p0v", bins.p0v.to_numpy(), bins.p0v_err.to_numpy(), reference, deviations)
    )

    if equilibrium.distribution_available:
        position = result._position_paper
        low, high = POSITION_RANGE
        inside = (
            (position.x_lo >= low * (1.0 - 1e-9))
            & (position.x_hi <= high * (1.0 + 1e-9))
            & np.isfinite(position.x_hi)
        )
        for quantity, bin_average in (
            ("px", equilibrium.px_bin_average),
            ("v2_given_x", equilibrium.v2_given_x_bin_average),
        ):
            error = position[f"{quantity}_err"]
            compared = (inside & np.isfinite(error) & (error > 0.0)).to_numpy()
            bins = position[compared]
            reference = np.atleast_1d(bin_average(bins.x_lo.to_numpy(), bins.x_hi.to_numpy()))
            deviations = _shard_deviations(
                per_shard, quantity, np.flatnonzero(compared), reference, result.shards
            )
            rows.append(
                _table_row(
                    quantity,
                    bins[quantity].to_numpy(),
                    bins[f"{quantity}_err"].to_numpy(),
                    reference,
                    deviations,
                )
            )
    return pd.DataFrame(rows, columns=list(COMPARE_COLUMNS)).astype(
        {"dof": "Int64", "bins": "Int64"}
    )
