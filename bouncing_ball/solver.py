"""P(0, v) for any r in (0, 1): the integral equation (inteq), solved and absolutely normalised.

Method (Nystrom).  Put v -> v / r in eq. (inteq):

    P(0, v) = r^-2 int_0^inf du u G_g(v / r, u) P(0, u),

so the unknown is needed only at quadrature nodes and the kernel is
evaluated at (v / r, u) exactly, with no interpolation.  The integral is a
trapezoidal rule, uniform in

    s = ln u + b u^(1/2):

ln u where the kernel is scale-free (u << 1: there G_g(v, u) du u is a
function of ln(v / u), analytic in the strip abs(Im ln(v/u)) < pi / 3, so the
rule converges like exp(-2 pi^2 / (3 h))), and u^(1/2) where a fast
particle comes back with its speed spread by (4u/3)^(1/2) ~ 1.15 u^(1/2) (the
standard deviation, docs/methods.md), so the spacing keeps pace with the
kernel's width.  Below the lowest node u_0 the power
law of eq. (asym1), P = P(0, u_0) (u / u_0)^-beta with beta from
eq. (asym2), is built in: the rule's nodes continue below u_0, their sum is
done directly for 25 e-folds and in closed form (a geometric series, with
the u -> 0 form of the kernel) beyond.  Above the highest node P(0, v) is
below exp(-45) of its value at v = 20 (from q(r) of eqs. (asym4), (asym6)),
and is dropped.

The discrete operator is positive; its eigenvalue nearest 1 belongs to the
solution.  It is found by inverse iteration on (A - 1), with the unknowns
scaled by v^-beta exp(-q v) so that values spanning hundreds of decades at small r
keep their relative digits.  How far that eigenvalue is from 1 is one
measure of the discretisation error.

Normalisation, eq. (normalization), from the momentum balance: Ito's
formula for v + t (dv = -dt + noise between collisions, v -> -r v at a
collision) gives, in the steady state, 1 = (1 + r) I <v_in>, i.e.

    M_2 = int_0^inf v^2 P(0, v) dv = r / (1 + r).                 (momentum)

The energy balance, Ito on v^2/2 + x (dE = dt + noise, E loses
(1 - r^2) v_in^2 / 2 at a collision), is an independent check:

    M_3 = 2 r^2 / (1 - r^2).                                         (energy)

Time averages from Ito's formula with the generator v d/dx - d/dv + d^2/dv^2
on x^2, x v, x v^2, x^2 v, x v^3, v^3 and v^5 (a function with a factor x
does not jump at a collision; v^n jumps by (1 + r^n) v_in^n; <v> = 0):

    <x v> = 0,   <x> = <v^2> = (1 + r^3) M_4 / (3 r^3),   <v^3> = -2 <x>,
    <x^2> = 2 <x v^2> = (2/3) <v^4>,   <v^4> = 4 <v^3> + (1 + r^5) M_6 / (5 r^5).

The collision rate is I = M_1, eq. (collrate); it is infinite where
beta >= 2 (r <= r_c).

The kernel is numba-compiled (``bouncing_ball.kernel``): a solve compiles it on its first
call (seconds), so the Examples that solve are not run as doctests; the unit tests
(``tests/unit/test_solver_range.py``) check the same values.  The Examples that run put the
exact P(0, v) of r = 1/2, eq. (P(0,v)), on the solver's nodes instead.

Examples
--------
The Ito identities above give the paper's <x> = 6, Delta x = 6 3^(1/2) and I = 1/3 at
r = 1/2, eq. (xandDeltax), from the exact P(0, v) on the solver's nodes:

>>> import numpy as np
>>> from bouncing_ball.exact import outgoing_speed_density
>>> from bouncing_ball.solver import OutgoingSpeedSolution, time_averages
>>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
>>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
>>> nodes = speed_of_coordinate(s)
>>> density = outgoing_speed_density(nodes, "1/2")
>>> exact = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
>>> print({name: round(value, 8) for name, value in time_averages(exact).items()})
{'mean_x': 6.0, 'delta_x': 10.39230485, 'collision_rate': 0.33333333}
"""

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import linalg, special

