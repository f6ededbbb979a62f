"""Flight times between collisions: McKean's first-passage law with gravity, for any r.

Units of the paper (g = Lambda = 1): dx = v dt, dv = -dt + xi dt, <xi(t) xi(t')> = 2 delta(t - t').
A ball leaves the floor with speed u > 0; p(t, v | u) dt dv is the probability that it first
comes back after a flight time in [t, t + dt] with speed (incoming velocity -v) in [v, v + dv].

1. McKean's law without gravity.  For integrated Brownian motion with unit diffusion
   (Var B_t = t) started at x = 0 with velocity a > 0, McKean (J. Math. Kyoto Univ. 2, 227
   (1963), eqs. (5), (6); also Lachal) gives the joint density of the hitting time and speed, ::

       (3 w / (pi sqrt(2) t^2)) exp[-2 (w^2 - a w + a^2) / t] int_0^(4 a w / t) e^(-3 th / 2) dth / (pi th)^(1/2).

   The integral is (2/3)^(1/2) erf[(6 a w / t)^(1/2)].  Our noise has Var = 2 t, i.e. speeds are
   sqrt(2) times McKean's (a = u / sqrt 2, w = v / sqrt 2, density x 1/sqrt 2)::

       p_0(t, v | u) = (sqrt(3) v / (2 pi t^2)) exp[-(v^2 - u v + u^2) / t] erf[(3 u v / t)^(1/2)].

   (= v P_0(0, -v; 0, u; t) of Appendix A.)

2. Gravity, eq. (0g): P_g = exp[-(v - v0)/2 - t/4] P_0 at incoming velocity -v, v0 = u, so
   p(t, v | u) = exp[(v + u)/2 - t/4] p_0(t, v | u).  The exponents combine into a sum of squares, ::

       p(t, v | u) = (sqrt(3) v / (2 pi t^2)) exp{-[(t - u - v)^2 + 3 (v - u)^2] / (4 t)}
                     * erf[(3 u v / t)^(1/2)],                                        (joint)

   every term <= 0: nothing overflows, nothing cancels (the erf of a small argument is
   evaluated to full relative precision by scipy).  In v at fixed t the exponent is
   -(v - v*)^2 / t - 3 (t - 2 u)^2 / (16 t) with v* = (t + 2 u) / 4: the ballistic flight time 2 u
   with a Gaussian spread.

3. Time moments of the return at fixed v, in closed form.  With
   erf(s^(1/2)) = 2 (s / pi)^(1/2) int_0^1 dy e^(-s y^2) and
   int_0^inf dt t^(n - 1) e^(-t/4 - z^2/t) = 2 (2 z)^n K_n(z), ::

       int_0^inf dt t^k p(t, v | u) = (3 v (u v)^(1/2) / pi) e^((v+u)/2) int_0^1 dy e^(-z) h_k(z),
       z^2 = v^2 - v u + u^2 + 3 v u y^2,
       h_0 = (z^-2 + z^-3) / 2,  h_1 = 1 / z,  h_2 = 2,  h_3 = 4 (1 + z)           (timemoments)

   (K_{k-3/2} is elementary).  k = 0 is v G_g(v, u) of eq. (kernel3), so (joint) integrates over
   t to the paper's kernel: this is the check that the time-domain law and its units are right
   (eq. (GgP)).  Each y-integral is made stable exactly as in ``kernel.py`` (y -> z -> tau); the
   result is ::

       int dt t^k p = (2 sqrt(3) v / pi) exp[-(3/4)(v - u)^2 / ((v + u)/2 + z0)]
                      * int_0^tau1 dtau e^(-z0 tau^2) z h_k(z) / (2 + tau^2)^(1/2),
       z = z0 (1 + tau^2).

4. Conditional moments E[T^k v^m | u] are one v-integral of (timemoments), done by the
   trapezoidal rule in s = ln v + v^(1/2) (as the solver's; exponential convergence).  Ito's
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

5. The flight-time density f(t | u) = int_0^inf dv p(t, v | u) by Gauss-Legendre in w = v^(1/2)
   over the window ``|v - v*| < 6.5 t^(1/2)`` (e^-42 of the Gaussian beyond); the integrand
   2 w^3 erf(a w) exp[-(w^2 - v*)^2 / t] is entire in w.

6. Equilibrium.  Collisions with outgoing speed in du come at the rate u P(0, u) du
   (eq. (collrate)), so flights of duration in dT come at the rate ::

       nu(T) = int_0^inf du u P(0, u) f(T | u)                                        (rate)

   per unit time, for every r.  int T nu(T) dT = M_2 + M_2 / r = 1 by eqs. (inteq) and
   (normalization) (the time between collisions fills the time), and int nu dT = I = M_1.
   Above r_c, rho(T) = nu(T) / I is the distribution of the flight time per collision, with mean
   1 / I.  Below r_c (beta >= 2), I is infinite: almost all flights are infinitely short and
   rho(T) = 0 for every T > 0, but nu(T) is finite for T > 0 and T nu(T) is a probability
   density, that of the duration of the flight in progress at a random instant (for r > r_c it
   is T rho(T) / <T>), with mean int T^2 nu dT (= <T^2> / <T> above r_c).

   Short flights: a ball leaving with u << 1 hardly feels gravity, f(T | u) = u^-2 F(T / u^2)
   with F McKean's law, and P(0, u) ~ A u^-beta (eq. (asym1)), so ::

       nu(T) ~ A C_beta T^(-beta/2),   T -> 0,   C_beta = (1/2) E_0[T^(beta/2 - 1) | u = 1]
             = (3 Gamma((5 - beta)/2) / (2 pi^(3/2))) int_0^inf dv v^(3/2) z0^(beta - 5)
               2F1((5 - beta)/2, 1/2; 3/2; -3 v / z0^2),   z0^2 = v^2 - v + 1,       (short)

   with relative corrections O(T^(1/2)).  The divergence T^(-beta/2) is integrable exactly when
   beta < 2, i.e. r > r_c.

   Long flights: at fixed u, f(T | u) ~ (sqrt(3) / (8 sqrt(pi))) T^(-1/2) e^(-3T/16)
   e^(3u/4) erf((3u)^(1/2) / 2).  With P(0, u) ~ B u^-m e^(-q u) (eqs. (asym3)-(asym6)) the
   u-integral converges where q > 3/4, i.e. r < (sqrt 5 - 1) / 2 = 0.618, and then ::

       nu(T) ~ K T^(-1/2) e^(-3T/16),
       K = (sqrt(3) / (8 sqrt(pi))) int du u P(0, u) e^(3u/4) erf((3u)^(1/2) / 2).   (long1)

   For r > 0.618 (q < 3/4) long flights come from fast balls: a saddle at u* = c T,
   c = 1/2 - 2q/3, gives ::

       nu(T) ~ (B / 4) (2 - 4q/3) c^(1-m) T^(1-m) e^(-(q/2 - q^2/3) T).                (long2)

   Both hold with relative corrections O(1/T) (near r = 0.618 they set in only at
   T >> (q - 3/4)^-2); B is read off the solver at its highest node (approximate).
"""

