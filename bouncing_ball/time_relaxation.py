"""How fast the process forgets in time: the bounce operator tilted by the flight time.

The process seen at the floor is a Markov renewal process: a flight leaving x = 0 with speed u
lasts T and returns with speed V, with the joint law p(t, v | u) of eq. (joint), and the next
flight leaves with r V (eq. (restitution)).  Correlations in time of the state decay as
e^(-gamma t), with -gamma the singularity of their Laplace transform nearest 0: the s < 0 at
which the Laplace-transformed bounce operator,

    (Q_gamma h)(u) = E[e^(gamma T) h(r V) | u] = int dt dv e^(gamma t) p(t, v | u) h(r v),

with gamma = -s, has the eigenvalue 1.  At gamma = 0 this is the bounce chain's backward
operator (``relaxation``) with its Perron eigenvalue 1 (h = 1, the stationary state); its
second eigenvalue lambda_2 < 1 rises with gamma, and the relaxation rate is the smallest
gamma > 0 at which it reaches 1 (the eigenfunction h then changes sign once: a positive h solves
Q_gamma h = h only at gamma = 0, where the Perron eigenvalue is 1).

The tilt in closed form.  Gravity enters the joint law through eq. (0g),
p(t, v | u) = e^((v + u)/2 - t/4) p_0(t, v | u), so with g = (1 - 4 gamma)^(1/2),

    e^(gamma t) p(t, v | u) = e^((1 - g)(v + u)/2) p_g(t, v | u),

p_g the joint law at gravity g (same noise).  Integrated over t, p_g gives the return-speed
law at gravity g, v G_g(v, u) with G_g(v, u) = g^2 G_1(g v, g u) (eq. (kernel3): speeds scale
as Lambda / g), so the tilted kernel is

    K_gamma(v | u) = e^((1 - g)(v + u)/2) g^2 v G_1(g v, g u).                     (tilted)

The Nystrom matrix of ``solver`` with this kernel (same nodes, weights and lower tail)
discretises Q_gamma's transpose; the rate is the root in gamma of its second real eigenvalue
minus 1 (``scipy.optimize.brentq``).

The two ends of the speeds.

- Small speeds: there T ~ u -> 0 and the tilt drops out, so the chain's continuum of deep
  low-speed cascades (``relaxation.continuum_edge``, lambda_c < 1) stays below 1 at every
  gamma: those cascades are many short flights that take little time, and they set no time
  scale.  Where lambda_c is the chain's relaxation eigenvalue (r below ~0.6), the time rate is
  still an isolated root.
- Large speeds: a flight from u >> 1 lasts ~2 u and returns with V ~ u + O(u^(1/2)), so high
  starts descend at a steady pace.  The tilted joint law's saddle at t = tau u, v = nu u gives
  E[e^(gamma T + s V) | u] ~ e^(u Lambda(gamma, s)),
  Lambda = 3/4 + s/2 - (3 (3/16 - gamma - s (s + 1)/4))^(1/2), and an eigenfunction e^(kappa u)
  at large u needs Lambda(gamma, kappa r) = kappa, i.e.
  (1 - r + r^2) kappa^2 - (3/2)(1 - r) kappa + 3 gamma = 0.  Its real roots merge at

      gamma_e = 3 (1 - r)^2 / (16 (1 - r + r^2)),      kappa = q / 2,               (edge)

  (q of eq. (asym4)): the top of a continuum of slow descents from high speeds (for the
  process near r = 1 a Brownian motion of drift -(1 - r)/2 and diffusion 1/3 in u, whose
  continuum starts at drift^2 / (4 D)).  Above gamma_e the matrix's eigenvalues from its
  highest nodes grow without bound as the highest node goes up; below it they converge.  The
  relaxation rate is the isolated root where it lies below gamma_e (every r the solver answers
  above r_c: gamma / gamma_e runs from ~0.95 near r_c to 3/4 at r -> 1), else gamma_e.

Near r = 1 the rate is the quasi-elastic diffusion's (docs/quasi_elastic.md): 1 / gamma ->
(64/9) (1 - r)^-2, 8/3 times n_c <T>.

Examples
--------
The large-speed edge at r = 1/2 is 1/16:

>>> from bouncing_ball.time_relaxation import large_speed_edge
>>> print(large_speed_edge(0.5))
0.0625
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy import linalg, optimize

from .asymptotics import large_speed_decay_rate, small_speed_exponent
from .kernel import kernel_small_u_limit, return_speed_kernel_matrix
from .relaxation import _chain_restitution, _checked_step
from .solver import (
    DEFAULT_STEP,
    FINER_HIGHEST_SPEED,
    FINER_LOWEST_SPEED,
    FINER_STEP,
    OutgoingSpeedSolution,
    coordinate_of_speed,
    default_highest_speed,
    default_lowest_speed,
    speed_of_coordinate,
)

__all__ = [
    "TIME_RELAXATION_COLUMNS",
    "large_speed_edge",
    "tilted_return_kernel",
    "TimeRelaxation",
    "time_relaxation",
    "time_relaxation_accuracy",
]

#: The columns of rule solve's summary on the relaxation of the process in time
#: (``Equilibrium.summary``); NaN below r_c, where they are not defined.
TIME_RELAXATION_COLUMNS = (
    "relaxation_rate",
    "relaxation_rate_accuracy",
    "large_speed_edge",
    "relaxation_time",
)

#: The fractions of gamma_e at which the root is bracketed: below ~0.98 gamma_e the matrix's
#: eigenvalues are converged in its highest node; the root lies at 0.75 - 0.95 gamma_e.
#: The highest node, in ``solver.default_highest_speed``: the tilted eigenvector falls more
#: slowly than P(0, v) (as e^(-3 q v / 4) at r -> 1), 1.25 of the solver's range keeps the
#: truncation error of gamma near 1e-7 (3e-6 with the solver's own at r = 0.99); much higher
#: nodes (2 x the solver's) make the eigenvalues ill-conditioned.
HIGHEST_NODE_FACTOR = 1.25
_BRACKET = (0.5, 0.7, 0.8, 0.85, 0.9, 0.95, 0.98)


def large_speed_edge(restitution) -> float:
    """gamma_e = 3 (1 - r)^2 / (16 (1 - r + r^2)): the top of the large-speed continuum in time.

    Eq. (edge) of the module's docstring: the slowest decay rate of descents from high speeds,
    where the roots kappa of Lambda(gamma, kappa r) = kappa merge.

    Parameters
    ----------
    restitution : float or str
        r, r_c < r <= 0.9999.

    Returns
    -------
    float
        gamma_e in units of g^2 / Lambda; (3/16) (1 - r)^2 as r -> 1.

    Raises
    ------
    ValueError
        Naming r, at or below r_c or outside the solver's range.

    Examples
    --------
    >>> from bouncing_ball.time_relaxation import large_speed_edge
    >>> print(round(large_speed_edge(0.75), 8))
    0.01442308
    """
    r = _chain_restitution(restitution)
    return 3.0 * (1.0 - r) ** 2 / (16.0 * (1.0 - r + r * r))


def _tilted_gravity(rate: float) -> float:
    if not 0.0 <= rate < 3.0 / 16.0:
        raise ValueError(
            f"rate = {rate}: E[e^(rate T) | u] is finite for 0 <= rate < 3/16 (the flight times' "
            "tail at large T, eq. (joint))"
        )
    return math.sqrt(1.0 - 4.0 * rate)


def tilted_return_kernel(v, u, rate) -> np.ndarray:
    """K_gamma(v | u) / v = e^((1 - g)(v + u)/2) g^2 G_1(g v, g u), g = (1 - 4 gamma)^(1/2).

    Eq. (tilted) of the module's docstring: int dt e^(gamma t) p(t, v | u) of eq. (joint), over
    v; at gamma = 0 the kernel G_g(v, u) of eq. (kernel3).

    Parameters
    ----------
    v, u : array_like
        Return and outgoing speeds, 1-d.
    rate : float
        gamma, 0 <= gamma < 3/16.

    Returns
    -------
    numpy.ndarray
        The matrix over (v_i, u_j).

    Examples
    --------
    Compiles the kernel on its first call, so not run as a doctest; at gamma = 0 it is G_g:

    >>> from bouncing_ball.time_relaxation import tilted_return_kernel
    >>> print(tilted_return_kernel([1.0], [1.0], 0.0).round(8))  # doctest: +SKIP
    [[0.42936793]]
    """
    g = _tilted_gravity(float(rate))
    v = np.asarray(v, dtype=float)
    u = np.asarray(u, dtype=float)
    tilt = np.exp(0.5 * (1.0 - g) * (v[:, None] + u[None, :]))
    return return_speed_kernel_matrix(g * v, g * u) * (g * g) * tilt


def _nodes(restitution, step, lowest_speed, highest_speed):
    """The solver's nodes (uniform in s = ln u + u^(1/2)) between the given or default ends."""
    beta = small_speed_exponent(restitution)
    lowest = default_lowest_speed(beta) if lowest_speed is None else float(lowest_speed)
    if highest_speed is None:
        highest = HIGHEST_NODE_FACTOR * default_highest_speed(restitution)
    else:
        highest = float(highest_speed)
    s_lo, s_hi = coordinate_of_speed(lowest), coordinate_of_speed(highest)
    count = int(np.floor((s_hi - s_lo) / step)) + 1
    return OutgoingSpeedSolution(
        restitution, beta, step, speed_of_coordinate(s_lo + step * np.arange(count)), None, 1.0
    )