from .asymptotics import large_speed_decay_rate, small_speed_exponent
from .jit import njit
from .kernel import (
    _NODES,
    _WEIGHTS,
    _geometry,
    _kernel,
    kernel_small_u_limit,
    return_speed_kernel_matrix,
)
from .restitution import SOLVER_RESTITUTION_RANGE, check_solver_range, in_range

__all__ = [
    "DEFAULT_STEP",
    "LARGEST_STEP",
    "ACCURACY_TARGET",
    "CHECKED_SPEEDS",
    "FINER_STEP",
    "FINER_LOWEST_SPEED",
    "FINER_HIGHEST_SPEED",
    "SMALLEST_OUTPUT_SPEED",
    "speed_of_coordinate",
    "coordinate_of_speed",
    "default_lowest_speed",
    "default_highest_speed",
    "OutgoingSpeedSolution",
    "solve_outgoing_speed_density",
    "solved_outgoing_density",
    "momentum_balance_residual",
    "energy_balance_residual",
    "time_averages",
    "accuracy_estimate",
    "solution_summary",
]

#: The trapezoidal step in s = ln u + u^(1/2); ~1e-11 relative error at r = 1/2, 1/3.
DEFAULT_STEP = 0.25  # trapezoidal step in s; ~1e-11 relative error at r = 1/2, 1/3
#: The largest step accepted: the error grows like exp(-2 pi^2 / (3 h)) (1e-6 at h = 0.5), and
#: the complex Nystrom sum of bouncing_ball.distribution loses accuracy faster still.
LARGEST_STEP = 0.5
SQRT_WEIGHT = 1.0  # b in s = ln u + b u^(1/2)
TAIL_EFOLDS = 25.0  # lower tail summed node by node over this many e-folds of u
DROP_EFOLDS = 45.0  # P(0, v_max) ~ exp(-45) P(0, 20); M_6 then misses < 1e-12
UNDERFLOW_EFOLDS = 700.0  # exp(-700) ~ 1e-304 is still a normal double
#: A term of the Nystrom sum of ``OutgoingSpeedSolution.outgoing_speed_density`` whose bound is
#: below e^-NEGLIGIBLE_TERM_EFOLDS (~1e-26) of the largest bound is skipped.
NEGLIGIBLE_TERM_EFOLDS = 60.0


def speed_of_coordinate(s, b=SQRT_WEIGHT):
    """u(s) for s = ln u + b u^(1/2): the speed at a coordinate of the solver's rule.

    Through the Lambert W function: u = (2 W(z) / b)^2 with z = (b / 2) e^(s/2); where z
    overflows (u above ~2e6), W from ln z by Newton's method on W + ln W = ln z.  The inverse
    of ``coordinate_of_speed``.

    Parameters
    ----------
    s : array_like
        Coordinates.
    b : float, optional
        The weight b of u^(1/2) (the solver's is 1).

    Returns
    -------
    numpy.ndarray
        The speeds u > 0, the shape of ``s``.

    Examples
    --------
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> print(speed_of_coordinate(1.0), speed_of_coordinate(coordinate_of_speed([1e-6, 1e8])))
    1.0 [1.e-06 1.e+08]
    """
    s = np.asarray(s, dtype=float)
    log_z = np.log(0.5 * b) + 0.5 * s
    huge = log_z > 700.0
    w = special.lambertw(0.5 * b * np.exp(np.where(huge, 0.0, 0.5 * s))).real
    if np.any(huge):
        large = log_z[huge]
        root = large - np.log(large)
        for _ in range(8):
            root -= (root + np.log(root) - large) / (1.0 + 1.0 / root)
        w = np.where(huge, 0.0, w)
        w[huge] = root
    w = (2.0 / b) * w
    return w * w


def coordinate_of_speed(u, b=SQRT_WEIGHT):
    """s = ln u + b u^(1/2): the coordinate in which the solver's rule is uniform.

    Parameters
    ----------
    u : array_like
        Speeds, u > 0.
    b : float, optional
        The weight b of u^(1/2) (the solver's is 1).

    Returns
    -------
    numpy.ndarray
        s, the shape of ``u``.

    Examples
    --------
    >>> from bouncing_ball.solver import coordinate_of_speed
    >>> print(coordinate_of_speed([1.0, 4.0]).round(8))
    [1.         3.38629436]
    """
    u = np.asarray(u, dtype=float)
    return np.log(u) + b * np.sqrt(u)