import functools

import numpy as np
import pandas as pd
from scipy import integrate, special

from .asymptotics import large_speed_decay_rate, large_speed_exponent
from .kernel import TAIL, TIME_MOMENT_TAU_NODES, return_speed_kernel_matrix
from .solver import coordinate_of_speed, speed_of_coordinate

__all__ = [
    "GOLDEN_RESTITUTION",
    "free_first_passage_density",
    "log_joint_density",
    "joint_density",
    "return_time_moment",
    "conditional_moment",
    "sech_bessel_moment",
    "sech_bessel_moment_derivative",
    "mean_flight_time_given_speed",
    "flight_time_second_moment_given_speed",
    "log_flight_time_density",
    "flight_time_density",
    "free_flight_time_density",
    "flight_rate_density",
    "flight_rate_in_regimes",
    "SHORT_FLIGHT_TIME",
    "FLIGHT_TIME_TABLE_RANGE",
    "shortest_flight_time",
    "underflow_flight_time",
    "collision_rate",
    "flight_time_density_equilibrium",
    "flight_rate_moment",
    "mean_flight_time",
    "flight_time_second_moment",
    "time_weighted_mean_flight_time",
    "short_time_constant",
    "small_speed_amplitude",
    "short_flight_rate_density",
    "large_speed_amplitude",
    "long_flight_rate_density",
    "long_time_decay_rate",
    "flight_time_summary",
    "flight_time_table",
    "return_speed_table",
    "flight_rate_bin_integrals",
    "flight_time_bin_average",
    "return_speed_bin_law",
    "return_speed_bin_probabilities",
]

SQRT3 = np.sqrt(3.0)
#: (sqrt 5 - 1) / 2 = 0.618...: q(r) = 3/4 (eq. (asym4)), where the long-flight law of
#: eq. (long1) gives way to that of eq. (long2).
GOLDEN_RESTITUTION = 0.5 * (np.sqrt(5.0) - 1.0)

# Gauss-Legendre on [0, 1] for the tau integral of (timemoments)
_TAU_NODES, _TAU_WEIGHTS = np.polynomial.legendre.leggauss(TIME_MOMENT_TAU_NODES)
_TAU_NODES, _TAU_WEIGHTS = 0.5 * (_TAU_NODES + 1.0), 0.5 * _TAU_WEIGHTS
# Gauss-Legendre on [0, 1] for the v-integral of f(t | u), in w = v^(1/2): 40 nodes give 1e-13
_SPEED_NODES, _SPEED_WEIGHTS = np.polynomial.legendre.leggauss(48)
_SPEED_NODES, _SPEED_WEIGHTS = 0.5 * (_SPEED_NODES + 1.0), 0.5 * _SPEED_WEIGHTS
# 16-point Gauss-Legendre on [-1, 1] for bin averages
_BIN_NODES, _BIN_WEIGHTS = np.polynomial.legendre.leggauss(16)

WINDOW = 6.5  # |v - v*| < WINDOW t^(1/2): the Gaussian of f(t | u) beyond is below e^-42
SPEED_STEP = 0.15  # trapezoidal step in s = ln v + v^(1/2) for the conditional moments
RATE_STEP = 0.125  # trapezoidal step in s = ln u + u^(1/2) for nu(T): e^-39 of the rule's error
TIME_STEP = 0.1  # trapezoidal step in s = ln t + t^(1/2) for integrals over f(t | u)
SMALLEST_RATIO = 1e-9  # lowest return speed / min(u, 1): (v / u)^(5/2) ~ 1e-22 of the rest
EXPONENT_CUT = 45.0  # time window: the Gaussian factor of f(t | u) above e^-45
MOMENT_POWERS = range(4)  # k of (timemoments)
SECH_SERIES_FROM = 80.0  # x above which S0 and S0' are summed from their asymptotic series
SECH_SERIES_TERMS = 35  # terms of that series: truncation about 1e-14 relative at x = 80
#: Below this flight time nu(T) is its short-flight law A C_beta T^(-beta/2), eq. (short),
#: whose relative correction (c1 T^(1/2), abs(c1) ~ 0.1 at r = 1/2 and 1/3) is below 1e-15
#: there; above it nu(T) is the quadrature of eq. (rate), which needs P(0, u) down to
#: 1e-4 T^(1/2) (1e-19 here).
SHORT_FLIGHT_TIME = 1e-30
#: The flight times of the pipeline's table (config solver.flight_times, min and max): from
#: SHORT_FLIGHT_TIME (below, the table's rate_density is its short_time_form) to 1e4 (beyond,
#: nu(T) is 0 for r <= 0.618, where it decays like e^(-3T/16), and the quadrature of each T
#: costs T^(1/2) nodes).
FLIGHT_TIME_TABLE_RANGE = (SHORT_FLIGHT_TIME, 1.0e4)
#: nu(T) is 0 beyond UNDERFLOW_MARGIN ln(1/tiny) / kappa (``underflow_flight_time``): twice the
#: flight time where e^(-kappa T) reaches the smallest normal double, which leaves the
#: prefactors of eqs. (long1), (long2) (at most ~e^20 over the solver's range of r) e^-700.
UNDERFLOW_MARGIN = 2.0
RATE_CHUNK_PAIRS = 2**15  # (T, u) pairs of nu(T) evaluated at once: ~13 MB a temporary


# --- the joint law ------------------------------------------------------------------------------


def free_first_passage_density(t, v, u):
    """McKean's first-passage law without gravity, p_0(t, v | u), in the paper's units.

    Item 1 of the module's account (McKean's eqs. (5), (6), with the noise of eq. (eqmo)).

    Parameters
    ----------
    t : array_like
        Flight times.
    v : array_like
        Return speeds (the incoming velocity is -v).
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        p_0(t, v | u), broadcast; 0 where t, v or u is not positive.
    """
    t, v, u = (np.asarray(a, dtype=float) for a in (t, v, u))
    with np.errstate(divide="ignore", invalid="ignore"):
        value = (
            SQRT3
            * v
            / (2.0 * np.pi * t * t)
            * np.exp(-(v * v - u * v + u * u) / t)
            * special.erf(np.sqrt(3.0 * u * v / t))
        )
    return np.where((t > 0.0) & (v > 0.0) & (u > 0.0), value, 0.0)


