"""w(F) of eq. (weightfunc) interpolated in ln F, and the exact w(F) in the same form.

w is computed at Chebyshev nodes in ln F on [F_min, F_max] and interpolated
(``WeightFunction``; log w + S/F is smooth); above F_max it is continued by
its power law w ~ F^((2 beta - 5)/6) (from h ~ v^-beta), below F_min (where
the contour would leave the range in which the solution's P(0, v) is
accurate, or its rounding noise exceeds NOISE_TOLERANCE) by the interpolant's end slope; both
regions carry weights far below 1e-10 in every result here.  ``closed_form_weight_function``
wraps an exact w(F) (eq. (weightfunc2) at r = 1/2) so that every function of w takes it as it
takes an interpolated one.
"""

import bisect
import functools
import math
from dataclasses import dataclass

import numpy as np

from ..restitution import check_distribution_range
from .outgoing_density import _outgoing_density
from .weight_function import (
    _log_weight_with_noise,
    log_weight_function,
    small_force_decay,
    small_force_power,
)

__all__ = [
    "PANEL_CHEBYSHEV_NODES",
    "NOISE_TOLERANCE",
    "WeightFunction",
    "interpolated_weight_function",
    "closed_form_weight_function",
    "ClosedFormWeight",
]


LARGEST_FORCE = 1e8  # w computed up to here, continued by its power law (and correction) above


PANEL_WIDTH = 3.5  # of the interpolation panels, in ln F (F < 1)


LARGE_PANEL_WIDTH = 5.0  # (F > 1: w is close to its power law there)


SMALL_PANEL_WIDTH = 1.2  # (F < 1, r > 1/2)


#: Chebyshev nodes per panel in ln F of the interpolated w(F) (``interpolated_weight_function``).
PANEL_CHEBYSHEV_NODES = 12


SMALL_FORCE_DEGREE = 5  # of the polynomial in F continuing ln w below F_min