def _jacobian(u, b=SQRT_WEIGHT):
    """du / ds."""
    return u / (1.0 + 0.5 * b * np.sqrt(u))


def default_lowest_speed(beta: float) -> float:
    """The solver's lowest node u_0, below which P(0, v) is its power law, eq. (asym1).

    Corrections to the built-in power law are O(u_0) relative; the
    error they cause at v >= 1e-3 grows as beta -> 5/2 (r -> 0), where the
    tail carries more weight (measured: 2e-8 at r = 0.1 with u_0 = 1e-8,
    5e-11 with 1e-12), so the lowest node goes deeper where beta > 2.

    Parameters
    ----------
    beta : float
        The exponent beta(r) of eq. (asym2).

    Returns
    -------
    float
        1e-12, or 1e-20 where beta >= 2 (r <= r_c).

    Examples
    --------
    >>> from bouncing_ball.solver import default_lowest_speed
    >>> default_lowest_speed(1.0), default_lowest_speed(2.2)
    (1e-12, 1e-20)
    """
    return 1e-12 if beta < 2.0 else 1e-20


def default_highest_speed(restitution: float) -> float:
    """The solver's highest node, where P(0, v) has fallen by exp(-45) from v = 20.

    It stays inside the double-precision range (q v < 700, q of eqs. (asym4), (asym6); at
    r < 0.016 this cap, not the exp(-45), decides), and is at least 60.

    Parameters
    ----------
    restitution : float
        r, 0 < r < 1.

    Returns
    -------
    float
        min(max(60, 20 + 45 / q), 700 / q).

    Examples
    --------
    >>> from bouncing_ball.solver import default_highest_speed
    >>> default_highest_speed(0.5)
    65.0
    """
    q = large_speed_decay_rate(restitution)
    return min(max(60.0, 20.0 + DROP_EFOLDS / q), UNDERFLOW_EFOLDS / q)