def log_joint_density(t, v, u):
    """ln p(t, v | u) of eq. (joint): McKean's law with gravity through eqs. (0g), (GgP).

    Parameters
    ----------
    t : array_like
        Flight times.
    v : array_like
        Return speeds (the incoming velocity is -v).
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        ln p(t, v | u), broadcast; -inf where t, v or u is not positive.
    """
    t, v, u = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (t, v, u)))
    valid = (t > 0.0) & (v > 0.0) & (u > 0.0)
    t, v, u = (np.where(valid, a, 1.0) for a in (t, v, u))
    exponent = -((t - u - v) ** 2 + 3.0 * (v - u) ** 2) / (4.0 * t)
    with np.errstate(divide="ignore"):
        value = (
            np.log(SQRT3 * v / (2.0 * np.pi))
            - 2.0 * np.log(t)
            + exponent
            + np.log(special.erf(np.sqrt(3.0 * u * v / t)))
        )
    return np.where(valid, value, -np.inf)


def joint_density(t, v, u):
    """The joint density p(t, v | u) of eq. (joint): flight time and return speed.

    p(t, v | u) dt dv is the probability that a ball leaving the floor with speed u first
    comes back after a time in [t, t + dt] with speed in [v, v + dv].

    Parameters
    ----------
    t : array_like
        Flight times.
    v : array_like
        Return speeds (the incoming velocity is -v).
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        p(t, v | u), broadcast; 0 where t, v or u is not positive.

    Examples
    --------
    Gravity multiplies the free law by exp[(v + u)/2 - t/4], eq. (0g):

    >>> import numpy as np
    >>> from bouncing_ball.flight_time import free_first_passage_density, joint_density
    >>> ratio = joint_density(2.0, 1.0, 1.0) / free_first_passage_density(2.0, 1.0, 1.0)
    >>> bool(np.isclose(ratio, np.exp(1.0 - 0.5)))
    True
    """
    return np.exp(log_joint_density(t, v, u))


def return_time_moment(v, u, k):
    """The time moments int_0^inf dt t^k p(t, v | u) of eq. (timemoments), k = 0..3.

    k = 0 is v G_g(v, u) of eq. (kernel3): the return-speed law (eq. (GgP)).

    Parameters
    ----------
    v : array_like
        Return speeds.
    u : array_like
        Outgoing speeds.
    k : int
        The power of t, 0 to 3.

    Returns
    -------
    numpy.ndarray
        Broadcast over v and u; 0 where v or u is not positive.

    Raises
    ------
    ValueError
        If k is not 0, 1, 2 or 3.

    Examples
    --------
    k = 0 integrates over v to 1 (eq. (normG)), k = 1 to E[T | u] (eq. (meanT)):

    >>> from bouncing_ball.flight_time import (
    ...     mean_flight_time_given_speed, return_time_moment, trapezoid_nodes)
    >>> v, weights = trapezoid_nodes(1e-9, 160.0, 0.15)
    >>> print(round(weights @ return_time_moment(v, 1.0, 0), 10))
    1.0
    >>> mean = weights @ return_time_moment(v, 1.0, 1)
    >>> print(round(mean, 8), round(float(mean_flight_time_given_speed(1.0)), 8))
    3.15247858 3.15247858
    """
    if k not in MOMENT_POWERS:
        raise ValueError(f"time power k must be one of {list(MOMENT_POWERS)}, got {k}")
    v, u = np.broadcast_arrays(np.asarray(v, dtype=float), np.asarray(u, dtype=float))
    valid = (v > 0.0) & (u > 0.0)
    v, u = np.where(valid, v, 1.0)[..., None], np.where(valid, u, 1.0)[..., None]
    difference = v - u
    z0 = np.sqrt(difference * difference + v * u)
    tau1 = np.sqrt(3.0 * v * u / ((v + u + z0) * z0))
    upper = np.minimum(tau1, TAIL / np.sqrt(z0))
    tau2 = (upper * _TAU_NODES) ** 2
    z = z0 * (1.0 + tau2)
    shape = {0: (1.0 + z) / (2.0 * z * z), 1: 1.0, 2: 2.0 * z, 3: 4.0 * z * (1.0 + z)}[k]
    integrand = np.exp(-z0 * tau2) * shape / np.sqrt(2.0 + tau2)
    gauss = np.exp(-0.75 * difference * difference / (0.5 * (v + u) + z0))
    value = (2.0 * SQRT3 / np.pi) * (v * gauss * upper)[..., 0] * (integrand @ _TAU_WEIGHTS)
    return np.where(valid, value, 0.0)


# --- conditional moments given u ----------------------------------------------------------------


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


# --- the flight-time density given u -------------------------------------------------------------


def _log_speed_integral(t, u, centre):
    """ln int_0^inf dv v exp[-(v - centre)^2 / t] erf((3 u v / t)^(1/2)), vectorised: Gauss-Legendre
    in w = v^(1/2) (the integrand 2 w^3 erf(a w) exp[-(w^2 - centre)^2 / t] is entire in w) over
    |v - centre| < WINDOW t^(1/2)."""
    half_width = WINDOW * np.sqrt(t)
    w_lo = np.sqrt(np.maximum(centre - half_width, 0.0))[..., None]
    w_hi = np.sqrt(centre + half_width)[..., None]
    w = w_lo + (w_hi - w_lo) * _SPEED_NODES
    v = w * w
    integrand = (
        2.0
        * w
        * v
        * special.erf(np.sqrt(3.0 * u / t)[..., None] * w)
        * np.exp(-((v - centre[..., None]) ** 2) / t[..., None])
    )
    with np.errstate(divide="ignore"):
        return np.log((w_hi - w_lo)[..., 0] * (integrand @ _SPEED_WEIGHTS))


def log_flight_time_density(t, u):
    """ln f(t | u), the log of the flight-time density given the outgoing speed.

    f(t | u) = int_0^inf dv p(t, v | u) of eq. (joint), by Gauss-Legendre in w = v^(1/2) (item 5
    of the module's account).

    Parameters
    ----------
    t : array_like
        Flight times.
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        Broadcast; -inf where t or u is not positive.
    """
    t, u = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(u, dtype=float))
    valid = (t > 0.0) & (u > 0.0)
    t, u = np.where(valid, t, 1.0), np.where(valid, u, 1.0)
    gauss = -3.0 * (t - 2.0 * u) ** 2 / (16.0 * t)
    value = np.log(SQRT3 / (2.0 * np.pi)) - 2.0 * np.log(t) + gauss
    value = value + _log_speed_integral(t, u, 0.25 * (t + 2.0 * u))
    return np.where(valid, value, -np.inf)