@dataclass(frozen=True)
class WeightFunction:
    """w(F) of eq. (weightfunc), interpolated in ln F (``interpolated_weight_function``).

    ln w + S/F by Chebyshev series in ln F on panels covering [smallest_force, largest_force];
    above, w = w(F_max) (F/F_max)^alpha [(1 - kappa) + kappa (F/F_max)^(-1/3)] with
    alpha = (2 beta - 5)/6 (from h ~ v^-beta; the correction from the next term of P(0, v) at
    small v) and kappa matching the slope; below, gamma ln F plus a polynomial in F fitted on
    the first panel (w ~ F^gamma e^(-S/F), ``small_force_power``; see the module docstring).
    Calling it gives w(F); ``log(F)`` gives ln w(F) (which neither over- nor underflows), and
    ``log_scalar(F)`` the same for one float F, fast; ``smallest_force`` and ``largest_force``
    are F_min and F_max.

    Parameters
    ----------
    restitution : float
        r.
    small_speed_exponent : float
        beta(r) of eq. (asym2).
    small_force_decay : float
        S of ``small_force_decay``.
    edges : numpy.ndarray
        The panel edges in ln F.
    series : tuple of numpy.polynomial.Chebyshev
        Per panel, ln w + S/F against ln F.
    small_force_power : float
        gamma in w ~ F^gamma e^(-S/F) as F -> 0 (``small_force_power``).
    small_force_series : numpy.polynomial.Polynomial
        ln w + S/F - gamma ln F against F, below F_min.
    interpolation_error : float, optional
        The largest difference of the interpolated and the direct ln w at two points of every
        panel between the nodes: an estimate of the relative error of w, and so of P(x) (NaN:
        not estimated).

    Examples
    --------
    Built by ``interpolated_weight_function`` in seconds, after the solve (which compiles the
    kernel on its first call), so not run as a doctest; at r = 1/2 it is eq. (weightfunc2):

    >>> from bouncing_ball.distribution import interpolated_weight_function
    >>> from bouncing_ball.distribution import outgoing_speed_solution
    >>> weight = interpolated_weight_function(outgoing_speed_solution("1/2"))  # doctest: +SKIP
    >>> print(weight([0.1, 1.0]).round(8), weight.interpolation_error < 1e-12)  # doctest: +SKIP
    [0.22905337 0.15334074] True
    >>> print(weight.smallest_force, weight.largest_force)  # doctest: +SKIP
    0.0008333333333333333 100000000.00000018
    """

    restitution: float
    small_speed_exponent: float
    small_force_decay: float  # S
    edges: np.ndarray  # panel edges in ln F
    series: tuple  # np.polynomial.Chebyshev per panel, of ln w + S / F against ln F
    small_force_power: float  # gamma in w ~ F^gamma e^(-S/F) as F -> 0
    small_force_series: np.polynomial.Polynomial  # ln w + S/F - gamma ln F against F, F < F_min
    # the largest |interpolated - direct ln w| at two points of every panel between the nodes:
    # an estimate of the relative error of w, and so of P(x) (NaN: not estimated)
    interpolation_error: float = float("nan")

    @property
    def smallest_force(self) -> float:
        """F_min, the lowest panel edge: below, w is continued by its small-F form."""
        return float(np.exp(self.edges[0]))

    @property
    def largest_force(self) -> float:
        """F_max, the highest panel edge: above, w is continued by its power law."""
        return float(np.exp(self.edges[-1]))

    def _smooth(self, y):
        index = np.clip(np.searchsorted(self.edges, y) - 1, 0, len(self.series) - 1)
        out = np.empty_like(y)
        for k in np.unique(index):
            chosen = index == k
            out[chosen] = self.series[k](y[chosen])
        return out

    def log(self, force):
        """ln w(F).

        Parameters
        ----------
        force : array_like
            Values of F > 0.

        Returns
        -------
        numpy.ndarray
            ln w(F), the shape of ``force``.
        """
        force = np.asarray(force, dtype=float)
        y = np.atleast_1d(np.log(force)).astype(float)
        lo, hi = self.edges[0], self.edges[-1]
        smooth = self._smooth(np.clip(y, lo, hi))
        below = y < lo
        f_below = np.exp(y[below])
        smooth[below] = self.small_force_power * y[below] + self.small_force_series(f_below)
        above = y > hi
        if above.any():
            value, alpha, kappa = self._large_force_law
            t = y[above] - hi
            smooth[above] = (
                value
                + alpha * t
                + np.log((1.0 - kappa) + kappa * np.exp(-t / 3.0))
                + self.small_force_decay * np.exp(-y[above])
            )
        return (smooth - self.small_force_decay * np.exp(-y)).reshape(np.shape(force))

    @functools.cached_property
    def _large_force_law(self):
        """ln w(F_max), alpha and kappa of the continuation above F_max."""
        hi, last, decay = self.edges[-1], self.series[-1], self.small_force_decay
        value = last(hi) - decay * np.exp(-hi)  # ln w at F_max
        slope = last.deriv()(hi) + decay * np.exp(-hi)  # d ln w / d ln F
        alpha = (2.0 * self.small_speed_exponent - 5.0) / 6.0
        return float(value), alpha, float(3.0 * (alpha - slope))

    def log_scalar(self, force: float) -> float:
        """ln w(F) for one F (a fast path for scalar integrands: Clenshaw on the panel's series).

        Parameters
        ----------
        force : float
            F > 0.

        Returns
        -------
        float
            ln w(F), as ``log`` gives it.
        """
        y = math.log(force)
        if y > self._edge_list[-1]:
            value, alpha, kappa = self._large_force_law
            t = y - self._edge_list[-1]
            return value + alpha * t + math.log((1.0 - kappa) + kappa * math.exp(-t / 3.0))
        if y < self._edge_list[0]:
            return float(
                self.small_force_power * y
                + self.small_force_series(force)
                - self.small_force_decay / force
            )
        index = min(bisect.bisect_right(self._edge_list, y) - 1, len(self.series) - 1)
        a, b = self._edge_list[index], self._edge_list[index + 1]
        t = (2.0 * y - a - b) / (b - a)
        b1 = b2 = 0.0
        coefficients = self._coefficients[index]
        for c in coefficients[:0:-1]:
            b1, b2 = c + 2.0 * t * b1 - b2, b1
        return coefficients[0] + t * b1 - b2 - self.small_force_decay / force

    @functools.cached_property
    def _edge_list(self):
        return [float(e) for e in self.edges]

    @functools.cached_property
    def _coefficients(self):
        return [[float(c) for c in piece.coef] for piece in self.series]

    def __call__(self, force):
        """w(F).

        Parameters
        ----------
        force : array_like
            Values of F > 0.

        Returns
        -------
        numpy.ndarray
            w(F), the shape of ``force`` (over- or underflows where ``log`` does not).
        """
        return np.exp(self.log(force))


