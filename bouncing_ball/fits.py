"""Fits of the asymptotic forms of P(0, v) to binned data, eqs. (asym1), (asym3).

Small v: P(0, v) = A v^-beta, eqs. (asym1), (asym2).
Large v: P(0, v) = A v^-m e^(-q v), eqs. (asym3)-(asym6).

The data are bin averages, int_bin v P dv / int_bin v dv (what the simulation
measures, eq. (collrate)), so the model is averaged over each bin the same
way (Gauss-Legendre in ln v), not evaluated at a bin centre.  Fits are
weighted least squares with the data's standard errors, taken as absolute:

  * fixed exponents (the theory's): only the prefactor, a linear fit;
  * free exponents: beta, or m and q, with the prefactor, by
    ``scipy.optimize.curve_fit``; errors from its covariance.

Errors of fitted parameters.  Low-speed collisions come in cascades that fill
neighbouring bins together, so bins are correlated and the least-squares
covariance (which assumes independent bins) understates the errors.  The
errors here are delete-one jackknife errors over shards of the whole fit
(the weights stay those of the full data).  95% intervals are value +-
t(0.975, shards - 1) error (on ln A for the prefactor); for free exponents the
theory's values are also tested together (Hotelling's T^2 on the jackknife
covariance: m and q are strongly anticorrelated, so two marginal intervals
say less than the joint test).  chi^2 per degree of freedom uses the per-bin
errors only and is indicative: it ignores the correlations between bins.

The window.  An asymptotic form holds only approximately at finite v: fitted
to the solver's noise-free P(0, v) its free exponents drift away from the
theory's as the window reaches in (by ~0.1 in m at v ~ 2 for r = 0.25).
The default window is the largest run of usable bins that starts at the
smallest (small v) or ends at the largest (large v) one and over which that
drift, for every free exponent, is at most ``max_bias`` times the data's
statistical error on it: there the form's own inexactness is small beside
the noise, and a fit of the data tests the theory.
"""

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import optimize, special  # not scipy.stats: half a second to import, in every job
from scipy.interpolate import CubicSpline

from .asymptotics import large_speed_decay_rate, large_speed_exponent, small_speed_exponent
from .bins import outgoing_speed_bin_average
from .estimators import outgoing_speed_density

__all__ = [
    "SMALL_SPEED",
    "LARGE_SPEED",
    "WindowError",
    "FitError",
    "small_speed_form",
    "large_speed_form",
    "theory_exponents",
    "bin_average",
    "AsymptoticFit",
    "fit_asymptotic_form",
    "fit_shards",
    "interval_factor",
    "asymptotic_window",
    "window_from_range",
    "fit_rows",
    "asymptotic_fits",
    "usable_curve",
    "bin_averages_of_curve",
    "fit_errors",
    "expected_collisions",
    "FitBins",
    "select_fit_bins",
]

#: The small-v side: P(0, v) = A v^-beta, eqs. (asym1), (asym2).
SMALL_SPEED = "small_speed"
#: The large-v side: P(0, v) = A v^-m e^(-q v), eqs. (asym3)-(asym6).
LARGE_SPEED = "large_speed"


class WindowError(ValueError):
    """No window on one side holds enough usable bins for a fit."""


class FitError(ValueError):
    """A fit of free exponents finds no optimum (``scipy.optimize.curve_fit`` gives up)."""


def small_speed_form(v, log_prefactor, beta):
    """The small-speed form A v^-beta of P(0, v), eq. (asym1).

    Parameters
    ----------
    v : array_like
        Speeds, > 0.
    log_prefactor : float
        ln A.
    beta : float
        The exponent (the theory's: eq. (asym2)).

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> from bouncing_ball.fits import small_speed_form
    >>> print(small_speed_form([0.25, 1.0], 0.0, 1.5))
    [8. 1.]
    """
    return np.exp(log_prefactor - beta * np.log(v))


def large_speed_form(v, log_prefactor, m, q):
    """The large-speed form A v^-m e^(-q v) of P(0, v), eq. (asym3).

    Parameters
    ----------
    v : array_like
        Speeds, > 0.
    log_prefactor : float
        ln A.
    m, q : float
        The power and the decay rate (the theory's: eqs. (asym4)-(asym6)).

    Returns
    -------
    numpy.ndarray
    """
    return np.exp(log_prefactor - m * np.log(v) - q * v)