def _tilted_matrix(draft, rate):
    """The scaled Nystrom matrix of Q_gamma's transpose on the nodes of ``draft``: the solver's
    A_ij = r^-2 G(u_i / r, u_j) u_j w_j with the tilted kernel, its lower tail (the power law
    u^-beta below the lowest node) in column 0, scaled by S = u^-beta e^(-q u)."""
    r, beta, step, u = draft.restitution, draft.small_speed_exponent, draft.step, draft.speeds
    incoming = u / r
    rows = tilted_return_kernel(incoming, u, rate) * (draft.quadrature_weights * u)
    tail_u, tail_weights, _ = draft._lower_tail(incoming)
    g = _tilted_gravity(rate)
    # beyond the last tail node G(V, u) = kernel_small_u_limit ~ u^(1/2): the tilted one is
    # e^((1 - g) V / 2) g^(5/2) kernel_small_u_limit(g V, 1) u^(1/2)
    alpha = 2.5 - beta
    remainder = (
        step
        * np.exp(0.5 * (1.0 - g) * incoming)
        * g**2.5
        * kernel_small_u_limit(g * incoming, 1.0)
        * u[0] ** 2.5
        * np.exp(-alpha * (tail_u.size + 1) * step)
        / -np.expm1(-alpha * step)
    )
    rows[:, 0] += tilted_return_kernel(incoming, tail_u, rate) @ tail_weights + remainder
    log_scale = -beta * np.log(u) - large_speed_decay_rate(r) * u
    with np.errstate(divide="ignore"):
        return np.exp(np.log(rows / (r * r)) + log_scale[None, :] - log_scale[:, None])


