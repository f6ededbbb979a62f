"""Conditional moments given the outgoing speed u: E[T^k v^m | u], and E[T | u], E[T^2 | u] in closed form.

Conditional moments E[T^k v^m | u] are one v-integral of eq. (timemoments) (``joint_law``), done
by the trapezoidal rule in s = ln v + v^(1/2) (as the solver's; exponential convergence).  Ito's
formula with the generator v d/dx - d/dv + d^2/dv^2 gives exact identities they must obey
(x = 0 at both ends, v -> -v_return)::

    v + t:        E[T | u] = u + E[v | u]
    v^2 + 2 x:    E[v^2 | u] = u^2 + 2 E[T | u]
    t v + t^2/2:  E[T^2 | u] = 2 E[T v | u]
    (v + t)^3:    E[(T - v)^3 | u] = u^3 + 3 E[T^2 | u]

Closed forms, from the Laplace transform of T.  By eq. (0g) the transform at sigma is the
free law's at s = sigma + 1/4, and the free law's scaling (t, v, x) -> (l^2 t, l v, l^3 x)
takes s = kappa^2 / 4 to s = 1/4, where eq. (GgP) gives G_g of eq. (kernel2) at (kappa v,
kappa u).  The v-integral int_0^inf dx e^(-x cos th) K_(i g)(x) = pi sinh(g th) / (sinh(pi g)
sin th) then leaves ::

    L(sigma | u) = E[e^(-sigma T) | u] = e^(u/2) J(th, kappa u) / (pi u kappa sin th),
    kappa = (1 + 4 sigma)^(1/2),  cos th = -1 / (2 kappa),
    J(th, x) = int_0^inf dg g sinh(g th) K_(i g)(x) / cosh(pi g / 3).              (laplaceT)

At th = 2 pi/3 + eps, sinh(g th) / cosh(pi g / 3) = 2 sinh(g (pi/3 + eps))
- sinh(g eps) / cosh(pi g / 3) exactly, and the Kontorovich-Lebedev identity
int_0^inf dg cosh(a g) K_(i g)(x) = (pi/2) e^(-x cos a) (``|a| < pi/2``), differentiated in a, gives ::

    J(2 pi/3 + eps, x) = pi x sin(pi/3 + eps) e^(-x cos(pi/3 + eps)) - eps S0(x) + O(eps^3),
    S0(x) = int_0^inf dg g^2 K_(i g)(x) / cosh(pi g / 3)
          = 3 e^(-x) [pi x (3x + 2)/12 erfcx((x/2)^(1/2)) + (pi x / 6) erfcx((2x)^(1/2))
                      - (2 pi)^(1/2) x^(3/2) / 4].                                  (S0)

S0 follows from the Fourier pair int_0^inf dg cos(g w) / cosh(pi g / 3) = (3/2) / cosh(3 w / 2),
K_(i g)(x) = int_0^inf dt e^(-x cosh t) cos(g t), two integrations by parts and y = sinh(t/2)
(Gaussian integrals of rational functions of y: erfcx).  As eps = -2 sigma / 3^(1/2) + O(sigma^2),
the O(eps^3) term is O(sigma^3), and -dL/dsigma, d^2L/dsigma^2 at sigma = 0 are ::

    E[T | u] = 2u + 4/3 - 4 e^(u/2) S0(u) / (3 pi u)
             = 2u + 4/3 - e^(-u/2) [(2/3) erfcx((2u)^(1/2)) + (2/3 + u) erfcx((u/2)^(1/2))
                                    - (2u/pi)^(1/2)],                                (meanT)

    E[T^2 | u] = 4u^2 + 32u/3 + 32/3 - 16 e^(u/2) S0(u) / (pi u) + 16 e^(u/2) S0'(u) / (3 pi)
               = 4u^2 + 32u/3 + 32/3 - e^(-u/2) [(16/3 - 8u/3) erfcx((2u)^(1/2))
                 + (16/3 + 16u/3 + 2u^2) erfcx((u/2)^(1/2)) - 2 (2/pi)^(1/2) (u^(1/2) + u^(3/2))]
                                                                                    (meanT2)

(E[T | u]: u -> 0, 3 (2u/pi)^(1/2); u -> inf, 2u + 4/3 + O(e^(-u/2)).  E[T^2 | u]: u -> 0,
18 (2u/pi)^(1/2); u -> inf, Var[T | u] = 16u/3 + 80/9.)  Both are evaluated with
erfcx(x) - 1 and expm1 so that nothing cancels at small u.  ``sech_bessel_moment`` and
``sech_bessel_moment_derivative`` give S0 and S0'; tests/unit/test_flight_time_laplace.py
checks S0 and S0' against quadrature of their g-integrals, (laplaceT) against the Laplace
transform of f(t | u), and (meanT), (meanT2) against their S0 forms.
"""