FORMS = {SMALL_SPEED: small_speed_form, LARGE_SPEED: large_speed_form}
EXPONENT_NAMES = {SMALL_SPEED: ("beta",), LARGE_SPEED: ("m", "q")}


def theory_exponents(side, restitution):
    """The theory's exponents of the asymptotic form on one side.

    Parameters
    ----------
    side : str
        ``SMALL_SPEED`` or ``LARGE_SPEED``.
    restitution : float
        r, in (0, 1).

    Returns
    -------
    tuple of float
        (beta,) of eq. (asym2), or (m, q) of eqs. (asym4)-(asym6).

    Examples
    --------
    >>> from bouncing_ball.fits import LARGE_SPEED, theory_exponents
    >>> theory_exponents(LARGE_SPEED, 0.25)
    (1.5, 2.0)
    """
    if side == SMALL_SPEED:
        return (small_speed_exponent(restitution),)
    return (large_speed_exponent(restitution), large_speed_decay_rate(restitution))


def bin_average(form, lower, upper, *parameters):
    """The bin averages of a form of P(0, v), as the simulation measures them (eq. (collrate)).

    Parameters
    ----------
    form : callable
        ``form(v, *parameters)``, e.g. ``small_speed_form``.
    lower, upper : array_like
        The bins' edges, 0 < lo < hi.
    *parameters
        The form's parameters after v.

    Returns
    -------
    numpy.ndarray
        ``bins.outgoing_speed_bin_average`` of the form in each bin.
    """
    return outgoing_speed_bin_average(lambda v: form(v, *parameters), lower, upper)


@dataclass(frozen=True)
class AsymptoticFit:
    """One fit of an asymptotic form of P(0, v).

    Parameters
    ----------
    side : str
        ``SMALL_SPEED`` or ``LARGE_SPEED``.
    free : bool
        Whether the exponents were fitted (else the theory's, fixed).
    parameters : dict
        Name -> value: "prefactor" (A) and the exponents ("beta", or "m" and "q").
    errors : dict
        Name -> standard error (0 for a fixed exponent).
    chi2 : float
        chi^2 of the fit with the per-bin errors.
    dof : int
        Its degrees of freedom.
    lower, upper : float
        The window: the lowest and highest bin edge fitted.
    joint_p_value : float
        p-value of the theory's exponents taken together, Hotelling's T^2 on the jackknife
        covariance (NaN where not computed).

    Attributes
    ----------
    chi2_per_dof : float
        chi^2 / dof (NaN without degrees of freedom).
    """

    side: str
    free: bool
    parameters: dict  # name -> value: "prefactor" and the exponents
    errors: dict  # name -> standard error (0 for a fixed exponent)
    chi2: float
    dof: int
    lower: float  # window
    upper: float
    # p-value of the theory's exponents jointly, Hotelling's T^2 on the jackknife covariance
    joint_p_value: float = np.nan

    @property
    def chi2_per_dof(self):
        """chi^2 per degree of freedom (NaN without degrees of freedom)."""
        return self.chi2 / self.dof if self.dof > 0 else np.nan