def _second_real_eigenvalue(draft, rate) -> float:
    """The second largest real eigenvalue of the tilted matrix (the largest is the Perron one,
    1 at gamma = 0 and above 1 beyond)."""
    values = linalg.eigvals(_tilted_matrix(draft, rate), check_finite=False)
    real = np.sort(values.real[np.abs(values.imag) <= 1e-9 * np.abs(values)])[::-1]
    return float(real[1])


@dataclass(frozen=True)
class TimeRelaxation:
    """The relaxation of the process in time at one r, from the tilted bounce operator.

    Parameters
    ----------
    restitution : float
        r.
    step : float
        The trapezoidal step in s = ln u + u^(1/2).
    lowest_speed, highest_speed : float
        The matrix's lowest and highest node.
    root : float
        The smallest gamma > 0 at which the tilted matrix has the eigenvalue 1, NaN if there
        is none below 0.98 gamma_e.
    large_speed_edge : float
        gamma_e (``large_speed_edge``).

    Attributes
    ----------
    isolated : bool
        Whether the root lies below the large-speed continuum (then it is the rate).
    rate : float
        gamma, the slowest decay rate of correlations in time: the root if isolated, else
        gamma_e (units g^2 / Lambda).
    time : float
        1 / gamma, the slowest relaxation time (units Lambda / g^2).
    """

    restitution: float
    step: float
    lowest_speed: float
    highest_speed: float
    root: float
    large_speed_edge: float

    @property
    def isolated(self) -> bool:
        return bool(self.root < self.large_speed_edge)

    @property
    def rate(self) -> float:
        return float(self.root) if self.isolated else self.large_speed_edge

    @property
    def time(self) -> float:
        return 1.0 / self.rate


