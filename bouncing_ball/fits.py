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
from .histograms import outgoing_speed_density

SMALL_SPEED = "small_speed"
LARGE_SPEED = "large_speed"
INTERVAL_95 = 1.959963984540054  # scipy.stats.norm.ppf(0.975)


class WindowError(ValueError):
    """No window on one side holds enough usable bins for a fit."""


def small_speed_form(v, log_prefactor, beta):
    """A v^-beta, eq. (asym1)."""
    return np.exp(log_prefactor - beta * np.log(v))


def large_speed_form(v, log_prefactor, m, q):
    """A v^-m e^(-q v), eq. (asym3)."""
    return np.exp(log_prefactor - m * np.log(v) - q * v)


FORMS = {SMALL_SPEED: small_speed_form, LARGE_SPEED: large_speed_form}
EXPONENT_NAMES = {SMALL_SPEED: ("beta",), LARGE_SPEED: ("m", "q")}


def theory_exponents(side, restitution):
    """The exponents of the asymptotic form on ``side``: (beta,) or (m, q)."""
    if side == SMALL_SPEED:
        return (small_speed_exponent(restitution),)
    return (large_speed_exponent(restitution), large_speed_decay_rate(restitution))


def bin_average(form, lower, upper, *parameters):
    """The bin averages (``bins.outgoing_speed_bin_average``) of ``form(v, *parameters)``."""
    return outgoing_speed_bin_average(lambda v: form(v, *parameters), lower, upper)


@dataclass(frozen=True)
class AsymptoticFit:
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
        return self.chi2 / self.dof if self.dof > 0 else np.nan


