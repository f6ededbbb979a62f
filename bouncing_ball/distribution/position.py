"""P(x) of eq. (P(x)1), its tail int_x^inf P and <v^2>_x of eq. (moment2), from w(F).

Each is one integral over F of w(F) against an elementary function of F x, taken by
Gauss-Legendre panels in ln F about the saddle of e^(-(S + 1/12)/F - F x) (``_force_nodes``);
the power law of w(F) beyond its largest node is summed in closed form.  The moments of P(x) and
the bin averages of P(x) and of <v^2>_x are in closed form under the same F integral.
"""

import math

import numpy as np

from ..asymptotics import small_speed_exponent
from .outgoing_density import _GL_W, _GL_X
from .weight_function import _log_sum, small_force_decay

__all__ = [
    "SMALLEST_POSITION",
    "LARGEST_POSITION",
    "LARGEST_VELOCITY",
    "SMALLEST_WEIGHT_FORCE",
    "position_density",
    "position_tail",
    "mean_speed_squared_given_position",
    "position_moment",
    "position_averages",
    "position_bin_average",
    "speed_squared_given_position_bin_average",
]


def _total_decay(weight) -> float:
    """S + 1/12: F^(-1/2) w(F) e^(-1/(12F)) ~ exp(-(S + 1/12)/F) at small F."""
    return small_force_decay(weight.restitution) + 1.0 / 12.0


#: The F integrals of P(x) (``_log_laplace``) run between the two F at which the factor
#: e^(-(S + 1/12)/F - F x) has fallen FORCE_EFOLDS e-folds below its saddle value.
FORCE_EFOLDS = 100.0


#: Their Gauss-Legendre panels in ln F are at most this wide, and at most FORCE_PANEL_SIGMAS
#: times the width of the saddle in ln F, (2 ((S + 1/12) x)^(1/2))^(-1/2) (a power of 2 below
#: the widest, so that the panel edges lie on a grid fixed by x alone).
FORCE_PANEL_WIDTH = 0.5


FORCE_PANEL_SIGMAS = 2.5


#: The heights at which P(x), its tail and <v^2>_x are computed (x = 0 aside): below, the F
#: integral reaches past the largest double; above, the saddle in ln F narrows towards the
#: spacing of doubles.
SMALLEST_POSITION = 1e-300


LARGEST_POSITION = 1e12


#: Beyond this speed abs(v), P(x, v) is 0 to every double (``Equilibrium.pxv``): on the floor P(0, v) ~
#: e^(-q v) and P(0, -v) = r^2 P(0, r v) fall below e^-1400 at every r of
#: DISTRIBUTION_RESTITUTION_RANGE (r q = 1.5e-3 at r = 0.999), and above it P(x, v) is a
#: Gaussian in v of variance <v^2>_x < 1e8 wherever P(x) is a double, e^-5000 down there.
LARGEST_VELOCITY = 1e6


#: The smallest F of the config's ``solver.forces``: above ``Equilibrium.smallest_force`` (below
#: which w(F) ~ F^gamma e^(-S/F), S < 0, exceeds the largest double) at every r of
#: DISTRIBUTION_RESTITUTION_RANGE (-S / F < 1 / (12 F) = 417 < 709 at 2e-4 for every r).
SMALLEST_WEIGHT_FORCE = 2e-4


#: ln of the largest F of the F integrals at x = 0 (F = e^690 ~ 1e300): beyond, the power law
#: of w(F) is summed in closed form (``_force_nodes``).
LARGEST_LOG_FORCE = 690.0