@dataclass(frozen=True)
class OutgoingSpeedSolution:
    """P(0, v) on the outgoing side at the solver's nodes, and how to evaluate it anywhere.

    The solution of eq. (inteq) that ``solve_outgoing_speed_density`` returns.  Its method
    ``outgoing_speed_density(v)`` gives P(0, v) at any v >= 0 by the Nystrom formula
    r^-2 int du u G_g(v / r, u) P(0, u) (it compiles the kernel on its first call);
    ``moment(k)`` gives M_k = int_0^inf v^k P(0, v) dv (inf where it diverges at v -> 0);
    ``quadrature_weights`` are the rule's weights w_j, int f(u) du ~ sum_j w_j f(u_j) (plus
    the lower tail, the power law of eq. (asym1) below the lowest node).

    Parameters
    ----------
    restitution : float
        r.
    small_speed_exponent : float
        beta(r) of eq. (asym2), the power law below the lowest node.
    step : float
        The trapezoidal step in s = ln u + u^(1/2).
    speeds : numpy.ndarray
        The nodes u_j, uniform in s.
    density : numpy.ndarray
        P(0, u_j), absolutely normalised (M_2 = r / (1 + r)).
    eigenvalue : float
        The discrete operator's eigenvalue nearest 1 (1 in the continuum limit).

    Examples
    --------
    The exact P(0, v) of r = 1/2 on the solver's nodes has M_2 = r / (1 + r) = 1/3 and an
    infinite M_0 (P(0, v) ~ 1 / v at small v):

    >>> import numpy as np
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = outgoing_speed_density(nodes, "1/2")
    >>> exact = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> print(round(exact.moment(2), 12), exact.moment(0))
    0.333333333333 inf
    """

    restitution: float
    small_speed_exponent: float
    step: float
    speeds: np.ndarray  # nodes u_j
    density: np.ndarray  # P(0, u_j), absolutely normalised
    eigenvalue: float  # of the discrete operator, 1 in the continuum limit

    @property
    def quadrature_weights(self):
        """w_j with int f(u) du ~ sum_j w_j f(u_j) (plus the lower tail)."""
        return self.step * _jacobian(self.speeds)

    def _tail_speeds(self):
        count = int(np.ceil(TAIL_EFOLDS / self.step))
        s0 = coordinate_of_speed(self.speeds[0])
        return speed_of_coordinate(s0 - self.step * np.arange(1, count + 1)), count

    def _lower_tail(self, incoming):
        """The rule's nodes below u_0 (P(u) = P(u_0) (u / u_0)^-beta there): the nodes, their
        weights of int du u G_g(V, u) P(u) / P(u_0), and the closed-form rest beyond the last."""
        u0 = self.speeds[0]
        tail_u, count = self._tail_speeds()
        beta = self.small_speed_exponent
        tail_weights = self.step * _jacobian(tail_u) * tail_u * (tail_u / u0) ** -beta
        # beyond the last tail node, G(V, u) = kernel_small_u_limit (relative error ~ u / V)
        alpha = 2.5 - beta
        remainder = (
            self.step
            * kernel_small_u_limit(incoming, 1.0)
            * u0**2.5
            * np.exp(-alpha * (count + 1) * self.step)
            / -np.expm1(-alpha * self.step)
        )
        return tail_u, tail_weights, remainder

    def _rows(self, incoming):
        """Rows of r^2 x the operator: int du u G_g(V, u) P(u) = rows @ P for V = incoming."""
        u = self.speeds
        rows = return_speed_kernel_matrix(incoming, u) * (self.quadrature_weights * u)
        tail_u, tail_weights, remainder = self._lower_tail(incoming)
        rows[:, 0] += return_speed_kernel_matrix(incoming, tail_u) @ tail_weights + remainder
        return rows

    def outgoing_speed_density(self, v):
        """P(0, v) anywhere (v >= 0): the Nystrom formula of eq. (inteq) from the lowest node
        u_0 up, and its power law eq. (asym1) below.

        At v >= u_0, r^-2 int du u G_g(v / r, u) P(0, u), the integral by the solver's rule.
        Below u_0, A v^-beta with A = ``small_speed_prefactor`` (the Nystrom value at u_0
        times u_0^beta): the rule's lower tail reaches only TAIL_EFOLDS below u_0, and the
        power law is what the solver builds in there.  Its relative error is that of the
        next term of P(0, v) at u_0, of relative order u_0 (e^(-v) / (3 v) at r = 1/2:
        exactly u_0 - v), besides the error of the Nystrom value.

        Parameters
        ----------
        v : array_like
            Outgoing speeds, v >= 0.

        Returns
        -------
        numpy.ndarray
            P(0, v), the shape of ``v``: inf at v = 0, and where A v^-beta exceeds the largest
            double (v below ~(A / 1.8e308)^(1/beta), 1e-120 or less); 0 where it underflows.

        Raises
        ------
        ValueError
            If a v is negative or NaN (the incoming side is r^2 P(0, -r v), eq. (bc)).
        """
        v = np.asarray(v, dtype=float)
        if np.any(~(v >= 0.0)):
            raise ValueError(
                "v: P(0, v) is the density of outgoing speeds, v >= 0; "
                "the incoming side is r^2 P(0, r |v|), eq. (bc)"
            )
        flat = np.ascontiguousarray(v.ravel())
        out = np.empty(flat.size)
        below = flat < self.speeds[0]
        # beyond twice the underflow scale P(0, v) < e^-1400 (eq. (asym4)): 0 in doubles, and
        # v / r would overflow in the Nystrom formula near the largest double
        beyond = flat > 2.0 * UNDERFLOW_EFOLDS / large_speed_decay_rate(self.restitution)
        inside = ~below & ~beyond
        out[beyond] = 0.0
        out[inside] = self._nystrom(flat[inside])
        with np.errstate(divide="ignore", over="ignore"):
            out[below] = np.exp(
                np.log(self.small_speed_prefactor) - self.small_speed_exponent * np.log(flat[below])
            )
        return out.reshape(v.shape)

    @functools.cached_property
    def small_speed_prefactor(self) -> float:
        """A of P(0, v) ~ A v^-beta at v -> 0, eq. (asym1): the Nystrom value at the lowest node
        u_0 times u_0^beta (relative error of order u_0, the next term of P(0, v))."""
        u0 = self.speeds[0]
        return float(self._nystrom(np.array([u0]))[0] * u0**self.small_speed_exponent)

    def _nystrom(self, v):
        """r^-2 int du u G_g(v / r, u) P(0, u) for a 1-d array v >= 0, by the solver's rule and
        its lower tail."""
        r = self.restitution
        incoming = v / r
        u = self.speeds
        tail_u, tail_weights, remainder = self._lower_tail(incoming)
        flat = _kernel_sums(
            incoming,
            np.concatenate([u, tail_u]),
            np.concatenate([self.quadrature_weights * u, tail_weights]),
            np.concatenate([self.density, np.full(tail_u.size, self.density[0])]),
            _NODES,
            _WEIGHTS,
        )
        return (flat + remainder * self.density[0]) / (r * r)

    def moment(self, k: float) -> float:
        """M_k = int_0^inf v^k P(0, v) dv on the outgoing side.

        Parameters
        ----------
        k : float
            The power of v.

        Returns
        -------
        float
            M_k, with the power law of eq. (asym1) below the lowest node summed in closed form;
            inf where it diverges at v -> 0 (k + 1 <= beta).
        """
        u = self.speeds
        main = np.sum(self.quadrature_weights * u**k * self.density)
        exponent = k + 1.0 - self.small_speed_exponent
        if exponent <= 0.0:
            return np.inf
        # the rule's nodes below u_0, summed in closed form (du/ds = u there)
        tail = self.step * self.density[0] * u[0] ** (k + 1.0) / np.expm1(exponent * self.step)
        return float(main + tail)