def fit_asymptotic_form(side, lower, upper, values, errors, restitution, free):
    """Weighted least-squares fit of the form on ``side`` to bin averages ``values`` +- ``errors``."""
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
    best, covariance = optimize.curve_fit(
        lambda _, *p: bin_average(form, lower, upper, *p),
        np.zeros(len(values)),
        values,
        p0=start,
        sigma=errors,
        absolute_sigma=True,
        maxfev=20000,
    )
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
    """The fit of the pooled P(0, v) of shards (``counts``: shards x bins, ``times``: shards),
    with delete-one jackknife errors over shards; ``errors`` are the weights.

    For free exponents also the p-value of the theory's exponents taken together:
    Hotelling's T^2 = d' C^-1 d with C the jackknife covariance of the fitted
    exponents, (n - p) T^2 / (p (n - 1)) ~ F(p, n - p) for n shards and p exponents.
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
        if shards > exponents:
            t_squared = float(deviation @ np.linalg.solve(covariance[1:, 1:], deviation))
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
    """Student t factor of a ``level`` interval from a jackknife over ``shards`` shards
    (``scipy.stats.t.ppf``)."""
    return float(special.stdtrit(shards - 1, 0.5 + level / 2.0))


def asymptotic_window(
    side, lower, upper, counts, times, errors, reference, restitution, max_bias=0.5, minimum_bins=4
):
    """The default window on ``side`` as a slice of the usable bins; see the module docstring.

    ``reference`` are noise-free bin averages of P(0, v) (the solver's) in the same bins.
    """
    count = len(lower)
    if count < minimum_bins:
        raise WindowError(f"{side} window: only {count} usable bins, {minimum_bins} needed")
    theory = np.array(theory_exponents(side, restitution))
    best = None
    for size in range(minimum_bins, count + 1):
        window = slice(0, size) if side == SMALL_SPEED else slice(count - size, count)
        parts = (lower[window], upper[window])
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
        spread = np.array([noisy.errors[name] for name in EXPONENT_NAMES[side]])
        if np.any(np.abs(drift) > max_bias * spread):
            break
        best = window
    if best is None:
        raise WindowError(
            f"{side} window: fitted to the solver over the {minimum_bins} outermost usable bins, the free "
            f"exponents already differ from the theory's by more than {max_bias} of the data's errors"
        )
    return best


def window_from_range(side, lower, upper, speed_range):
    """The usable bins inside a configured [min, max] window."""
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
    """Every asymptotic fit of P(0, v) for one r, as a long table: each window (small and
    large v), with the theory's exponents and with free ones, to the simulation and to the
    solver.

    ``counts`` (shards x bins) and ``times`` are the simulation's usable bins, ``errors``
    its standard errors (the weights), ``reference`` the solver's bin averages;
    ``windows`` maps each side to "auto" or {"min": .., "max": ..}.  A side without a
    usable window gets NaN rows; the reasons are returned alongside.
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
            names = ("prefactor", *EXPONENT_NAMES[side])
            empty = AsymptoticFit(
                side,
                False,
                dict.fromkeys(names, np.nan),
                dict.fromkeys(names, np.nan),
                np.nan,
                0,
                np.nan,
                np.nan,
            )
            for source in ("simulation", "solver"):
                for free in (False, True):
                    rows += fit_rows(
                        source, AsymptoticFit(**{**empty.__dict__, "free": free}), theory
                    )
            continue
        parts = (lower[window], upper[window])
        for free in (False, True):
            simulated = fit_shards(
                side, *parts, counts[:, window], times, errors[window], restitution, free
            )
            rows += fit_rows("simulation", simulated, theory, shards=len(times))
            solved = fit_asymptotic_form(
                side, *parts, reference[window], errors[window], restitution, free
            )
            rows += fit_rows("solver", solved, theory)
    return pd.DataFrame(rows), problems


def usable_curve(speeds, density):
    """The part of a tabulated P(0, v) that can be interpolated in logs: up to the last
    positive value (for r below ~0.035 the solver's P(0, v) ~ exp(-v / (2r)) underflows
    to 0 before the grid ends)."""
    speeds, density = np.asarray(speeds, dtype=float), np.asarray(density, dtype=float)
    bad = np.flatnonzero(~(np.isfinite(density) & (density > 0.0)))
    end = bad[0] if len(bad) else len(density)
    return speeds[:end], density[:end]


def bin_averages_of_curve(speeds, density, lower, upper):
    """Bin averages of P(0, v) given on a dense log grid (the solver's output): a cubic spline
    of ln P in ln v, averaged like the data (relative error ~1e-7 at 50 points per decade)."""
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if len(lower) == 0:
        return np.empty(0)
    spline = CubicSpline(np.log(speeds), np.log(density))
    if lower.min() < speeds[0] or upper.max() > speeds[-1]:
        raise ValueError(f"bins reach beyond the curve's speeds [{speeds[0]}, {speeds[-1]}]")
    return outgoing_speed_bin_average(lambda v: np.exp(spline(np.log(v))), lower, upper)


def fit_errors(errors, reference, expected):
    """The per-bin standard errors that weight a fit: the jackknife's, except where it has
    none to give.

    With few shards a bin's jackknife error can be exactly 0 (every shard put the same
    number of collisions there) or undefined; such a bin is weighted by its Poisson error
    from the collisions it should hold, ``reference / sqrt(expected)``, so that it stays in
    the fit (dropping it because of what its counts happened to be would select on the data).
    """
    errors = np.array(errors, dtype=float)
    missing = ~(np.isfinite(errors) & (errors > 0.0))
    errors[missing] = np.asarray(reference, dtype=float)[missing] / np.sqrt(
        np.asarray(expected, dtype=float)[missing]
    )
    return errors


def expected_collisions(reference, lower, upper, total_time):
    """Collisions a run of ``total_time`` should put in each bin, from noise-free bin averages
    (eq. (collrate): rate = P-bar int_bin v dv)."""
    return (
        np.asarray(reference) * total_time * 0.5 * (np.asarray(upper) ** 2 - np.asarray(lower) ** 2)
    )


@dataclass(frozen=True)
class FitBins:
    """The P(0, v) bins a fit uses, chosen by the collisions they should hold."""

    rows: np.ndarray  # indices into the merged p0v table (and a shard's speed counts)
    lower: np.ndarray
    upper: np.ndarray
    reference: np.ndarray  # the reference curve's bin averages
    expected: np.ndarray  # collisions a run of the total time should put in each
    beyond: int  # populated bins above the curve's last speed, left out


def select_fit_bins(table, speeds, density, total_time, minimum_count) -> FitBins:
    """The finite bins of a merged p0v ``table`` inside the reference curve's speeds (``speeds``,
    ``density``: the solver's P(0, v), see ``usable_curve``) that should hold at least
    ``minimum_count`` collisions in ``total_time``.  Chosen by the collisions a bin should hold,
    not by those it happens to hold, so the choice does not select on the data."""
    v_lo, v_hi = table.v_lo.to_numpy(), table.v_hi.to_numpy()
    finite = np.isfinite(v_hi)
    inside = finite & (v_lo >= speeds[0]) & (v_hi <= speeds[-1])
    beyond = int(np.sum(finite & (v_hi > speeds[-1]) & (table["count"].to_numpy() > 0)))
    reference = bin_averages_of_curve(speeds, density, v_lo[inside], v_hi[inside])
    expected = expected_collisions(reference, v_lo[inside], v_hi[inside], total_time)
    keep = expected >= minimum_count
    rows = np.flatnonzero(inside)[keep]
    return FitBins(rows, v_lo[rows], v_hi[rows], reference[keep], expected[keep], beyond)