def flight_time_density(t, u):
    """f(t | u): the density of the flight time of a ball leaving the floor with speed u.

    The integral over the return speed of eq. (joint) (see ``log_flight_time_density``).

    Parameters
    ----------
    t : array_like
        Flight times.
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        Broadcast; 0 where t or u is not positive.

    Examples
    --------
    It is normalised, with the mean of eq. (meanT):

    >>> from bouncing_ball.flight_time import flight_time_density, flight_time_nodes
    >>> t, weights = flight_time_nodes(1.0)
    >>> f = weights * flight_time_density(t, 1.0)
    >>> print(round(f.sum(), 10), round(f @ t, 8))
    1.0 3.15247858
    """
    return np.exp(log_flight_time_density(t, u))


def free_flight_time_density(t, u):
    """f_0(t | u) = int dv p_0(t, v | u): McKean's flight-time law without gravity.

    The short-flight limit of ``flight_time_density`` (eq. (short)).

    Parameters
    ----------
    t : array_like
        Flight times, > 0.
    u : array_like
        Outgoing speeds, > 0.

    Returns
    -------
    numpy.ndarray
    """
    t, u = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(u, dtype=float))
    value = (
        np.log(SQRT3 / (2.0 * np.pi))
        - 2.0 * np.log(t)
        - 0.75 * u * u / t
        + _log_speed_integral(t, u, 0.5 * u)
    )
    return np.exp(value)


def _flight_time_window(u, cut=EXPONENT_CUT):
    """[t_lo, t_hi] outside which 3 (t - 2u)^2 / (16 t) > cut: f(t | u) is negligible there."""
    b = 4.0 * u + 16.0 * cut / 3.0
    t_hi = 0.5 * (b + np.sqrt(b * b - 16.0 * u * u))
    return 4.0 * u * u / t_hi, t_hi


def flight_time_nodes(u, step=TIME_STEP):
    """Flight times and weights that integrate functions of t against f(t | u).

    A trapezoidal rule in s = ln t + t^(1/2) over the times where the Gaussian factor of
    f(t | u) is above e^-45.

    Parameters
    ----------
    u : float
        The outgoing speed.
    step : float
        The rule's step in s.

    Returns
    -------
    t, weights : numpy.ndarray
    """
    return trapezoid_nodes(*_flight_time_window(u), step)


# --- equilibrium ---------------------------------------------------------------------------------


def _outgoing_weights(solution):
    """u_j P(0, u_j) w_j: the collision rate carried by each node of the solver."""
    u = solution.speeds
    return u, solution.quadrature_weights * u * solution.density


def _lower_tail_factor(solution, exponent):
    """Sum over the solver's rule continued below its lowest node u_0 of
    w u P(0, u) (u / u_0)^exponent, divided by P(0, u_0); P is the power law u^-beta there (as in
    the solver), du/ds = u."""
    decay = 2.0 - solution.small_speed_exponent + exponent
    if decay <= 0.0:
        return np.inf
    return solution.step * solution.speeds[0] ** 2 / np.expm1(decay * solution.step)


def _outgoing_lattice(solution, first, last, step):
    """Nodes u_k = u(k step), s = ln u + u^(1/2), for k = first..last, and the collision rate
    w_k u_k P(0, u_k) each carries: P from the solver's Nystrom formula up to its highest node
    u_max, continued above by its large-speed form (eq. (asym3))
    P(0, u_max) (u / u_max)^-m e^(-q (u - u_max)).  The lattice is fixed (k step, whatever
    the times asked for), so that each T is integrated on nodes of its own."""
    r, u_max = solution.restitution, solution.speeds[-1]
    u = speed_of_coordinate(step * np.arange(first, last + 1))
    inside = u <= u_max
    density = np.empty(u.size)
    density[inside] = solution.outgoing_speed_density(u[inside])
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    beyond = u[~inside] / u_max
    density[~inside] = solution.density[-1] * beyond**-m * np.exp(-q * u_max * (beyond - 1.0))
    return u, step * u / (1.0 + 0.5 * np.sqrt(u)) * u * density


def _rate_windows(solution, times, step):
    """The lattice indices [first, last] of ``_outgoing_lattice`` that each T integrates over:
    from u_lo = min(u_0, 1e-4 T^(1/2)) (u_0 the solver's lowest node) to T/2 + 10 T^(1/2),
    beyond which f(T | u) < e^-75 of its peak."""
    lowest = np.minimum(solution.speeds[0], 1e-4 * np.sqrt(times))
    highest = 0.5 * times + 10.0 * np.sqrt(times)
    first = np.floor(coordinate_of_speed(lowest) / step).astype(np.int64)
    last = np.ceil(coordinate_of_speed(highest) / step).astype(np.int64)
    return first, last


def _direct_flight_rate_density(solution, times, step):
    """nu(T) of eq. (rate) by the trapezoidal rule of ``flight_rate_density``, each T on its own
    window of the lattice (``_rate_windows``), in chunks of at most ``RATE_CHUNK_PAIRS``
    (T, u) pairs (a T whose window is longer is a chunk of its own)."""
    times = np.asarray(times, dtype=float)
    first, last = _rate_windows(solution, times, step)
    u, rate = _outgoing_lattice(solution, int(first.min()), int(last.max()), step)
    start = first - first.min()  # each window's first node in u
    sizes = last - first + 1
    # the rule below u_lo: sum_k>=1 of rate_0 (u_-k / u_lo)^(5/2 - beta) (1 + u_lo^(1/2) / 2)
    decay = 2.5 - solution.small_speed_exponent
    tail = rate[start] * (1.0 + 0.5 * np.sqrt(u[start])) / np.expm1(decay * step)
    result = np.empty(times.size)
    chunk_ends = np.cumsum(sizes) // RATE_CHUNK_PAIRS
    for chunk in np.unique(chunk_ends):
        rows = np.flatnonzero(chunk_ends == chunk)
        offsets = np.concatenate(([0], np.cumsum(sizes[rows])))
        row_of_pair = np.repeat(rows, sizes[rows])
        column = start[row_of_pair] + np.arange(offsets[-1]) - np.repeat(offsets[:-1], sizes[rows])
        f = flight_time_density(times[row_of_pair], u[column])
        result[rows] = (
            np.add.reduceat(f * rate[column], offsets[:-1]) + tail[rows] * f[offsets[:-1]]
        )
    return result