@njit(cache=True)
def _kernel_sums(incoming, u, weights, density, nodes, tau_weights):
    """sum_j G_g(V_i, u_j) weights_j density_j, eq. (kernel3), for weights, density >= 0,
    skipping the terms whose bound weights_j density_j (3^(1/2) / pi) e^(-(3/4) (V - u)^2 /
    ((V + u)/2 + z0)) tau1 (1 + z0) / (2^(1/2) z0^2) (the tau integrand is at most
    (1 + z0) / 2^(1/2)) is below e^-NEGLIGIBLE_TERM_EFOLDS of the largest."""
    out = np.zeros(incoming.size)
    bounds = np.empty(u.size)
    log_weights = np.full(u.size, -np.inf)
    for j in range(u.size):
        if weights[j] > 0.0 and density[j] > 0.0 and u[j] > 0.0:
            log_weights[j] = math.log(weights[j]) + math.log(density[j])
    for i in range(incoming.size):
        big_v = incoming[i]
        if big_v <= 0.0:
            continue
        best = -np.inf
        for j in range(u.size):
            if log_weights[j] == -np.inf:
                bounds[j] = -np.inf
                continue
            exponent, z0, upper = _geometry(big_v, u[j])
            bounds[j] = log_weights[j] + math.log(upper) + math.log1p(z0) - 2.0 * math.log(z0)
            bounds[j] += exponent
            best = max(best, bounds[j])
        total = 0.0
        for j in range(u.size):
            if bounds[j] >= best - NEGLIGIBLE_TERM_EFOLDS:
                total += _kernel(big_v, u[j], nodes, tau_weights) * weights[j] * density[j]
        out[i] = total
    return out