import numpy as np
from scipy import special

from ..solver import coordinate_of_speed, speed_of_coordinate
from .joint_law import return_time_moment

__all__ = [
    "conditional_moment",
    "sech_bessel_moment",
    "sech_bessel_moment_derivative",
    "mean_flight_time_given_speed",
    "flight_time_second_moment_given_speed",
]


SPEED_STEP = 0.15  # trapezoidal step in s = ln v + v^(1/2) for the conditional moments


SMALLEST_RATIO = 1e-9  # lowest return speed / min(u, 1): (v / u)^(5/2) ~ 1e-22 of the rest


SECH_SERIES_FROM = 80.0  # x above which S0 and S0' are summed from their asymptotic series


SECH_SERIES_TERMS = 35  # terms of that series: truncation about 1e-14 relative at x = 80


def trapezoid_nodes(lowest, highest, step):
    """Nodes and weights of the trapezoidal rule in s = ln x + x^(1/2) over [lowest, highest].

    Parameters
    ----------
    lowest, highest : float
        The ends, 0 < lowest < highest.
    step : float
        The largest step in s.

    Returns
    -------
    x, weights : numpy.ndarray
        The nodes and the weights for dx.
    """
    s_lo, s_hi = coordinate_of_speed(lowest), coordinate_of_speed(highest)
    count = int(np.ceil((s_hi - s_lo) / step)) + 1
    x = speed_of_coordinate(np.linspace(s_lo, s_hi, count))
    weights = np.full(count, (s_hi - s_lo) / (count - 1)) * x / (1.0 + 0.5 * np.sqrt(x))
    weights[[0, -1]] *= 0.5
    return x, weights


def _return_speed_nodes(u, step=SPEED_STEP):
    """Return speeds and weights that integrate functions of v against p(., v | u)."""
    lowest = SMALLEST_RATIO * min(u, 1.0)
    highest = u + 140.0 + 16.0 * np.sqrt(u)  # e^-70 of the return-speed law, Gaussian and tail
    return trapezoid_nodes(lowest, highest, step)


def conditional_moment(u, time_power, speed_power, step=SPEED_STEP):
    """E[T^k v^m | u] for a ball leaving with speed u: the v-integral of eq. (timemoments).

    A trapezoidal rule in s = ln v + v^(1/2) (exponential convergence).

    Parameters
    ----------
    u : float
        The outgoing speed, > 0.
    time_power : int
        k, 0 to 3.
    speed_power : float
        m.
    step : float
        The rule's step in s.

    Returns
    -------
    float

    Examples
    --------
    Ito's formula on v + t: E[T | u] = u + E[v | u].

    >>> from bouncing_ball.flight_time import conditional_moment
    >>> mean_time, mean_speed = conditional_moment(1.0, 1, 0), conditional_moment(1.0, 0, 1)
    >>> print(round(mean_time - mean_speed, 10))
    1.0
    """
    v, weights = _return_speed_nodes(float(u), step)
    return float(np.sum(weights * v**speed_power * return_time_moment(v, u, time_power)))


def _erfcx_minus_one(x):
    """erfcx(x) - 1 without cancellation at small x: expm1(x^2) - e^(x^2) erf(x) below x = 1."""
    x = np.asarray(x, dtype=float)
    small = np.minimum(x, 1.0)
    return np.where(
        x < 1.0,
        np.expm1(small * small) - np.exp(small * small) * special.erf(small),
        special.erfcx(x) - 1.0,
    )


def _flight_time_ingredients(u):
    """e^(-u/2), erfcx((2u)^(1/2)) - 1, erfcx((u/2)^(1/2)) - 1, (2u/pi)^(1/2): eqs. (meanT), (meanT2)."""
    u = np.asarray(u, dtype=float)
    return (
        np.exp(-0.5 * u),
        _erfcx_minus_one(np.sqrt(2.0 * u)),
        _erfcx_minus_one(np.sqrt(0.5 * u)),
        np.sqrt(2.0 * u / np.pi),
    )


def _sech_bessel_series():
    """Coefficients c_j (j = 0..SECH_SERIES_TERMS) of e^x S0(x) = (2 pi)^(1/2) / 4
    sum_j c_j x^(1/2 - j): the asymptotic series erfcx(y) ~ (pi^(1/2) y)^-1 sum_k (-1)^k
    (2k - 1)!! / (2 y^2)^k put into eq. (S0); c_j = 3 a_(j+1) + 2 a_j + a_j / 4^j with
    a_k = (-1)^k (2k - 1)!!, so c_0 = 0 and c_1 = 27/4."""
    k = np.arange(SECH_SERIES_TERMS + 2)
    odd_factorial = np.cumprod(np.where(k == 0, 1.0, 2.0 * k - 1.0))  # (2k - 1)!!, (-1)!! = 1
    a = (-1.0) ** k * odd_factorial
    return 3.0 * a[1:] + 2.0 * a[:-1] + a[:-1] / 4.0 ** k[:-1]