def _force_plan(weight, power, x):
    """The panels of ``_force_nodes`` at one x: (width, first, last, tail), the panels
    [k width, (k + 1) width] for first <= k < last and the power-law tail's decay (None at
    x > 0)."""
    total = _total_decay(weight)
    tail = None
    if x > 0.0:
        root = math.sqrt(total * x)
        centre = 0.5 * math.log(total / x)
        reach = math.acosh(1.0 + FORCE_EFOLDS / (2.0 * root))
        lo, hi = centre - reach, centre + reach
        sigma = (2.0 * root) ** -0.5
        halvings = max(0, math.ceil(math.log2(FORCE_PANEL_WIDTH / (FORCE_PANEL_SIGMAS * sigma))))
    else:
        decay = power - (small_speed_exponent(weight.restitution) - 1.0) / 3.0
        lo, hi = math.log(total / FORCE_EFOLDS), math.log(1e24) + FORCE_EFOLDS / decay
        if hi > LARGEST_LOG_FORCE:
            hi, tail = LARGEST_LOG_FORCE, decay
        halvings = 0
    width = FORCE_PANEL_WIDTH * 2.0**-halvings
    first, last = math.floor(lo / width), math.ceil(hi / width)
    if tail is not None:
        last = math.floor(hi / width)
    return width, first, last, tail


def _panel_nodes(weight, power, width, first, last):
    """ln F of the Gauss-Legendre nodes on the panels [k width, (k + 1) width],
    first <= k < last (each node a function of k and width alone), F, and ln of the weights
    with F^(1/2 - power) w e^(-1/(12F)) dF/dlnF folded in."""
    k = np.arange(first, last, dtype=float)[:, None]
    y = ((k + 0.5) * width + (0.5 * width) * _GL_X[None, :]).ravel()
    log_wy = np.log(0.5 * width * np.broadcast_to(_GL_W, (last - first, _GL_W.size)).ravel())
    force = np.exp(y)
    return y, force, log_wy + (0.5 - power) * y + weight.log(force) - 1.0 / (12.0 * force)


def _with_tail(weight, power, width, last, tail, y, force, log_weights):
    # int_end^inf dy e^(f(end) - decay (y - end)) = e^f(end) / decay, one more node at the end
    end = last * width
    f_end = math.exp(end)
    log_end = (0.5 - power) * end + float(weight.log(np.array([f_end]))[0]) - 1.0 / (12.0 * f_end)
    return np.append(force, f_end), np.append(log_weights, log_end - math.log(tail))


def _force_nodes(weight, power, x):
    """Gauss-Legendre nodes ln F and ln of their weights for int dF F^(-1/2 - power) w(F)
    e^(-1/(12F) - F x) at one x >= 0, the factor F^(1/2 - power) w e^(-1/(12F)) dF/dlnF folded
    into the weights.  The nodes depend on x alone (each panel's on its place on a grid fixed
    by x: ``_force_plan``), so a result never depends on the other points of an array.  At
    x > 0 they span the FORCE_EFOLDS e-folds of e^(-(S + 1/12)/F - F x) about its saddle
    F_s = ((S + 1/12) / x)^(1/2) (out to F = FORCE_EFOLDS / x at small x, where w is its power
    law, so P(x) follows its small-x law, docs/distribution.md); at x = 0 (the moments,
    power >= 1; P(0) where beta < 1) out to where the power law F^((beta - 1)/3 - power) has
    fallen by e^-FORCE_EFOLDS beyond F = 1e24, but no further than F = e^LARGEST_LOG_FORCE
    (where F stays a double), the power law's tail beyond summed in closed form as one more
    node (its F is never multiplied by an x > 0)."""
    width, first, last, tail = _force_plan(weight, power, x)
    _, force, log_weights = _panel_nodes(weight, power, width, first, last)
    if tail is not None:
        force, log_weights = _with_tail(weight, power, width, last, tail, None, force, log_weights)
    return force, log_weights


def _log_laplace(weight, power, x):
    """ln int dF F^(-1/2 - power) w(F) exp(-1/(12F) - F x), for an array x >= 0, each x on its
    own nodes (``_force_nodes``): finite where the integral itself under- or overflows.  The
    points with the same panel width share one evaluation of w at the union of their panels
    (a node's value depends on its panel alone, so each result is that of ``_force_nodes``)."""
    x = np.asarray(x, dtype=float)
    flat = x.ravel()
    out = np.empty(flat.size)
    plans = [_force_plan(weight, power, float(point)) for point in flat]
    count = _GL_X.size
    for width in {plan[0] for plan in plans}:
        members = [i for i, plan in enumerate(plans) if plan[0] == width]
        lowest = min(plans[i][1] for i in members)
        highest = max(plans[i][2] for i in members)
        _, force, log_weights = _panel_nodes(weight, power, width, lowest, highest)
        for i in members:
            _, first, last, tail = plans[i]
            chosen = slice((first - lowest) * count, (last - lowest) * count)
            f, lw = force[chosen], log_weights[chosen]
            if tail is not None:
                f, lw = _with_tail(weight, power, width, last, tail, None, f, lw)
            out[i] = _log_sum(lw - flat[i] * f)[0]
    return out.reshape(x.shape)