def flight_rate_in_regimes(times, direct, short_amplitude, beta, restitution):
    """nu(T) of eq. (rate) from its three regimes, each T on its own.

    Eq. (short) below ``SHORT_FLIGHT_TIME``, ``direct`` up to ``underflow_flight_time``, 0
    beyond it (and wherever nu is below the smallest normal double).  The one home of the
    domain of nu(T), for ``flight_rate_density`` and ``equilibrium.ExactEquilibrium``.

    Parameters
    ----------
    times : array_like
        Flight times, ``shortest_flight_time(short_amplitude, beta) <= T``.
    direct : callable
        nu of a 1-d array of T in [SHORT_FLIGHT_TIME, underflow_flight_time], by quadrature
        of eq. (rate).
    short_amplitude : float
        A C_beta of eq. (short).
    beta : float
        The small-speed exponent of eq. (asym2).
    restitution : float
        r (for ``underflow_flight_time``).

    Returns
    -------
    numpy.ndarray
        nu(T), shaped like ``times``; finite.

    Raises
    ------
    ValueError
        If a T is not positive or lies below ``shortest_flight_time``, where nu(T) exceeds the
        largest double.
    """
    times = np.asarray(times, dtype=float)
    shortest = shortest_flight_time(short_amplitude, beta)
    bad = ~(times >= max(shortest, np.finfo(float).smallest_subnormal))
    if bad.any():
        raise ValueError(
            f"times: nu(T) is finite for T >= {shortest:.3g} (T > 0; below, A C_beta "
            f"T^(-beta/2) of eq. (short) exceeds the largest double), got {times[bad].flat[0]!r}"
        )
    result = np.zeros(times.shape)
    short = times < SHORT_FLIGHT_TIME
    result[short] = _short_law(short_amplitude, beta, times[short])
    middle = ~short & (times <= underflow_flight_time(restitution))
    if middle.any():
        result[middle] = direct(times[middle])
    return np.where(result >= np.finfo(float).tiny, result, 0.0)


def flight_rate_density(solution, times, step=RATE_STEP):
    """nu(T) of eq. (rate): flights of duration in dT per unit time, for any r.

    nu(T) = int_0^inf du u P(0, u) f(T | u), finite for T > 0 (also below r_c), in three
    regimes (``flight_rate_in_regimes``), each T on its own (a value never depends on the
    others asked for with it):

    - ``SHORT_FLIGHT_TIME`` <= T <= ``underflow_flight_time(r)``: the u-integral is a
      trapezoidal rule in s = ln u + u^(1/2) of step ``step`` on the fixed lattice s = k step,
      finer than the solver's (f(T | u) falls like exp(-3 u^2 / 4T) for u >> T^(1/2), which the
      solver's step 0.25 resolves only to ~1e-8), with P(0, u) from the solver's Nystrom
      formula, from u_lo = min(u_0, 1e-4 T^(1/2)) to T/2 + 10 T^(1/2).  Below u_lo the rule is
      summed in closed form with f(T | u) = f(T | u_lo) (u / u_lo)^(1/2) (relative error
      O(u_lo / T^(1/2))) and P(0, u) its power law.  Above the solver's highest node u_max,
      P(0, u) is continued by its large-speed form (long flights come from fast balls where
      q(r) < 3/4, i.e. r > 0.618); where that matters (T >~ u_max / (1/2 - 2q/3)) nu(T) is
      only as good as that form (and below e^-690 of its peak).  Accurate to ~1e-9 relative
      with the solver's P(0, u).
    - T < ``SHORT_FLIGHT_TIME``: eq. (short), A C_beta T^(-beta/2), its relative correction
      O(T^(1/2)) below 1e-14 (A read off the solver's lowest node, ``small_speed_amplitude``).
    - T > ``underflow_flight_time(r)``: 0 (nu decays like e^(-kappa T), eqs. (long1),
      (long2), and is below the smallest normal double there); so is any nu below that double.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times, T >= ``shortest_flight_time`` (> 0; below it nu(T) exceeds the largest
        double: 0 unless beta > 1.9, i.e. r < 0.2; 2.4e-258 at r = 0.02).
    step : float
        The rule's step in s.

    Returns
    -------
    numpy.ndarray
        nu(T), shaped like ``times``; finite.

    Raises
    ------
    ValueError
        If a T is not positive or lies below ``shortest_flight_time``.
    """
    beta = solution.small_speed_exponent
    return flight_rate_in_regimes(
        times,
        lambda t: _direct_flight_rate_density(solution, t, step),
        small_speed_amplitude(solution) * short_time_constant(beta),
        beta,
        solution.restitution,
    )


def collision_rate(solution):
    """The collision rate I = M_1 of eq. (collrate).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
        I; inf below r_c (eq. (rc)).
    """
    return solution.moment(1)


def flight_time_density_equilibrium(solution, times):
    """rho(T) = nu(T) / I: the distribution of the flight time per collision, eq. (rate).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times T > 0.

    Returns
    -------
    numpy.ndarray
        rho(T); 0 below r_c, where I = inf.
    """
    rate = collision_rate(solution)
    nu = flight_rate_density(solution, times)
    return nu / rate if np.isfinite(rate) else np.zeros_like(nu)


def flight_rate_moment(solution, k):
    """int_0^inf T^k nu(T) dT = int du u P(0, u) E[T^k | u], k = 0..3, for any r.

    k = 0 is I (inf below r_c); k = 1 is 1 for every r (a check); k = 2 is the mean duration of
    the flight in progress at a random instant.  E[T^k | u] from eqs. (meanT), (meanT2) for
    k = 1, 2, by quadrature (``conditional_moment``) for k = 3.  Below u_0,
    E[T^k | u] ~ u^(1/2) (k >= 1).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    k : int
        The power of T, 0 to 3.

    Returns
    -------
    float
    """
    if k == 0:
        return collision_rate(solution)
    u, rate = _outgoing_weights(solution)
    if k == 1:
        moments = mean_flight_time_given_speed(u)
    elif k == 2:
        moments = flight_time_second_moment_given_speed(u)
    else:
        moments = np.array([conditional_moment(x, k, 0) for x in u])
    tail = _lower_tail_factor(solution, 0.5) * solution.density[0] * moments[0]
    return float(rate @ moments + tail)


def mean_flight_time(solution):
    """The mean flight time per collision, <T> = int T nu dT / I, eq. (rate).

    By the momentum balance it is 1 / I, eqs. (inteq), (normalization).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
        <T>; 0 below r_c (I = inf).

    Examples
    --------
    At r = 1/2, I = 1/3 (eq. (xandDeltax)):

    >>> from bouncing_ball import Equilibrium
    >>> from bouncing_ball.flight_time import mean_flight_time
    >>> print(round(mean_flight_time(Equilibrium(0.5).solution), 8))
    3.0
    """
    rate = collision_rate(solution)
    return flight_rate_moment(solution, 1) / rate if np.isfinite(rate) else 0.0


def flight_time_second_moment(solution):
    """The second moment of the flight time per collision, <T^2> = int T^2 nu dT / I.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
        <T^2>; 0 below r_c (I = inf).
    """
    rate = collision_rate(solution)
    return flight_rate_moment(solution, 2) / rate if np.isfinite(rate) else 0.0


def time_weighted_mean_flight_time(solution):
    """The mean duration of the flight in progress at a random instant, int T^2 nu dT.

    Defined for any r; <T^2> / <T> above r_c.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
    """
    return flight_rate_moment(solution, 2)


# --- asymptotic forms ----------------------------------------------------------------------------