_SECH_SERIES = _sech_bessel_series()


# S0'(x) e^x = (2 pi)^(1/2) / 4 sum_j d_j x^(1/2 - j), d_j = -c_j + (3/2 - j) c_(j-1)
_SECH_SERIES_DERIVATIVE = -_SECH_SERIES + (1.5 - np.arange(_SECH_SERIES.size)) * np.concatenate(
    ([0.0], _SECH_SERIES[:-1])
)


def _sech_series_bracket(x, coefficients):
    """(2 pi)^(1/2) / 12 x^(1/2) sum_j coefficients_j x^(-j): e^x S0(x) / 3 or e^x S0'(x) / 3 at
    large x (``_sech_bessel_series``)."""
    return (
        np.sqrt(2.0 * np.pi)
        / 12.0
        * np.sqrt(x)
        * np.polynomial.polynomial.polyval(1.0 / x, coefficients)
    )


def _sech_bessel_argument(x, name):
    """x as a float array, checked to be >= 0 (S0 and S0' are defined for x >= 0)."""
    x = np.asarray(x, dtype=float)
    if np.any(~(x >= 0.0)):
        raise ValueError(f"{name}: the argument x must be >= 0 (and not NaN), got {x}")
    return x


def sech_bessel_moment(x):
    """S0(x) = int_0^inf dg g^2 K_(i g)(x) / cosh(pi g / 3), eq. (S0) of the module docstring.

    The term linear in eps of J(2 pi/3 + eps, x) in the Laplace transform of the flight time,
    eq. (laplaceT); E[T | u] and E[T^2 | u], eqs. (meanT) and (meanT2), follow from it.

    Parameters
    ----------
    x : array_like
        Argument, x >= 0.

    Returns
    -------
    numpy.ndarray
        S0(x) = 3 e^(-x) [pi x (3x + 2)/12 erfcx((x/2)^(1/2)) + (pi x / 6) erfcx((2x)^(1/2))
        - (2 pi)^(1/2) x^(3/2) / 4], S0(0) = 0, S0(x) = pi x + O(x^(3/2)) at small x.

    Notes
    -----
    At large x the bracket, of order x^(-1/2), is a difference of terms of order x^(3/2): the
    closed form loses a factor x^2 of relative precision.  Above ``SECH_SERIES_FROM`` the bracket
    is summed from its asymptotic series instead, S0(x) ~ (27/8) (pi / (2x))^(1/2) e^(-x)
    [1 + O(1/x)], whose first ``SECH_SERIES_TERMS`` terms are exact to about 1e-14 there.

    Raises
    ------
    ValueError
        If an x is negative or NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.flight_time import sech_bessel_moment
    >>> print(np.round(sech_bessel_moment([0.0, 1.0]), 10))
    [0.         0.25846029]
    >>> bool(np.isclose(sech_bessel_moment(1e-8), np.pi * 1e-8, rtol=1e-3))
    True
    """
    x = _sech_bessel_argument(x, "sech_bessel_moment")
    near = np.minimum(x, SECH_SERIES_FROM)
    far = np.maximum(x, SECH_SERIES_FROM)
    closed = (
        np.pi * near * (3.0 * near + 2.0) / 12.0 * special.erfcx(np.sqrt(0.5 * near))
        + np.pi * near / 6.0 * special.erfcx(np.sqrt(2.0 * near))
        - np.sqrt(2.0 * np.pi) * near**1.5 / 4.0
    )
    series = _sech_series_bracket(far, _SECH_SERIES)
    return 3.0 * np.exp(-x) * np.where(x < SECH_SERIES_FROM, closed, series)