def _scaled_operator(restitution, step, lowest_speed, highest_speed):
    """The solver's Nystrom matrix of eq. (inteq), checked arguments, in the scaled unknowns.

    A_ij = r^-2 G_g(u_i / r, u_j) u_j w_j (plus the lower tail in column 0) acts on
    P(0, u_j); the matrix returned is S^-1 A S with S = diag(u^-beta e^(-q u)), which keeps
    relative digits where P spans many decades (the same eigenvalues).  The one home of the
    discretisation: ``solve_outgoing_speed_density`` takes its eigenvector of eigenvalue 1,
    ``bounce_chain_spectrum`` its other eigenvalues.

    Returns
    -------
    tuple
        (r, beta, speeds u_j, log of the scale S, the scaled matrix).
    """
    r = float(check_solver_range(restitution, "restitution"))
    if not 0.0 < step <= LARGEST_STEP:
        raise ValueError(
            f"step = {step}: the quadrature step must lie in (0, {LARGEST_STEP}] (the error grows "
            "like exp(-2 pi^2 / (3 step)))"
        )
    beta = small_speed_exponent(r)
    lowest = default_lowest_speed(beta) if lowest_speed is None else float(lowest_speed)
    highest = default_highest_speed(r) if highest_speed is None else float(highest_speed)
    if not 0.0 < lowest <= default_lowest_speed(beta):
        raise ValueError(
            f"lowest_speed = {lowest_speed}: must lie in (0, {default_lowest_speed(beta):g}], "
            "where P(0, v) follows its power law v^-beta to the solver's accuracy"
        )
    ceiling = UNDERFLOW_EFOLDS / large_speed_decay_rate(r)
    floor = min(max(60.0, 20.0 + DROP_EFOLDS / large_speed_decay_rate(r)), 0.9 * ceiling)
    if not floor <= highest <= ceiling:
        raise ValueError(
            f"highest_speed = {highest_speed}: must lie in [{floor:.6g}, {ceiling:.6g}] at "
            f"r = {r}: from where P(0, v) has fallen by e^-{DROP_EFOLDS:g} below its value at "
            "v = 20 (or nearly left the range of doubles) to where it leaves the range of doubles"
        )
    s_lo, s_hi = coordinate_of_speed(lowest), coordinate_of_speed(highest)
    count = int(np.floor((s_hi - s_lo) / step)) + 1  # last node <= highest
    speeds = speed_of_coordinate(s_lo + step * np.arange(count))
    draft = OutgoingSpeedSolution(r, beta, step, speeds, np.ones(count), 1.0)
    operator = draft._rows(speeds / r) / (r * r)
    # unknowns y = P / scale: keeps relative digits where P spans many decades
    # scale = u^-beta e^(-q u), the two asymptotic forms; the ratio is taken in logs
    log_scale = -beta * np.log(speeds) - large_speed_decay_rate(r) * speeds
    with np.errstate(divide="ignore"):
        log_entries = np.log(operator) + log_scale[None, :] - log_scale[:, None]
    scaled = np.exp(log_entries)
    return r, beta, speeds, log_scale, scaled


def solve_outgoing_speed_density(
    restitution, step=DEFAULT_STEP, lowest_speed=None, highest_speed=None
):
    """Solve eq. (inteq) for P(0, v), v > 0, normalised by the momentum balance M_2 = r / (1 + r).

    Parameters
    ----------
    restitution : float or str
        r, a float or an exact fraction string ("1/3"), in ``SOLVER_RESTITUTION_RANGE``.
    step : float
        Trapezoidal step in s = ln u + u^(1/2), 0 < step <= ``LARGEST_STEP``.
    lowest_speed, highest_speed : float, optional
        The lowest and highest node; at most ``default_lowest_speed`` (the built-in power law
        below it holds only there) and between ``default_highest_speed`` and where P(0, v)
        leaves the range of doubles (UNDERFLOW_EFOLDS / q).

    Returns
    -------
    OutgoingSpeedSolution
        P(0, v) at the nodes, normalised, with the eigenvalue of the discrete operator.

    Raises
    ------
    ValueError
        Naming the argument, for an r, step or node the solver cannot answer to its accuracy.

    Examples
    --------
    Compiles the kernel on its first call (so not run as a doctest); at r = 1/2 the solution
    is eq. (P(0,v)), e^(-v) / (3 v):

    >>> from bouncing_ball.solver import solve_outgoing_speed_density
    >>> solution = solve_outgoing_speed_density("1/2")  # doctest: +SKIP
    >>> print(solution.outgoing_speed_density([0.5, 1.0]).round(8))  # doctest: +SKIP
    [0.40435377 0.12262648]
    """
    r, beta, speeds, log_scale, scaled = _scaled_operator(
        restitution, step, lowest_speed, highest_speed
    )
    count = speeds.size
    factors = linalg.lu_factor(scaled - np.eye(count), check_finite=False)
    y = np.ones(count)
    for _ in range(3):
        y = linalg.lu_solve(factors, y, check_finite=False)
        y /= y[np.argmax(np.abs(y))]
    image = scaled @ y
    eigenvalue = float(np.dot(image, y) / np.dot(y, y))
    density = np.exp(np.log(np.abs(y)) + log_scale) * np.sign(y)
    unnormalised = OutgoingSpeedSolution(r, beta, step, speeds, density, eigenvalue)
    norm = (r / (1.0 + r)) / unnormalised.moment(2)
    return OutgoingSpeedSolution(r, beta, step, speeds, density * norm, eigenvalue)