#: The largest estimated relative rounding error of w(F) accepted: the interpolated w starts
#: at the smallest F at which the direct evaluation is this accurate.
NOISE_TOLERANCE = 2e-9


def _accurate(density, force) -> bool:
    _, noise = _log_weight_with_noise(np.array([force]), density)
    return bool(noise[0] < NOISE_TOLERANCE)


def _smallest_force(density, floor) -> float:
    """The smallest F >= ``floor`` (to a factor 10^(1/8)) above which w(F) is computed with an
    estimated rounding error below NOISE_TOLERANCE and with P(0, v) only where the solution's is
    accurate.  The error grows as F decreases, but not monotonically everywhere (near r = 1 a
    lone F far below the noise limit can pass): the F found by bisection in ln F is accepted
    only if every F above it on a ladder of factors 10^(1/8) up to 1 passes too; otherwise the
    bisection starts again above the highest F of the ladder that fails."""
    if not _accurate(density, 1.0):
        raise ValueError("w(1) cannot be computed accurately from this solution")
    rung = np.log(10.0) / 8.0
    lo, hi = np.log(floor), 0.0  # inaccurate at lo (unless it is the floor), accurate at hi
    if _accurate(density, floor):
        hi = lo
    while True:
        while hi - lo > rung:
            middle = 0.5 * (lo + hi)
            if _accurate(density, np.exp(middle)):
                hi = middle
            else:
                lo = middle
        ladder = hi + rung * np.arange(1, int(np.ceil(-hi / rung)))
        failing = [y for y in ladder if not _accurate(density, np.exp(y))]
        if not failing:
            return float(np.exp(hi))
        lo, hi = failing[-1], min(failing[-1] + rung, 0.0)