@functools.lru_cache(maxsize=256)  # a pure function of beta, asked for at each call of nu(T)
def short_time_constant(beta):
    """The constant C_beta of the short-flight law, eq. (short).

    C_beta = int_0^inf du u^(1 - beta) f_0(1 | u) = (1/2) E_0[T^(beta/2 - 1) | u = 1], by
    quadrature of its hypergeometric form.

    Parameters
    ----------
    beta : float
        The small-speed exponent of eq. (asym2), below 5/2.

    Returns
    -------
    float
    """
    a = 0.5 * (5.0 - beta)

    def integrand(v):
        z0_squared = v * v - v + 1.0
        return v**1.5 * z0_squared ** (-a) * special.hyp2f1(a, 0.5, 1.5, -3.0 * v / z0_squared)

    head, _ = integrate.quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-12, limit=200)
    tail, _ = integrate.quad(integrand, 1.0, np.inf, epsabs=0.0, epsrel=1e-12, limit=200)
    return 3.0 * special.gamma(a) / (2.0 * np.pi**1.5) * (head + tail)


def small_speed_amplitude(solution):
    """The amplitude A of P(0, u) ~ A u^-beta at small u, eq. (asym1).

    Read off the solver's lowest node (where that law is built in).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
    """
    return solution.density[0] * solution.speeds[0] ** solution.small_speed_exponent


def short_flight_rate_density(solution, times):
    """The short-flight law nu(T) ~ A C_beta T^(-beta/2) for T -> 0, eq. (short).

    Relative corrections are O(T^(1/2)).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times T > 0.

    Returns
    -------
    numpy.ndarray
    """
    beta = solution.small_speed_exponent
    amplitude = small_speed_amplitude(solution) * short_time_constant(beta)
    return _short_law(amplitude, beta, np.asarray(times, dtype=float))


def _short_law(amplitude, beta, times):
    """amplitude T^(-beta/2) of eq. (short), as (amplitude^(1/2) T^(-beta/4))^2: finite
    wherever the product is (T^(-beta/2) alone overflows first where amplitude < 1), to a few
    ulp."""
    return (np.sqrt(amplitude) * times ** (-0.25 * beta)) ** 2


def large_speed_amplitude(solution):
    """The amplitude B of P(0, u) ~ B u^-m e^(-q u) at large u, eq. (asym3).

    Read off the solver's highest node (approximate).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
    """
    r, u = solution.restitution, solution.speeds[-1]
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    return solution.density[-1] * u**m * np.exp(q * u)


def long_flight_rate_density(solution, times):
    """The long-flight law of nu(T) for T -> infinity, eqs. (long1) and (long2).

    Eq. (long1), K T^(-1/2) e^(-3T/16), where q(r) > 3/4 (r < 0.618); eq. (long2) above.
    Relative corrections are O(1/T).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times T > 0.

    Returns
    -------
    numpy.ndarray
    """
    times = np.asarray(times, dtype=float)
    r = solution.restitution
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    if q > 0.75:
        u, rate = _outgoing_weights(solution)
        weight = np.exp(0.75 * u) * special.erf(0.5 * np.sqrt(3.0 * u))
        # above u_max: P = B u^-m e^(-q u), erf = 1 (to e^-(3 u_max / 4)), an incomplete Gamma
        a, x = 2.0 - m, (q - 0.75) * u[-1]
        beyond = large_speed_amplitude(solution) * special.gammaincc(a, x) * special.gamma(a)
        beyond /= (q - 0.75) ** a
        constant = SQRT3 / (8.0 * np.sqrt(np.pi)) * (float(rate @ weight) + beyond)
        return constant * times**-0.5 * np.exp(-3.0 * times / 16.0)
    c = 0.5 - 2.0 * q / 3.0
    amplitude = 0.25 * large_speed_amplitude(solution) * (2.0 - 4.0 * q / 3.0) * c ** (1.0 - m)
    return amplitude * times ** (1.0 - m) * np.exp(-(0.5 * q - q * q / 3.0) * times)


def long_time_decay_rate(restitution):
    """The decay rate kappa of nu(T) ~ e^(-kappa T) at long flight times.

    Parameters
    ----------
    restitution : float
        r, in (0, 1).

    Returns
    -------
    float
        3/16 (eq. (long1)) where q(r) > 3/4, q/2 - q^2/3 (eq. (long2)) where q(r) < 3/4
        (r > ``GOLDEN_RESTITUTION`` = 0.618).

    Examples
    --------
    >>> from bouncing_ball.flight_time import long_time_decay_rate
    >>> print(long_time_decay_rate(0.5), round(long_time_decay_rate(0.8), 10))
    0.1875 0.1360544218
    """
    q = large_speed_decay_rate(restitution)
    return 3.0 / 16.0 if q > 0.75 else 0.5 * q - q * q / 3.0


def underflow_flight_time(restitution):
    """The flight time beyond which nu(T) is below the smallest normal double, and is 0.

    ``UNDERFLOW_MARGIN`` ln(1/tiny) / kappa, with kappa of ``long_time_decay_rate``: nu(T)
    ~ K T^a e^(-kappa T), eqs. (long1), (long2).

    Parameters
    ----------
    restitution : float
        r, in (0, 1).

    Returns
    -------
    float

    Examples
    --------
    >>> from bouncing_ball.flight_time import underflow_flight_time
    >>> print(round(underflow_flight_time(0.5)))
    7556
    """
    return UNDERFLOW_MARGIN * -np.log(np.finfo(float).tiny) / long_time_decay_rate(restitution)


def shortest_flight_time(amplitude, beta):
    """The flight time below which amplitude T^(-beta/2) exceeds the largest double.

    nu(T) ~ A C_beta T^(-beta/2) at short T (eq. (short)): below this T it is not a float.

    Parameters
    ----------
    amplitude : float
        A C_beta (or A C_beta / I for rho(T)), > 0.
    beta : float
        The small-speed exponent of eq. (asym2), >= 0.

    Returns
    -------
    float
        0 where even the smallest double gives a finite value.

    Examples
    --------
    >>> from bouncing_ball.flight_time import shortest_flight_time
    >>> print(shortest_flight_time(1.0, 1.0), f"{shortest_flight_time(1.0, 2.4):.3g}")
    0.0 1.32e-257
    """
    if beta <= 0.0:
        return 0.0
    exponent = 2.0 / beta * (np.log(amplitude) - np.log(np.finfo(float).max))
    return float(np.exp(exponent)) if exponent > np.log(np.finfo(float).smallest_subnormal) else 0.0