@functools.lru_cache(maxsize=8)
def solved_outgoing_density(restitution):
    """The solver's P(0, u) of eq. (inteq) at r as a function of u, or None out of range.

    What the estimators' return-law and flight-law controls are built from
    (``estimators.outgoing_speed_histogram``, ``estimators.position_moments_summary``); None
    outside the solver's range of r.

    Solved once per process and r (``solve_outgoing_speed_density`` at ``DEFAULT_STEP``).

    Parameters
    ----------
    restitution : fractions.Fraction or float
        r as parsed (``restitution.parse_restitution``).

    Returns
    -------
    callable or None
        ``OutgoingSpeedSolution.outgoing_speed_density`` (the Nystrom formula, any u >= 0), or
        None where r lies outside ``restitution.SOLVER_RESTITUTION_RANGE``.

    Examples
    --------
    >>> from fractions import Fraction
    >>> from bouncing_ball.solver import solved_outgoing_density
    >>> print(solved_outgoing_density(Fraction(1, 100)))
    None
    """
    if not in_range(restitution, SOLVER_RESTITUTION_RANGE):
        return None
    return solve_outgoing_speed_density(restitution).outgoing_speed_density


def momentum_balance_residual(solution) -> float:
    """M_2 / (r / (1 + r)) - 1: how far a solution is from the momentum balance (momentum) above.

    ``solve_outgoing_speed_density`` normalises by this balance, so its solutions have a
    residual at rounding level.

    Parameters
    ----------
    solution : OutgoingSpeedSolution

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = outgoing_speed_density(nodes, "1/2")
    >>> exact = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> from bouncing_ball.solver import momentum_balance_residual
    >>> abs(momentum_balance_residual(exact)) < 1e-12
    True
    """
    r = solution.restitution
    return solution.moment(2) / (r / (1.0 + r)) - 1.0


def energy_balance_residual(solution) -> float:
    """M_3 / (2 r^2 / (1 - r^2)) - 1: how far a solution is from the energy balance (energy) above.

    An independent check of a solution normalised by the momentum balance.

    Parameters
    ----------
    solution : OutgoingSpeedSolution

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = outgoing_speed_density(nodes, "1/2")
    >>> exact = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> from bouncing_ball.solver import energy_balance_residual
    >>> abs(energy_balance_residual(exact)) < 1e-10
    True
    """
    r = solution.restitution
    return solution.moment(3) / (2.0 * r * r / (1.0 - r * r)) - 1.0


def time_averages(solution) -> dict:
    """<x>, Delta x (eq. (xandDeltax)) and I (eq. (collrate)) from the moments of P(0, v).

    By the Ito identities of the module's docstring.

    Parameters
    ----------
    solution : OutgoingSpeedSolution

    Returns
    -------
    dict
        ``mean_x`` (<x>), ``delta_x`` (Delta x) and ``collision_rate`` (I = M_1; inf where
        r <= r_c).

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = outgoing_speed_density(nodes, "1/2")
    >>> exact = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> from bouncing_ball.solver import time_averages
    >>> print({name: round(value, 8) for name, value in time_averages(exact).items()})
    {'mean_x': 6.0, 'delta_x': 10.39230485, 'collision_rate': 0.33333333}
    """
    r = solution.restitution
    mean_x = (1.0 + r**3) * solution.moment(4) / (3.0 * r**3)
    fourth_speed = (1.0 + r**5) * solution.moment(6) / (5.0 * r**5) - 8.0 * mean_x
    mean_x_squared = 2.0 / 3.0 * fourth_speed
    return {
        "mean_x": mean_x,
        "delta_x": float(np.sqrt(mean_x_squared - mean_x**2)),
        "collision_rate": solution.moment(1),
    }


#: The smallest speed the workflow writes P(0, v) at (``solver.output_speeds``): there
#: A v^-beta (eq. (asym1)) stays below 1e250 for every r the solver answers (beta < 5/2).
SMALLEST_OUTPUT_SPEED = 1e-100