def time_relaxation(restitution, step=DEFAULT_STEP, lowest_speed=None, highest_speed=None):
    """The slowest decay rate gamma(r) of the process in time, and its relaxation time 1/gamma.

    The smallest gamma > 0 at which E[e^(gamma T) h(r V) | u] = h(u) has a solution h (the
    module's docstring; T, V of eq. (joint), the tilted kernel eq. (tilted) in the solver's
    Nystrom discretisation of eq. (inteq)), where it lies below the large-speed continuum
    gamma_e of eq. (edge), else gamma_e.  The rate of exp(-gamma t) at which correlations in
    time of any observable of the state decay at long times (a slower one is not excited only
    by observables orthogonal to its mode).

    Parameters
    ----------
    restitution : float or str
        r, r_c < r <= 0.9999 (the solver's range above r_c, eq. (rc)).
    step : float, optional
        The trapezoidal step in s = ln u + u^(1/2), 0 < step <= 0.5.
    lowest_speed, highest_speed : float, optional
        The matrix's lowest and highest node (``solver.default_lowest_speed``,
        ``HIGHEST_NODE_FACTOR`` x ``solver.default_highest_speed``).

    Returns
    -------
    TimeRelaxation
        Its ``rate`` gamma in g^2 / Lambda and ``time`` 1 / gamma in Lambda / g^2.

    Raises
    ------
    ValueError
        Naming r at or below r_c (the speeds collapse; no stationary state to relax to) or
        outside the solver's range, or a step the solver refuses.

    Examples
    --------
    Builds the tilted matrix about a dozen times, so not run as a doctest:

    >>> from bouncing_ball.time_relaxation import time_relaxation
    >>> relaxation = time_relaxation(0.5)  # doctest: +SKIP
    >>> print(relaxation.isolated, round(relaxation.time, 4))  # doctest: +SKIP
    True 19.3446
    """
    r = _chain_restitution(restitution)
    step = _checked_step(step)
    edge = large_speed_edge(r)
    draft = _nodes(r, step, lowest_speed, highest_speed)

    def excess(rate):
        return _second_real_eigenvalue(draft, rate) - 1.0

    low, root = 0.0, math.nan
    for fraction in _BRACKET:
        high = fraction * edge
        if excess(high) > 0.0:
            root = optimize.brentq(excess, low, high, xtol=1e-12 * edge, rtol=1e-12)
            break
        low = high
    return TimeRelaxation(
        restitution=r,
        step=step,
        lowest_speed=float(draft.speeds[0]),
        highest_speed=float(draft.speeds[-1]),
        root=float(root),
        large_speed_edge=edge,
    )


def time_relaxation_accuracy(relaxation) -> float:
    """The error estimate of the relaxation rate: its relative change against a finer matrix.

    The finer matrix has step x 0.8, lowest node x 1e-4 (as ``relaxation.relaxation_accuracy``)
    and highest node x 1.2 (a root set by the large-speed continuum would move with it).

    Parameters
    ----------
    relaxation : TimeRelaxation

    Returns
    -------
    float
        abs(gamma / gamma_finer - 1), the same for 1 / gamma to first order.

    Examples
    --------
    Builds the matrices, so not run as a doctest:

    >>> from bouncing_ball.time_relaxation import time_relaxation, time_relaxation_accuracy
    >>> time_relaxation_accuracy(time_relaxation(0.5)) < 1e-8  # doctest: +SKIP
    True
    """
    finer = time_relaxation(
        relaxation.restitution,
        step=FINER_STEP * relaxation.step,
        lowest_speed=FINER_LOWEST_SPEED * relaxation.lowest_speed,
        highest_speed=FINER_HIGHEST_SPEED * relaxation.highest_speed,
    )
    return float(abs(relaxation.rate / finer.rate - 1.0))