def flight_time_summary(solution):
    """The flight-time statistics of one r, as one row.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    dict
        r, collision_rate (I), mean_flight_time (<T> = 1/I; 0 below r_c),
        flight_time_second_moment (<T^2> per collision; 0 below r_c),
        time_weighted_mean_flight_time (the flight in progress at a random instant, any r),
        short_time_exponent (beta/2 of nu ~ T^(-beta/2), eq. (short)), short_time_amplitude
        (A C_beta) and long_time_decay_rate (kappa, eqs. (long1), (long2)).
    """
    beta = solution.small_speed_exponent
    return {
        "r": solution.restitution,
        "collision_rate": collision_rate(solution),
        "mean_flight_time": mean_flight_time(solution),
        "flight_time_second_moment": flight_time_second_moment(solution),
        "time_weighted_mean_flight_time": time_weighted_mean_flight_time(solution),
        "short_time_exponent": 0.5 * beta,
        "short_time_amplitude": small_speed_amplitude(solution) * short_time_constant(beta),
        "long_time_decay_rate": long_time_decay_rate(solution.restitution),
    }


# --- tables and bin averages for the pipeline -----------------------------------------------------


def flight_time_table(solution, times):
    """The flight-time densities of eq. (rate) and their asymptotic forms, as a table.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times T > 0.

    Returns
    -------
    pandas.DataFrame
        Columns t, density (rho(T); NaN below r_c, where it is not defined), rate_density
        (nu(T)), time_weighted_density (T nu(T), a probability density for every r), and the
        short- and long-time forms of nu(T) (short_time_form, eq. (short); long_time_form,
        eqs. (long1), (long2)) for the figure.
    """
    times = np.asarray(times, dtype=float)
    nu = flight_rate_density(solution, times)
    rate = collision_rate(solution)
    density = nu / rate if np.isfinite(rate) else np.full_like(nu, np.nan)
    return pd.DataFrame(
        {
            "t": times,
            "density": density,
            "rate_density": nu,
            "time_weighted_density": times * nu,
            "short_time_form": short_flight_rate_density(solution, times),
            "long_time_form": long_flight_rate_density(solution, times),
        }
    )


def return_speed_table(solution, speed_bins):
    """The return-speed law v G_g(v, u) of eq. (kernel3) on a simulation's speed bins.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    speed_bins : bins.LogBins
        The simulation's bins of speeds.

    Returns
    -------
    pandas.DataFrame
        Columns u_lo, u_hi, v_lo, v_hi, probability (``return_speed_bin_probabilities`` with
        the solver's P(0, u)), for every finite u-bin and every v-bin (under- and overflow
        included).
    """
    u_lo, u_hi = speed_bins.edges[:-1], speed_bins.edges[1:]
    v_lo, v_hi = speed_bins.lower, speed_bins.upper
    cells = return_speed_bin_probabilities(solution.outgoing_speed_density, u_lo, u_hi, v_lo, v_hi)
    rows, columns = np.indices(cells.shape)
    return pd.DataFrame(
        {
            "u_lo": u_lo[rows.ravel()],
            "u_hi": u_hi[rows.ravel()],
            "v_lo": v_lo[columns.ravel()],
            "v_hi": v_hi[columns.ravel()],
            "probability": cells.ravel(),
        }
    )


def _log_gauss(lower, upper, points=16):
    """Gauss-Legendre in ln x on each finite bin, 16 points unless ``points`` says otherwise:
    nodes (bins x points) and weights for dx."""
    lower = np.asarray(lower, dtype=float)[:, None]
    upper = np.asarray(upper, dtype=float)[:, None]
    half = 0.5 * np.log(upper / lower)
    nodes, weights = (
        (_BIN_NODES, _BIN_WEIGHTS) if points == 16 else np.polynomial.legendre.leggauss(points)
    )
    x = np.exp(half * nodes[None, :] + 0.5 * np.log(upper * lower))
    return x, half * x * weights[None, :]


def flight_rate_bin_integrals(solution, lower, upper):
    """The integral of nu(T) dT over each bin: flights per unit time with duration in the bin.

    For any r.  Finite bins: 16-point Gauss-Legendre in ln T.  An underflow bin (lo = 0):
    twelve decades below hi the same way, and below those eq. (short) in closed form (inf
    below r_c, where nu is not integrable at T = 0).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    lower, upper : array_like
        The bins' edges [lo, hi); lo = 0 allowed.

    Returns
    -------
    numpy.ndarray
        One value per bin; NaN for an overflow bin (hi = inf), which is not supported.
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    result = np.full(lower.shape, np.nan)
    finite = (lower > 0.0) & np.isfinite(upper)
    if np.any(finite):
        t, weights = _log_gauss(lower[finite], upper[finite])
        result[finite] = np.sum(flight_rate_density(solution, t) * weights, axis=1)
    beta = solution.small_speed_exponent
    for index in np.flatnonzero((lower <= 0.0) & np.isfinite(upper)):
        edges = upper[index] * np.logspace(-12.0, 0.0, 13)
        t, weights = _log_gauss(edges[:-1], edges[1:])
        above = np.sum(flight_rate_density(solution, t) * weights)
        if beta >= 2.0:
            result[index] = np.inf
        else:
            head = short_flight_rate_density(solution, edges[0]) * edges[0] / (1.0 - 0.5 * beta)
            result[index] = above + head
    return result


def flight_time_bin_average(solution, lower, upper):
    """rho(T) averaged over each bin, what a histogram of simulated flight times measures.

    int_bin rho dT / (hi - lo), rho = nu / I the flight-time distribution per collision.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    lower, upper : array_like
        The bins' edges [lo, hi); lo = 0 (underflow) allowed, hi = inf not (NaN).

    Returns
    -------
    numpy.ndarray
        Defined above r_c; below, I = inf and this is 0 (use ``flight_rate_bin_integrals``).
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    rate = collision_rate(solution)
    if not np.isfinite(rate):
        return np.where(np.isfinite(upper), 0.0, np.nan)
    return flight_rate_bin_integrals(solution, lower, upper) / rate / (upper - lower)


def _speed_sub_bins(lower, upper, panels=10, efolds=40.0):
    """Finite sub-bins covering each v-bin: itself if finite; an underflow bin [0, hi) by
    ``panels`` log-panels over ``efolds`` e-folds below hi (v G_g ~ v^(3/2): e^-100 beyond);
    an overflow bin by none.  Returns their edges and the index of the bin each belongs to."""
    lo, hi, owner = [], [], []
    for index, (a, b) in enumerate(zip(lower, upper)):
        if not np.isfinite(b):
            continue
        underflow = b * np.exp(np.linspace(-efolds, 0.0, panels + 1))
        edges = np.array([a, b]) if a > 0.0 else underflow
        lo.extend(edges[:-1])
        hi.extend(edges[1:])
        owner.extend([index] * (edges.size - 1))
    return np.array(lo), np.array(hi), np.array(owner, dtype=int)


#: Chebyshev nodes per panel in ln u of ``return_speed_bin_law(..., interpolated=True)``.
LAW_PANEL_NODES = 24