def fit_asymptotic_form(side, lower, upper, values, errors, restitution, free):
    """Weighted least-squares fit of an asymptotic form to bin averages of P(0, v).

    The model is averaged over each bin like the data (``bin_average``).  With fixed
    exponents only the prefactor is fitted (linear); with free ones, the exponents too, by
    ``scipy.optimize.curve_fit`` from the theory's values, with errors from its covariance.

    Parameters
    ----------
    side : str
        ``SMALL_SPEED`` (eq. (asym1)) or ``LARGE_SPEED`` (eq. (asym3)).
    lower, upper : array_like
        The bins' edges.
    values, errors : array_like
        The bin averages and their standard errors (taken as absolute).
    restitution : float
        r: the theory's exponents, fixed or the start.
    free : bool
        Whether the exponents are fitted.

    Returns
    -------
    AsymptoticFit

    Raises
    ------
    FitError
        If the free-exponent fit finds no optimum, naming the side and the window.

    Examples
    --------
    Exact bin averages of 2 v^-1 at r = 1/2 (beta = 1) give the prefactor back:

    >>> import numpy as np
    >>> from bouncing_ball.fits import SMALL_SPEED, fit_asymptotic_form
    >>> lower, upper = np.array([0.01, 0.02, 0.04]), np.array([0.02, 0.04, 0.08])
    >>> values = 2.0 * 2.0 / (lower + upper)
    >>> fit = fit_asymptotic_form(SMALL_SPEED, lower, upper, values, 0.01 * values, 0.5, True)
    >>> print(round(fit.parameters["prefactor"], 6), round(fit.parameters["beta"], 6))
    2.0 1.0
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    values, errors = np.asarray(values, dtype=float), np.asarray(errors, dtype=float)
    form = FORMS[side]
    theory = theory_exponents(side, restitution)
    names = EXPONENT_NAMES[side]
    shape = bin_average(form, lower, upper, 0.0, *theory)
    weights = 1.0 / errors**2
    # fixed exponents: the prefactor is linear
    prefactor = np.sum(weights * values * shape) / np.sum(weights * shape**2)
    if not free:
        residual = (values - prefactor * shape) / errors
        return AsymptoticFit(
            side,
            False,
            {"prefactor": prefactor, **dict(zip(names, theory))},
            {"prefactor": 1.0 / np.sqrt(np.sum(weights * shape**2)), **dict.fromkeys(names, 0.0)},
            float(np.sum(residual**2)),
            len(values) - 1,
            float(lower[0]),
            float(upper[-1]),
        )
    start = (np.log(prefactor), *theory)
    try:
        best, covariance = optimize.curve_fit(
            lambda _, *p: bin_average(form, lower, upper, *p),
            np.zeros(len(values)),
            values,
            p0=start,
            sigma=errors,
            absolute_sigma=True,
            maxfev=20000,
        )
    except (RuntimeError, ValueError) as error:  # no optimum, or a NaN on the way
        raise FitError(
            f"{side} fit of free exponents over v in [{lower[0]:.3g}, {upper[-1]:.3g}] "
            f"({len(values)} bins) finds no optimum: {error}"
        ) from None
    spread = np.sqrt(np.diag(covariance))
    residual = (values - bin_average(form, lower, upper, *best)) / errors
    return AsymptoticFit(
        side,
        True,
        {"prefactor": float(np.exp(best[0])), **dict(zip(names, map(float, best[1:])))},
        {
            "prefactor": float(np.exp(best[0]) * spread[0]),
            **dict(zip(names, map(float, spread[1:]))),
        },
        float(np.sum(residual**2)),
        len(values) - len(best),
        float(lower[0]),
        float(upper[-1]),
    )


def _parameter_vector(fit):
    names = ("prefactor", *EXPONENT_NAMES[fit.side])
    return np.array([fit.parameters[n] for n in names])


def fit_shards(side, lower, upper, counts, times, errors, restitution, free):
    """The fit of the shards' pooled P(0, v), with delete-one jackknife errors over shards.

    For free exponents also the p-value of the theory's exponents taken together:
    Hotelling's T^2 = d' C^-1 d with C the jackknife covariance of the fitted
    exponents, (n - p) T^2 / (p (n - 1)) ~ F(p, n - p) for n shards and p exponents.

    Parameters
    ----------
    side : str
        ``SMALL_SPEED`` or ``LARGE_SPEED``.
    lower, upper : array_like
        The bins' edges.
    counts : array_like, shape (shards, bins)
        Each shard's collisions per bin.
    times : array_like, shape (shards,)
        Each shard's recorded time.
    errors : array_like
        The per-bin standard errors that weight the fit (those of the full data, for every
        jackknife fit).
    restitution : float
        r.
    free : bool
        Whether the exponents are fitted.

    Returns
    -------
    AsymptoticFit
        The fit of the pooled data, with the jackknife errors and, for free exponents,
        ``joint_p_value``.

    Raises
    ------
    ValueError
        With fewer than 2 shards, or an error that is not finite and positive.
    FitError
        If a free-exponent fit (of the pooled data or of a shard left out) finds no optimum.
    """
    counts = np.asarray(counts, dtype=float)
    times = np.asarray(times, dtype=float)
    shards = len(times)
    if shards < 2:
        raise ValueError(f"{side} fit: {shards} shard; errors need at least 2 (simulation.shards)")
    if not np.all(np.isfinite(errors) & (errors > 0)):
        raise ValueError(f"{side} fit: every bin needs a finite positive error")

    def fitted(count_sum, time_sum):
        values = outgoing_speed_density(count_sum, time_sum, lower, upper)
        return fit_asymptotic_form(side, lower, upper, values, errors, restitution, free)

    fit = fitted(counts.sum(axis=0), times.sum())
    leave_one_out = np.stack(
        [
            _parameter_vector(fitted(counts.sum(axis=0) - counts[k], times.sum() - times[k]))
            for k in range(shards)
        ]
    )
    spread = leave_one_out - leave_one_out.mean(axis=0)
    covariance = (shards - 1) / shards * spread.T @ spread
    names = ("prefactor", *EXPONENT_NAMES[side])
    errors_out = {
        n: float(np.sqrt(covariance[i, i])) if free or n == "prefactor" else 0.0
        for i, n in enumerate(names)
    }
    joint = np.nan
    if free:
        exponents = len(names) - 1
        deviation = _parameter_vector(fit)[1:] - np.array(theory_exponents(side, restitution))
        exponent_covariance = covariance[1:, 1:]
        # a singular covariance (shards whose exponents do not scatter: a window of too few
        # bins or counts) allows no joint test
        if shards > exponents and np.linalg.matrix_rank(exponent_covariance) == exponents:
            t_squared = float(deviation @ np.linalg.solve(exponent_covariance, deviation))
            statistic = (shards - exponents) * t_squared / (exponents * (shards - 1))
            joint = _f_survival(statistic, exponents, shards - exponents)
    return AsymptoticFit(
        side, free, fit.parameters, errors_out, fit.chi2, fit.dof, fit.lower, fit.upper, joint
    )


def _f_survival(statistic, numerator, denominator) -> float:
    """P(F > statistic) of Snedecor's F distribution (``scipy.stats.f.sf``: its support starts
    at 0)."""
    return 1.0 if statistic < 0.0 else float(special.fdtrc(numerator, denominator, statistic))


def interval_factor(shards, level=0.95):
    """The Student t factor of a two-sided interval from a jackknife over shards.

    Parameters
    ----------
    shards : int
        The number of shards (shards - 1 degrees of freedom).
    level : float
        The interval's probability.

    Returns
    -------
    float
        ``scipy.stats.t.ppf(0.5 + level / 2, shards - 1)``.

    Examples
    --------
    >>> from bouncing_ball.fits import interval_factor
    >>> print(round(interval_factor(10), 6), round(interval_factor(10**6), 4))
    2.262157 1.96
    """
    return float(special.stdtrit(shards - 1, 0.5 + level / 2.0))


def asymptotic_window(
    side, lower, upper, counts, times, errors, reference, restitution, max_bias=0.5, minimum_bins=4
):
    """The default window on one side, as a slice of the usable bins.

    The largest run of bins from the outermost one on that side over which the solver's
    noise-free P(0, v), fitted with free exponents, drifts from the theory's exponents by at
    most ``max_bias`` times the data's jackknife error on them (see the module's account).

    Parameters
    ----------
    side : str
        ``SMALL_SPEED`` (the run starts at the lowest bin) or ``LARGE_SPEED`` (it ends at the
        highest).
    lower, upper : numpy.ndarray
        The usable bins' edges.
    counts, times : numpy.ndarray
        The shards' collisions per bin (shards x bins) and recorded times.
    errors : numpy.ndarray
        The per-bin standard errors.
    reference : numpy.ndarray
        Noise-free bin averages of P(0, v) (the solver's) in the same bins.
    restitution : float
        r.
    max_bias : float
        The drift allowed, in units of the data's error.
    minimum_bins : int
        The fewest bins of a window.

    Returns
    -------
    slice
        Into the usable bins.

    Raises
    ------
    WindowError
        With fewer than ``minimum_bins`` bins, or a drift too large already there, or a fit
        that finds no optimum there (a larger window whose fit finds none ends the run).
    """
    count = len(lower)
    if count < minimum_bins:
        raise WindowError(f"{side} window: only {count} usable bins, {minimum_bins} needed")
    theory = np.array(theory_exponents(side, restitution))
    best, failure = None, None
    for size in range(minimum_bins, count + 1):
        window = slice(0, size) if side == SMALL_SPEED else slice(count - size, count)
        parts = (lower[window], upper[window])
        try:
            drift = (
                _parameter_vector(
                    fit_asymptotic_form(
                        side, *parts, reference[window], errors[window], restitution, free=True
                    )
                )[1:]
                - theory
            )
            noisy = fit_shards(
                side, *parts, counts[:, window], times, errors[window], restitution, free=True
            )
        except FitError as error:  # the form cannot be fitted this far in: the window ends
            failure = error
            break
        spread = np.array([noisy.errors[name] for name in EXPONENT_NAMES[side]])
        if np.any(np.abs(drift) > max_bias * spread):
            break
        best = window
    if best is None and failure is not None:
        raise WindowError(f"{side} window: {failure}")
    if best is None:
        raise WindowError(
            f"{side} window: fitted to the solver over the {minimum_bins} outermost usable bins, the free "
            f"exponents already differ from the theory's by more than {max_bias} of the data's errors"
        )
    return best


def window_from_range(side, lower, upper, speed_range):
    """The usable bins inside a configured window.

    Parameters
    ----------
    side : str
        ``SMALL_SPEED`` or ``LARGE_SPEED``.
    lower, upper : numpy.ndarray
        The usable bins' edges.
    speed_range : dict
        The keys min and max: the window's speeds.

    Returns
    -------
    slice
        Into the usable bins.

    Raises
    ------
    WindowError
        If the window holds too few bins for the fit's parameters and one degree of freedom.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.fits import SMALL_SPEED, window_from_range
    >>> edges = np.geomspace(1e-3, 1.0, 7)
    >>> window = window_from_range(SMALL_SPEED, edges[:-1], edges[1:], {"min": 1e-3, "max": 0.1})
    >>> print(window.start, window.stop)
    0 4
    """
    inside = np.flatnonzero(
        (lower >= speed_range["min"] * (1 - 1e-12)) & (upper <= speed_range["max"] * (1 + 1e-12))
    )
    if len(inside) < 2 + len(EXPONENT_NAMES[side]):
        raise WindowError(
            f"{side} window [{speed_range['min']}, {speed_range['max']}] holds {len(inside)} usable bins, "
            f"too few for a fit of {1 + len(EXPONENT_NAMES[side])} parameters"
        )
    return slice(inside[0], inside[-1] + 1)


def fit_rows(source, fit, theory, shards=None):
    """Long-format rows of one fit, one per parameter.

    Simulation rows (``shards`` given) carry jackknife errors and 95% intervals
    (Student t; the prefactor's on ln A, so it stays positive).  Solver rows are
    noise-free: their value is what the method gives, with no error.

    Parameters
    ----------
    source : str
        "simulation" or "solver".
    fit : AsymptoticFit
        The fit.
    theory : dict
        The theory's exponents by name.
    shards : int, optional
        The number of shards of the simulation's jackknife (None: noise-free rows).

    Returns
    -------
    list of dict
        Keys source, window, fit, parameter, value, error, lower_95, upper_95, theory,
        joint_p_value, chi2_per_dof, dof, v_min, v_max.
    """
    factor = interval_factor(shards) if shards else np.nan
    rows = []
    for name, value in fit.parameters.items():
        error = fit.errors[name] if shards else np.nan
        if name == "prefactor":
            lower, upper = (
                value * np.exp(-factor * error / value),
                value * np.exp(factor * error / value),
            )
        else:
            lower, upper = value - factor * error, value + factor * error
        rows.append(
            {
                "source": source,
                "window": fit.side,
                "fit": "free_exponents" if fit.free else "fixed_exponents",
                "parameter": name,
                "value": value,
                "error": error,
                "lower_95": lower,
                "upper_95": upper,
                "theory": theory.get(name, np.nan),
                "joint_p_value": fit.joint_p_value,
                "chi2_per_dof": fit.chi2_per_dof,
                "dof": fit.dof,
                "v_min": fit.lower,
                "v_max": fit.upper,
            }
        )
    return rows


def asymptotic_fits(
    lower, upper, counts, times, errors, reference, restitution, windows, max_bias=0.5
):
    """Every asymptotic fit of P(0, v) for one r, eqs. (asym1)-(asym6), as a long table.

    Each window (small and large v), with the theory's exponents and with free ones, to the
    simulation and to the solver.

    Parameters
    ----------
    lower, upper : numpy.ndarray
        The usable bins' edges.
    counts, times : numpy.ndarray
        The simulation's collisions per usable bin (shards x bins) and the shards' times.
    errors : numpy.ndarray
        Its per-bin standard errors (the weights, see ``fit_errors``).
    reference : numpy.ndarray
        The solver's bin averages in the same bins.
    restitution : float
        r.
    windows : dict
        Each side (``SMALL_SPEED``, ``LARGE_SPEED``) to "auto" (``asymptotic_window``) or
        ``{"min": .., "max": ..}`` (``window_from_range``).
    max_bias : float
        Of ``asymptotic_window``.

    Returns
    -------
    table : pandas.DataFrame
        The rows of ``fit_rows``; a side without a usable window, or a fit that finds no
        optimum (``FitError``), gets NaN rows.
    problems : list of str
        Why a side has no window, or a fit no value.
    """
    rows, problems = [], []
    for side in (SMALL_SPEED, LARGE_SPEED):
        theory = dict(zip(EXPONENT_NAMES[side], theory_exponents(side, restitution)))
        try:
            if windows[side] == "auto":
                window = asymptotic_window(
                    side, lower, upper, counts, times, errors, reference, restitution, max_bias
                )
            else:
                window = window_from_range(side, lower, upper, windows[side])
        except WindowError as error:
            problems.append(str(error))
            for source in ("simulation", "solver"):
                for free in (False, True):
                    rows += fit_rows(source, _empty_fit(side, free), theory)
            continue
        parts = (lower[window], upper[window])
        for free in (False, True):
            for source in ("simulation", "solver"):
                try:
                    if source == "simulation":
                        fit = fit_shards(
                            side,
                            *parts,
                            counts[:, window],
                            times,
                            errors[window],
                            restitution,
                            free,
                        )
                    else:
                        fit = fit_asymptotic_form(
                            side, *parts, reference[window], errors[window], restitution, free
                        )
                except FitError as error:
                    problems.append(f"{source}: {error}")
                    fit = _empty_fit(side, free, parts[0][0], parts[1][-1])
                rows += fit_rows(
                    source, fit, theory, shards=len(times) if source == "simulation" else None
                )
    return pd.DataFrame(rows), problems


def _empty_fit(side, free, lower=np.nan, upper=np.nan):
    """An ``AsymptoticFit`` of NaN values: a side without a window, or a fit without optimum."""
    names = ("prefactor", *EXPONENT_NAMES[side])
    return AsymptoticFit(
        side,
        free,
        dict.fromkeys(names, np.nan),
        dict.fromkeys(names, np.nan),
        np.nan,
        0,
        float(lower),
        float(upper),
    )


def usable_curve(speeds, density):
    """The part of a tabulated P(0, v) that can be interpolated in logs.

    For r below ~0.035 the solver's P(0, v) ~ exp(-v / (2r)) underflows to 0 before the grid
    ends.

    Parameters
    ----------
    speeds, density : array_like
        The table's v and P(0, v).

    Returns
    -------
    speeds, density : numpy.ndarray
        Up to the first value that is not finite and positive (not included).

    Examples
    --------
    >>> from bouncing_ball.fits import usable_curve
    >>> usable_curve([1.0, 2.0, 3.0], [0.5, 1e-300, 0.0])
    (array([1., 2.]), array([5.e-001, 1.e-300]))
    """
    speeds, density = np.asarray(speeds, dtype=float), np.asarray(density, dtype=float)
    bad = np.flatnonzero(~(np.isfinite(density) & (density > 0.0)))
    end = bad[0] if len(bad) else len(density)
    return speeds[:end], density[:end]


def bin_averages_of_curve(speeds, density, lower, upper):
    """Bin averages of P(0, v) given on a dense log grid (the solver's output).

    A cubic spline of ln P in ln v, averaged like the data (``bins.outgoing_speed_bin_average``,
    eq. (collrate)); relative error ~1e-7 at 50 points per decade.

    Parameters
    ----------
    speeds, density : numpy.ndarray
        The curve (see ``usable_curve``).
    lower, upper : array_like
        The bins' edges, inside the curve's speeds.

    Returns
    -------
    numpy.ndarray
        The bin averages.

    Raises
    ------
    ValueError
        If a bin reaches beyond the curve's speeds.
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if len(lower) == 0:
        return np.empty(0)
    spline = CubicSpline(np.log(speeds), np.log(density))
    if lower.min() < speeds[0] or upper.max() > speeds[-1]:
        raise ValueError(f"bins reach beyond the curve's speeds [{speeds[0]}, {speeds[-1]}]")
    return outgoing_speed_bin_average(lambda v: np.exp(spline(np.log(v))), lower, upper)


def fit_errors(errors, reference, expected):
    """The per-bin standard errors that weight a fit.

    The jackknife's, except where it has none to give.  With few shards a bin's jackknife error can be exactly 0 (every shard put the same
    number of collisions there) or undefined; such a bin is weighted by its Poisson error
    from the collisions it should hold, ``reference / sqrt(expected)``, so that it stays in
    the fit (dropping it because of what its counts happened to be would select on the data).

    Parameters
    ----------
    errors : array_like
        The jackknife's errors per bin.
    reference : array_like
        The noise-free bin averages.
    expected : array_like
        The collisions each bin should hold (``expected_collisions``).

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.fits import fit_errors
    >>> print(fit_errors([0.1, 0.0, np.nan], [1.0, 2.0, 3.0], [100.0, 400.0, 900.0]))
    [0.1 0.1 0.1]
    """
    errors = np.array(errors, dtype=float)
    missing = ~(np.isfinite(errors) & (errors > 0.0))
    errors[missing] = np.asarray(reference, dtype=float)[missing] / np.sqrt(
        np.asarray(expected, dtype=float)[missing]
    )
    return errors


def expected_collisions(reference, lower, upper, total_time):
    """The collisions a run should put in each bin, from noise-free bin averages.

    By eq. (collrate) collisions come in a bin at the rate P-bar int_bin v dv, P-bar the
    bin average.

    Parameters
    ----------
    reference : array_like
        The bin averages of P(0, v).
    lower, upper : array_like
        The bins' edges.
    total_time : float
        The run's recorded time.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> from bouncing_ball.fits import expected_collisions
    >>> print(expected_collisions([0.5], [1.0], [3.0], 100.0))
    [200.]
    """
    return (
        np.asarray(reference) * total_time * 0.5 * (np.asarray(upper) ** 2 - np.asarray(lower) ** 2)
    )


@dataclass(frozen=True)
class FitBins:
    """The P(0, v) bins a fit uses, chosen by the collisions they should hold.

    Parameters
    ----------
    rows : numpy.ndarray
        Indices into the merged p0v table (and a shard's speed counts).
    lower, upper : numpy.ndarray
        The bins' edges.
    reference : numpy.ndarray
        The reference curve's bin averages.
    expected : numpy.ndarray
        The collisions a run of the total time should put in each.
    beyond : int
        Populated bins above the curve's last speed, left out.
    """

    rows: np.ndarray  # indices into the merged p0v table (and a shard's speed counts)
    lower: np.ndarray
    upper: np.ndarray
    reference: np.ndarray  # the reference curve's bin averages
    expected: np.ndarray  # collisions a run of the total time should put in each
    beyond: int  # populated bins above the curve's last speed, left out


def select_fit_bins(table, speeds, density, total_time, minimum_count) -> FitBins:
    """The bins of a merged P(0, v) table a fit uses.

    The finite bins inside the reference curve's speeds that should hold at least
    ``minimum_count`` collisions in ``total_time``: chosen by the collisions a bin should
    hold, not by those it happens to hold, so the choice does not select on the data.

    Parameters
    ----------
    table : pandas.DataFrame
        A merged p0v table (columns v_lo, v_hi, count).
    speeds, density : numpy.ndarray
        The reference curve, the solver's P(0, v) (see ``usable_curve``).
    total_time : float
        The run's recorded time.
    minimum_count : float
        The fewest collisions a bin should hold.

    Returns
    -------
    FitBins
    """
    v_lo, v_hi = table.v_lo.to_numpy(), table.v_hi.to_numpy()
    finite = np.isfinite(v_hi)
    inside = finite & (v_lo >= speeds[0]) & (v_hi <= speeds[-1])
    beyond = int(np.sum(finite & (v_hi > speeds[-1]) & (table["count"].to_numpy() > 0)))
    reference = bin_averages_of_curve(speeds, density, v_lo[inside], v_hi[inside])
    expected = expected_collisions(reference, v_lo[inside], v_hi[inside], total_time)
    keep = expected >= minimum_count
    rows = np.flatnonzero(inside)[keep]
    return FitBins(rows, v_lo[rows], v_hi[rows], reference[keep], expected[keep], beyond)