def sech_bessel_moment_derivative(x):
    """S0'(x), the derivative of eq. (S0) (``sech_bessel_moment``), which enters eq. (meanT2).

    Parameters
    ----------
    x : array_like
        Argument, x >= 0.

    Returns
    -------
    numpy.ndarray
        S0'(x) = 3 e^(-x) [pi (4 + 10x - 3x^2)/24 erfcx((x/2)^(1/2))
        + pi (1 + x)/6 erfcx((2x)^(1/2)) + (2 pi)^(1/2) x^(1/2) (x - 5)/8], S0'(0) = pi
        (from d erfcx((c x)^(1/2)) / dx = c erfcx((c x)^(1/2)) - (c / (pi x))^(1/2)).

    Notes
    -----
    Above ``SECH_SERIES_FROM``, the term-by-term derivative of the asymptotic series of
    ``sech_bessel_moment``, for the same reason.

    Raises
    ------
    ValueError
        If an x is negative or NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.flight_time import sech_bessel_moment, sech_bessel_moment_derivative
    >>> bool(np.isclose(sech_bessel_moment_derivative(0.0), np.pi))
    True
    >>> h = 1e-5
    >>> slope = (sech_bessel_moment(2.0 + h) - sech_bessel_moment(2.0 - h)) / (2 * h)
    >>> bool(np.isclose(slope, sech_bessel_moment_derivative(2.0), rtol=1e-8))
    True
    """
    x = _sech_bessel_argument(x, "sech_bessel_moment_derivative")
    near = np.minimum(x, SECH_SERIES_FROM)
    far = np.maximum(x, SECH_SERIES_FROM)
    closed = (
        np.pi * (4.0 + 10.0 * near - 3.0 * near * near) / 24.0 * special.erfcx(np.sqrt(0.5 * near))
        + np.pi * (1.0 + near) / 6.0 * special.erfcx(np.sqrt(2.0 * near))
        + np.sqrt(2.0 * np.pi) * np.sqrt(near) * (near - 5.0) / 8.0
    )
    series = _sech_series_bracket(far, _SECH_SERIES_DERIVATIVE)
    return 3.0 * np.exp(-x) * np.where(x < SECH_SERIES_FROM, closed, series)


def mean_flight_time_given_speed(u):
    """The mean flight time E[T | u] of a ball leaving the floor with speed u, eq. (meanT).

    E[T | u] = 2u + 4/3 - e^(-u/2) [(2/3) erfcx((2u)^(1/2)) + (2/3 + u) erfcx((u/2)^(1/2))
    - (2u/pi)^(1/2)], written without cancellation at small u (where
    E[T | u] = 3 (2u/pi)^(1/2) + O(u)).  E[v | u] = E[T | u] - u (Ito on v + t).  From the
    Laplace transform of T, eq. (laplaceT): = 2u + 4/3 - 4 e^(u/2) S0(u) / (3 pi u) with S0 of
    eq. (S0) (``sech_bessel_moment``).

    Parameters
    ----------
    u : array_like
        Outgoing speeds, >= 0.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    The ballistic 2u + 4/3 at large u, 3 (2u/pi)^(1/2) at small u:

    >>> import numpy as np
    >>> from bouncing_ball.flight_time import mean_flight_time_given_speed
    >>> print(np.round(mean_flight_time_given_speed([1.0, 60.0]), 8))
    [  3.15247858 121.33333333]
    >>> bool(np.isclose(mean_flight_time_given_speed(1e-12), 3 * np.sqrt(2e-12 / np.pi)))
    True
    """
    u = np.asarray(u, dtype=float)
    decay, a, b, root = _flight_time_ingredients(u)
    bracket = (2.0 / 3.0) * (a + b) + u * (1.0 + b) - root
    return 2.0 * u - (4.0 / 3.0) * np.expm1(-0.5 * u) - decay * bracket


def flight_time_second_moment_given_speed(u):
    """The second moment E[T^2 | u] of the flight time given the outgoing speed, eq. (meanT2).

    E[T^2 | u] = 4u^2 + 32u/3 + 32/3 - e^(-u/2) [(16/3 - 8u/3) erfcx((2u)^(1/2))
    + (16/3 + 16u/3 + 2u^2) erfcx((u/2)^(1/2)) - 2 (2/pi)^(1/2) (u^(1/2) + u^(3/2))], without
    cancellation at small u (where it is 18 (2u/pi)^(1/2) + O(u)).  Derived from the Laplace
    transform of T, eq. (laplaceT): = 4u^2 + 32u/3 + 32/3 - 16 e^(u/2) S0(u) / (pi u)
    + 16 e^(u/2) S0'(u) / (3 pi) with S0 of eq. (S0) (``sech_bessel_moment``).

    Parameters
    ----------
    u : array_like
        Outgoing speeds, >= 0.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    At large u the variance is 16u/3 + 80/9:

    >>> from bouncing_ball.flight_time import (
    ...     flight_time_second_moment_given_speed, mean_flight_time_given_speed)
    >>> u = 100.0
    >>> variance = flight_time_second_moment_given_speed(u) - mean_flight_time_given_speed(u) ** 2
    >>> print(round(float(variance), 8), round(16 * u / 3 + 80 / 9, 8))
    542.22222222 542.22222222
    """
    u = np.asarray(u, dtype=float)
    decay, a, b, root = _flight_time_ingredients(u)
    bracket = (
        (16.0 / 3.0) * (a + b)
        - (8.0 / 3.0) * u * (1.0 + a)
        + (16.0 / 3.0 + 2.0 * u) * u * (1.0 + b)
        - 2.0 * root * (1.0 + u)
    )
    return 4.0 * u * u + (32.0 / 3.0) * u - (32.0 / 3.0) * np.expm1(-0.5 * u) - decay * bracket