def interpolated_weight_function(solution, panel_nodes=PANEL_CHEBYSHEV_NODES) -> WeightFunction:
    """w(F) of eq. (weightfunc), computed at Chebyshev nodes on panels in ln F and interpolated.

    The panels run from F_min, the smallest F at which the direct evaluation
    (``log_weight_function``) is accurate to ``NOISE_TOLERANCE``, to LARGEST_FORCE.  Where
    r > 1/2 the panels at F < 1 are SMALL_PANEL_WIDTH wide (there the saddle e^(-S/F) and
    end-point e^(-1/(12F)) terms of w cross over), else PANEL_WIDTH; LARGE_PANEL_WIDTH at
    F > 1.  The interpolation error is estimated against w computed directly between the nodes.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        P(0, v) of eq. (inteq), from ``outgoing_speed_solution`` (which reaches as far as
        small F needs).
    panel_nodes : int, optional
        Chebyshev nodes per panel (``PANEL_CHEBYSHEV_NODES``).

    Returns
    -------
    WeightFunction
        The interpolated w(F), with its estimated ``interpolation_error``.

    Raises
    ------
    ValueError
        If r lies outside ``DISTRIBUTION_RESTITUTION_RANGE``, w(1) cannot be computed
        accurately from the solution, or w is not finite at an interpolation node.

    Examples
    --------
    Takes seconds, after the solve (which compiles the kernel on its first call), so not run
    as a doctest:

    >>> from bouncing_ball.distribution import interpolated_weight_function
    >>> from bouncing_ball.distribution import outgoing_speed_solution
    >>> weight = interpolated_weight_function(outgoing_speed_solution("1/2"))  # doctest: +SKIP
    >>> print(weight([0.1, 1.0]).round(8))  # doctest: +SKIP
    [0.22905337 0.15334074]
    """
    check_distribution_range(solution.restitution, "solution.restitution")
    density = _outgoing_density(solution)
    decay = small_force_decay(solution.restitution)
    # below (S + 1/12)/200, F^(-1/2) w e^(-1/(12F)) < e^-200 of its largest values
    lowest = _smallest_force(density, (decay + 1.0 / 12.0) / 200.0)
    lo, hi = np.log(lowest), np.log(LARGEST_FORCE)
    narrow = SMALL_PANEL_WIDTH if solution.restitution > 0.5 else PANEL_WIDTH
    small = int(np.ceil(-lo / narrow)) if lo < 0.0 else 0
    large = max(1, int(np.ceil((hi - max(lo, 0.0)) / LARGE_PANEL_WIDTH)))
    edges = np.concatenate(
        [np.linspace(lo, 0.0, small + 1)[:-1], np.linspace(max(lo, 0.0), hi, large + 1)]
    )
    x = np.cos(np.pi * (np.arange(panel_nodes) + 0.5) / panel_nodes)
    y = 0.5 * (edges[:-1, None] + edges[1:, None]) + 0.5 * np.diff(edges)[:, None] * x[None, :]
    forces = np.exp(y.ravel())
    values = log_weight_function(forces, solution, density) + decay / forces
    if not np.all(np.isfinite(values)):
        bad = forces[~np.isfinite(values)]
        raise ValueError(
            f"r = {solution.restitution}: w(F) of eq. (weightfunc) is not finite at "
            f"{bad.size} of its {forces.size} interpolation nodes (F = {bad.min():.3g} to "
            f"{bad.max():.3g}); the weight function cannot be interpolated"
        )
    series = tuple(
        np.polynomial.Chebyshev.fit(yk, vk, panel_nodes - 1, domain=[a, b])
        for yk, vk, a, b in zip(y, values.reshape(y.shape), edges[:-1], edges[1:])
    )
    # the interpolation error, estimated against w computed directly between the nodes
    probes = 0.5 * (edges[:-1, None] + edges[1:, None]) + 0.3 * np.diff(edges)[:, None] * np.array(
        [-1.0, 1.0]
    )
    direct = log_weight_function(np.exp(probes.ravel()), solution, density).reshape(probes.shape)
    direct += decay * np.exp(-probes)
    interpolated = np.array([piece(yk) for piece, yk in zip(series, probes)])
    deviation = np.abs(interpolated - direct)
    error = float(np.max(deviation)) if np.all(np.isfinite(deviation)) else np.inf
    # below F_min: gamma ln F + a polynomial in F, fitted on the first panel
    gamma = small_force_power(solution.restitution)
    f_fit = np.exp(np.linspace(edges[0], edges[1], 40))
    below = np.polynomial.Polynomial.fit(
        f_fit, series[0](np.log(f_fit)) - gamma * np.log(f_fit), SMALL_FORCE_DEGREE
    )
    return WeightFunction(
        solution.restitution,
        solution.small_speed_exponent,
        decay,
        edges,
        series,
        gamma,
        below,
        error,
    )


def closed_form_weight_function(restitution, log_weight) -> "ClosedFormWeight":
    """A weight function known in closed form, usable wherever a ``WeightFunction`` is.

    Everything here that takes a weight function takes it, except ``measured_exponents`` and
    ``exponents_table`` (they need the interpolant's beta and F_min).

    Parameters
    ----------
    restitution : float
        r.
    log_weight : callable
        ln w(F) for an array of F > 0, e.g. from ``exact.weight_function``,
        eq. (weightfunc2).

    Returns
    -------
    ClosedFormWeight
        The weight function.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(weight([0.1, 1.0]).round(8))
    [0.22905337 0.15334074]
    """
    return ClosedFormWeight(float(restitution), log_weight)


@dataclass(frozen=True)
class ClosedFormWeight:
    """w(F) given by its logarithm in closed form (``closed_form_weight_function``).

    Calling it gives w(F); ``log(F)`` gives ln w(F).

    Parameters
    ----------
    restitution : float
        r.
    log : callable
        ln w(F) for an array of F > 0.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> from bouncing_ball.distribution import ClosedFormWeight
    >>> weight = ClosedFormWeight(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(round(float(weight(1.0)), 8))
    0.15334074
    """

    restitution: float
    log: object  # callable: ln w(F)

    def __call__(self, force):
        """w(F).

        Parameters
        ----------
        force : array_like
            Values of F > 0.

        Returns
        -------
        numpy.ndarray
            w(F), the shape of ``force``.
        """
        return np.exp(self.log(force))