def _law_panel_edges():
    """The panels in ln u on which ``return_speed_bin_law`` interpolates: from 1e-12 to 1e5,
    each min(1, 2 u^(-1/2)) wide at its lower end u (the law of a ball leaving at speed
    u >> 1 varies over |v - u| ~ u^(1/2)).  One fixed set, whatever the points, so that a
    point's value does not depend on which others are asked for."""
    edges = [np.log(1e-12)]
    while edges[-1] < np.log(1e5):
        edges.append(edges[-1] + min(1.0, 2.0 * np.exp(-0.5 * edges[-1])))
    return np.array(edges)


_LAW_PANEL_EDGES = _law_panel_edges()
_LAW_PANEL_X = np.cos(np.pi * (np.arange(LAW_PANEL_NODES) + 0.5) / LAW_PANEL_NODES)
_LAW_PANEL_VANDERMONDE = np.polynomial.chebyshev.chebvander(_LAW_PANEL_X, LAW_PANEL_NODES - 1)


def _direct_return_speed_bin_law(u, v_lower, v_upper):
    """M_j(u) of ``return_speed_bin_law`` at each u, Gauss-Legendre in ln v on each finite
    v-bin (its sub-bins, ``_speed_sub_bins``); the overflow bin left at 0."""
    lo, hi, owner = _speed_sub_bins(v_lower, v_upper)
    v, v_weights = _log_gauss(lo, hi)  # (n_sub, 16)
    # G_g(v, u) of every pair as [u, v sub-bin, v point] (the matrix is [v, u]: a copy of its
    # transpose costs less than broadcasting the pairs)
    kernel = np.ascontiguousarray(return_speed_kernel_matrix(v.ravel(), u).T)
    sub = np.einsum("acd,cd->ac", kernel.reshape(u.size, *v.shape), v * v_weights)
    cells = np.zeros((u.size, v_lower.size))
    np.add.at(cells.T, owner, sub.T)
    return cells


def return_speed_bin_law(u, v_lower, v_upper, interpolated=False):
    """M_j(u) = int_(v-bin j) dv v G_g(v, u): the return-speed law of eq. (kernel3) in v-bins.

    The probability that a ball leaving the floor at speed u comes back with a speed in
    v-bin j.  A v-bin may start at 0 (underflow) or end at inf (overflow: 1 minus the rest,
    by eq. (normG)).  Gauss-Legendre in ln v.

    Parameters
    ----------
    u : array_like
        Outgoing speeds, 1-d, > 0.
    v_lower, v_upper : array_like
        The v-bins' edges.
    interpolated : bool, optional
        M_j computed at ``LAW_PANEL_NODES`` Chebyshev nodes on each panel in ln u that holds
        a u (panels of fixed edges, one e-fold wide, narrower above u = 4) and interpolated,
        where that takes fewer kernel evaluations: for many u close together.  M_j is
        analytic in ln u on that scale, and the interpolation agrees with the direct
        evaluation to rounding (a few 1e-15, ``tests/unit/test_flight_time.py``).

    Returns
    -------
    numpy.ndarray, shape (u, v-bins)
        Each row sums to 1 where the v-bins cover [0, inf).
    """
    u = np.ascontiguousarray(u, dtype=float)
    v_lower, v_upper = np.asarray(v_lower, dtype=float), np.asarray(v_upper, dtype=float)
    s = np.log(u)
    panel = np.searchsorted(_LAW_PANEL_EDGES, s, side="right") - 1
    used = np.unique(panel)
    inside = used.size and used[0] >= 0 and used[-1] < _LAW_PANEL_EDGES.size - 1
    if interpolated and inside and used.size * LAW_PANEL_NODES < u.size:
        middle = 0.5 * (_LAW_PANEL_EDGES[used + 1] + _LAW_PANEL_EDGES[used])
        half = 0.5 * (_LAW_PANEL_EDGES[used + 1] - _LAW_PANEL_EDGES[used])
        nodes = np.exp(middle[:, None] + half[:, None] * _LAW_PANEL_X[None, :])
        at_nodes = _direct_return_speed_bin_law(nodes.ravel(), v_lower, v_upper)
        coefficients = np.linalg.solve(
            _LAW_PANEL_VANDERMONDE, at_nodes.reshape(used.size, LAW_PANEL_NODES, -1)
        )
        k = np.searchsorted(used, panel)
        x = (s - middle[k]) / half[k]
        vandermonde = np.polynomial.chebyshev.chebvander(x, LAW_PANEL_NODES - 1)
        cells = np.einsum("pn,pnj->pj", vandermonde, coefficients[k])
    else:
        cells = _direct_return_speed_bin_law(u, v_lower, v_upper)
    overflow = np.flatnonzero(~np.isfinite(v_upper))
    if overflow.size:
        cells[:, overflow[0]] = 0.0
        cells[:, overflow[0]] = 1.0 - cells.sum(axis=1)
    return cells


def return_speed_bin_probabilities(
    outgoing_density, u_lower, u_upper, v_lower, v_upper, outgoing_points=16
):
    """The return-speed law v G_g(v, u) of eq. (kernel3) between bins of u and of v.

    Matrix [i, j]: probability that the return speed lies in v-bin j, given an outgoing speed in
    u-bin i distributed as u P(0, u) (the rate of collisions, eq. (collrate)) within the bin:

        int_(u-bin) du u P(0, u) int_(v-bin) dv v G_g(v, u) / int_(u-bin) du u P(0, u).

    ``outgoing_density`` is P(0, u) as a function of an array (e.g. the solver's
    ``outgoing_speed_density``).  u-bins must be finite; a v-bin may start at 0 (underflow) or end
    at inf (overflow: 1 minus the rest, by eq. (normG)).  Gauss-Legendre in ln u and ln v, the
    law at the points of u interpolated in ln u where that takes fewer kernel evaluations
    (``return_speed_bin_law``, the same values to rounding).

    Parameters
    ----------
    outgoing_density : callable
        P(0, u) of an array of u.
    u_lower, u_upper : array_like
        The finite u-bins' edges.
    v_lower, v_upper : array_like
        The v-bins' edges.
    outgoing_points : int, optional
        Gauss-Legendre points in ln u per u-bin (16; fewer suffice for narrow u-bins).

    Returns
    -------
    numpy.ndarray, shape (u-bins, v-bins)
        Each row sums to 1 where the v-bins cover [0, inf).
    """
    u, u_weights = _log_gauss(u_lower, u_upper, outgoing_points)
    flux = u * outgoing_density(u) * u_weights  # (n_u, points)
    law = return_speed_bin_law(u.ravel(), v_lower, v_upper, interpolated=True)
    return np.einsum("ab,abj->aj", flux, law.reshape(*u.shape, -1)) / flux.sum(axis=1)[:, None]