def _laplace(weight, power, x):
    """int dF F^(-1/2 - power) w(F) exp(-1/(12F) - F x), for an array x >= 0 (0 where it
    underflows)."""
    return np.exp(_log_laplace(weight, power, x))


def position_density(x, weight):
    """P(x) = int dF F^(-1/2) w(F) exp(-1/(12F) - F x), eq. (P(x)1).

    The F integral by Gauss-Legendre in ln F, from where the integrand has fallen below e^-100
    up to F = 1e24.

    Parameters
    ----------
    x : array_like
        Heights x >= 0.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    numpy.ndarray
        P(x), the shape of ``x``.

    Examples
    --------
    At r = 1/2, from the exact w(F), it is eq. (P(x)2):

    >>> from bouncing_ball.distribution import closed_form_weight_function, position_density
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(position_density([0.1, 1.0, 10.0], weight).round(8))
    [0.50377641 0.18378367 0.01886243]
    >>> print(exact.position_density([0.1, 1.0, 10.0], "1/2").round(8))
    [0.50377641 0.18378367 0.01886243]
    """
    return _laplace(weight, 0.0, x)


def position_tail(x, weight):
    """int_x^inf P(x') dx' = int dF F^(-3/2) w(F) exp(-1/(12F) - F x), from eq. (P(x)1).

    Parameters
    ----------
    x : array_like
        Heights x >= 0.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    numpy.ndarray
        The probability above x, the shape of ``x``; 1 at x = 0 (eq. (normalization2)).

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function, position_tail
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(position_tail([0.1, 1.0, 10.0], weight).round(8))
    [0.93357681 0.68198146 0.17235138]
    >>> print(round(float(position_tail(0.0, weight)), 12))
    1.0
    """
    return _laplace(weight, 1.0, x)


def mean_speed_squared_given_position(x, weight):
    """<v^2>_x = P(x)^-1 int_x^inf P(x') dx', eq. (moment2).

    Parameters
    ----------
    x : array_like
        Heights x >= 0.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    numpy.ndarray
        The mean square speed at height x, the shape of ``x``.

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.distribution import mean_speed_squared_given_position
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(mean_speed_squared_given_position([0.1, 1.0, 10.0], weight).round(8))
    [1.85315706 3.71078371 9.13728189]
    >>> print(exact.mean_speed_squared_given_position([0.1, 1.0, 10.0], "1/2").round(8))
    [1.85315706 3.71078371 9.13728189]
    """
    return np.exp(_log_laplace(weight, 1.0, x) - _log_laplace(weight, 0.0, x))


def position_moment(k: int, weight) -> float:
    """int_0^inf x^k P(x) dx = k! int dF F^(-3/2 - k) w(F) e^(-1/(12F)), eq. (P(x)1).

    At k = 0 it is the normalisation, eq. (normalization2).

    Parameters
    ----------
    k : int
        The power of x, k >= 0.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    float
        The k-th moment of P(x).

    Examples
    --------
    At r = 1/2: 1, <x> = 6 and <x^2> = 6^2 + 108, eq. (xandDeltax):

    >>> from bouncing_ball.distribution import closed_form_weight_function, position_moment
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print([round(position_moment(k, weight), 9) for k in (0, 1, 2)])
    [1.0, 6.0, 144.0]
    """
    return float(math.factorial(k) * _laplace(weight, 1.0 + k, 0.0))


def position_averages(weight) -> dict:
    """The normalisation, <x> and Delta x (eq. (xandDeltax)) from P(x) of eq. (P(x)1).

    Parameters
    ----------
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    dict
        normalization (int P dx, eq. (normalization2)), mean_x (<x>) and delta_x (Delta x).

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function, position_averages
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print({name: round(value, 9) for name, value in position_averages(weight).items()})
    {'normalization': 1.0, 'mean_x': 6.0, 'delta_x': 10.392304845}
    """
    norm, first, second = (position_moment(k, weight) for k in (0, 1, 2))
    mean_x = first / norm
    return {
        "normalization": norm,
        "mean_x": mean_x,
        "delta_x": float(np.sqrt(second / norm - mean_x**2)),
    }