#: The accuracy the solver is held to: relative error of P(0, v) over CHECKED_SPEEDS
#: (independent of the output grid), and of the energy balance (M_3 above).
ACCURACY_TARGET = 1e-8
#: The finer discretisation every accuracy estimate compares with (``accuracy_estimate``,
#: ``relaxation.relaxation_accuracy``, ``time_relaxation.time_relaxation_accuracy``): the
#: step, the lowest node and the highest node times these.
FINER_STEP, FINER_LOWEST_SPEED, FINER_HIGHEST_SPEED = 0.8, 1e-4, 1.2

#: The speeds at which ``accuracy_estimate`` compares P(0, v) with a finer solve.
CHECKED_SPEEDS = np.geomspace(1e-3, 20.0, 400)


def accuracy_estimate(solution) -> float:
    """Largest relative change of P(0, v) over CHECKED_SPEEDS against a finer solve.

    The finer solve has step x 0.8, lowest node x 1e-4, highest node x 1.2 (where P stays a
    normal double).

    Parameters
    ----------
    solution : OutgoingSpeedSolution
        A solution of ``solve_outgoing_speed_density``.

    Returns
    -------
    float
        max abs(P(0, v) / P_finer(0, v) - 1) over the speeds of ``CHECKED_SPEEDS`` where P_finer
        is positive; compare with ``ACCURACY_TARGET``.

    Examples
    --------
    Solves twice, compiling the kernel on its first call (so not run as a doctest):

    >>> from bouncing_ball.solver import ACCURACY_TARGET, accuracy_estimate
    >>> from bouncing_ball.solver import solve_outgoing_speed_density
    >>> solution = solve_outgoing_speed_density("1/2")  # doctest: +SKIP
    >>> accuracy_estimate(solution) < ACCURACY_TARGET  # doctest: +SKIP
    True
    """
    r = solution.restitution
    cap = 0.99 * UNDERFLOW_EFOLDS / large_speed_decay_rate(r)
    finer = solve_outgoing_speed_density(
        r,
        step=FINER_STEP * solution.step,
        lowest_speed=FINER_LOWEST_SPEED * solution.speeds[0],
        highest_speed=min(FINER_HIGHEST_SPEED * solution.speeds[-1], cap),
    )
    reference = finer.outgoing_speed_density(CHECKED_SPEEDS)
    usable = reference > 0.0  # below r ~ 0.015, P(0, 20) underflows
    estimate = solution.outgoing_speed_density(CHECKED_SPEEDS[usable]) / reference[usable]
    return float(np.max(np.abs(estimate - 1.0)))


def solution_summary(solution, with_accuracy_estimate=True) -> dict:
    """One row of the solver's summary of a solution.

    Parameters
    ----------
    solution : OutgoingSpeedSolution
    with_accuracy_estimate : bool, optional
        Whether to add ``accuracy_estimate`` (it costs a second, finer solve).

    Returns
    -------
    dict
        ``r``, the exponent beta (``small_speed_exponent``), <x>, Delta x and I
        (``time_averages``), the balance residuals, ``eigenvalue_residual`` (eigenvalue - 1),
        the grid (``grid_size``, ``lowest_speed``, ``highest_speed``) and, if asked,
        ``accuracy_estimate``.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = outgoing_speed_density(nodes, "1/2")
    >>> exact = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> from bouncing_ball.solver import solution_summary
    >>> row = solution_summary(exact, with_accuracy_estimate=False)
    >>> print(row["grid_size"], round(row["mean_x"], 8), row["eigenvalue_residual"])
    160 6.0 0.0
    """
    row = {
        "r": solution.restitution,
        "small_speed_exponent": solution.small_speed_exponent,
        **time_averages(solution),
        "momentum_balance_residual": momentum_balance_residual(solution),
        "energy_balance_residual": energy_balance_residual(solution),
        "eigenvalue_residual": solution.eigenvalue - 1.0,
        "grid_size": len(solution.speeds),
        "lowest_speed": solution.speeds[0],
        "highest_speed": solution.speeds[-1],
    }
    if with_accuracy_estimate:
        row["accuracy_estimate"] = accuracy_estimate(solution)
    return row