def _log_bin_laplace(weight, power, lo, hi):
    """ln int dF F^(-1/2 - power) w e^(-1/(12F)) (e^(-F lo) - e^(-F hi)), each bin on the nodes
    of its own lower edge (``_force_nodes``: a bin's result never depends on the other bins; no
    cancellation in narrow bins; finite where the integral underflows)."""
    lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
    out = np.empty(lo.shape)
    for index in np.ndindex(lo.shape):
        edge, width = float(lo[index]), float(hi[index] - lo[index])
        force, log_weights = _force_nodes(weight, power, edge)
        with np.errstate(divide="ignore"):  # F width below the smallest double
            difference = np.log(-np.expm1(-force * width))
        out[index] = _log_sum(log_weights - force * edge + difference)[0]
    return out


def _check_bins(lo, hi):
    """The bins' edges broadcast, each bin within the heights computed: lo = 0 or
    SMALLEST_POSITION <= lo < hi <= LARGEST_POSITION (ValueError naming lo or hi and the
    bound)."""
    lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
    for name, edge, bad in (
        ("lo", lo, ~(lo >= 0.0) | ((lo > 0.0) & (lo < SMALLEST_POSITION))),
        ("hi", hi, ~(hi > lo) | ~(hi <= LARGEST_POSITION)),
    ):
        if bad.any():
            raise ValueError(
                f"{name} = {edge[bad].flat[0]:g}: bins need lo = 0 or SMALLEST_POSITION = "
                f"{SMALLEST_POSITION:g} <= lo < hi <= LARGEST_POSITION = {LARGEST_POSITION:g}"
            )
    return lo, hi


def position_bin_average(lo, hi, weight):
    """int_lo^hi P(x) dx / (hi - lo), the quantity a simulation's position bin measures.

    P(x) of eq. (P(x)1), the x integral done under the F integral in closed form (no
    cancellation in narrow bins).

    Parameters
    ----------
    lo, hi : array_like
        The bins' lower and upper edges, 0 <= lo < hi; they broadcast.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    numpy.ndarray
        The bin averages of P(x), the broadcast shape of ``lo`` and ``hi``.

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function, position_bin_average
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(position_bin_average([0.0, 1.0], [1.0, 2.0], weight).round(8))
    [0.31801854 0.1429493 ]
    >>> print(exact.position_bin_average([0.0, 1.0], [1.0, 2.0], "1/2").round(8))
    [0.31801854 0.1429493 ]
    """
    lo, hi = _check_bins(lo, hi)
    return np.exp(_log_bin_laplace(weight, 1.0, lo, hi)) / (hi - lo)


def speed_squared_given_position_bin_average(lo, hi, weight):
    """<v^2>_x of eq. (moment2) averaged over [lo, hi) with weight P(x), as a bin measures it.

    int_bin dx int_x^inf P / int_bin P dx; under the F integral,
    int_lo^hi dx int_x^inf e^(-F x') dx' = (e^(-F lo) - e^(-F hi)) / F^2.

    Parameters
    ----------
    lo, hi : array_like
        The bins' lower and upper edges, 0 <= lo < hi; they broadcast.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    numpy.ndarray
        The bin averages of <v^2>_x, the broadcast shape of ``lo`` and ``hi``.

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.distribution import speed_squared_given_position_bin_average
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(speed_squared_given_position_bin_average([0.0, 1.0], [1.0, 2.0], weight).round(8))
    [2.53258574 4.23045873]
    >>> print(exact.speed_squared_given_position_bin_average([0, 1], [1, 2], "1/2").round(8))
    [2.53258574 4.23045873]
    """
    lo, hi = _check_bins(lo, hi)
    return np.exp(_log_bin_laplace(weight, 2.0, lo, hi) - _log_bin_laplace(weight, 1.0, lo, hi))
