"""P(0, v) as w(F) of eq. (weightfunc) needs it: on the real axis and at complex v.

``outgoing_speed_solution`` solves eq. (inteq) out to where P(0, v) falls to e^-690 (w(F) at
small F needs P(0, v) far out), and ``restitution.check_distribution_range`` holds r to the range where
w(F), P(x) and P(x, v) are verified.  ``_outgoing_density`` turns a solution into
``_OutgoingDensity``: ln P(0, v) on the real axis by Chebyshev panels in s = ln v + v^(1/2), and
P(0, v) e^(q v) at complex v by the Nystrom formula of ``complex_kernel`` on a u grid REFINE
times finer than the solver's (the trapezoidal rule in ln u loses accuracy as
exp(-2 pi (pi/3 - arg v) / step)), summed at the nodes of Chebyshev cells of the wedge
0 <= arg v <= THETA_MAX and interpolated in between (``_OutgoingDensity.scaled_complex``;
directly where the sums cancel).  Where r > RAY_RESTITUTION it carries P(0, v) on the ray of
``ray_density`` as well.
"""

import functools
from dataclasses import dataclass, field

import numpy as np

from ..asymptotics import large_speed_decay_rate
from ..restitution import check_distribution_range
from ..solver import (
    DEFAULT_STEP,
    TAIL_EFOLDS,
    UNDERFLOW_EFOLDS,
    _jacobian,
    coordinate_of_speed,
    solve_outgoing_speed_density,
    speed_of_coordinate,
)
from .complex_kernel import (
    _HERMITE_COUNTS,
    _HERMITE_LIMITS,
    _HERMITE_W,
    _HERMITE_X2,
    _TAU_COUNTS,
    _TAU_LIMITS,
    _TAU_W,
    _TAU_X,
    _complex_kernel_sums,
)
from .ray_density import RAY_RESTITUTION, _ray_density

__all__ = [
    "THETA_MAX",
    "WEDGE_CLEAN",
    "outgoing_speed_solution",
]


#: The largest arg v on the contour of A(F) in eq. (weightfunc): the trapezoidal rule of the
#: complex Nystrom sum loses accuracy there as exp(-2 pi (pi/3 - THETA_MAX) / step).
THETA_MAX = 0.5


REFINE = 2  # the u grid for complex v is this many times finer than the solver's


SMALLEST_SPEED = 1e-14  # below, P(0, v) = C v^-beta and the v integrals are done in closed form


PANEL_NODES = 10  # Gauss-Legendre nodes per panel of the real-axis v integrals


REAL_PANEL_WIDTH = 0.5  # in s, of the panels of the real-axis part of A(F)


# P(0, v) e^(q v) in the wedge 0 <= arg v <= THETA_MAX, |v| >= WEDGE_SMALLEST_SPEED, is
# interpolated from Nystrom sums at the nodes of cells WEDGE_SPEED_WIDTH wide in s = ln |v| +
# |v|^(1/2) and across the wedge's angle (tensor Chebyshev, ~1e-13 relative: the contour
# integrals of w(F) need ~1e4 values per r, the cells ~1e3 sums; one panel of 12 nodes across
# the angle is as accurate as two of 8, and 22 nodes across 4 in s as two of 14 across 2, each
# with fewer sums).  Where a cell's sums cancel (at its largest arg v first) a cell across the
# lower half of the angle, WEDGE_LOW_ANGLE_NODES wide, serves the v there if its own sums do
# not cancel.
WEDGE_SMALLEST_SPEED = 5e-4


WEDGE_SPEED_WIDTH = 4.0


WEDGE_SPEED_NODES = 22


WEDGE_ANGLE_NODES = 12


WEDGE_LOW_ANGLE_NODES = 8


#: A cell of the interpolant of P(0, v) e^(q v) in the wedge 0 <= arg v <= THETA_MAX whose
#: Nystrom sums cancel by more (magnitude / abs(value)) is not interpolated: its nodes' rounding
#: errors would spread over it (the bound of the spread, in the noise estimate of w, would raise
#: F_min where r > 0.9); its v are summed directly.
WEDGE_CLEAN = 1e6


ACCURATE_RANGE = 0.4  # P(0, v) of a solution is used up to this fraction of its highest node


_GL_X, _GL_W = np.polynomial.legendre.leggauss(PANEL_NODES)


def _chebyshev_nodes_and_inverse(count):
    x = np.cos(np.pi * (np.arange(count) + 0.5) / count)
    return x, np.linalg.inv(np.polynomial.chebyshev.chebvander(x, count - 1))


_WEDGE_SPEED_X, _WEDGE_INVERSE_SPEED = _chebyshev_nodes_and_inverse(WEDGE_SPEED_NODES)


# the angle layouts of the wedge cells: (width in arg v from 0, Chebyshev nodes, inverse)
_WEDGE_ANGLES = (
    (THETA_MAX, *_chebyshev_nodes_and_inverse(WEDGE_ANGLE_NODES)),
    (0.5 * THETA_MAX, *_chebyshev_nodes_and_inverse(WEDGE_LOW_ANGLE_NODES)),
)


def outgoing_speed_solution(restitution, step=DEFAULT_STEP):
    """P(0, v) of eq. (inteq), solved out to where it falls to exp(-690), as w(F) needs it.

    The solver's default highest node stops where P(0, v) has fallen by exp(-45) below its value
    at v = 20; w(F) of eq. (weightfunc) at small F needs P(0, v) far out (v ~ q (1 - q) / F), so
    the highest node here is where P(0, v) reaches exp(-690).

    Parameters
    ----------
    restitution : float or str
        r, a float or a fraction string ("1/3"), in ``DISTRIBUTION_RESTITUTION_RANGE``
        (``restitution.check_distribution_range``).
    step : float, optional
        The solver's quadrature step in s = ln u + u^(1/2) (``solver.DEFAULT_STEP``).

    Returns
    -------
    solver.OutgoingSpeedSolution
        P(0, v) at the solver's nodes, absolutely normalised.

    Raises
    ------
    ValueError
        If r lies outside ``DISTRIBUTION_RESTITUTION_RANGE``, or the solver refuses ``step``.

    Examples
    --------
    Compiles the kernel on its first call (so not run as a doctest); at r = 1/2 the solution
    is eq. (P(0,v)), e^(-v) / (3 v):

    >>> from bouncing_ball.distribution import outgoing_speed_solution
    >>> solution = outgoing_speed_solution("1/2")  # doctest: +SKIP
    >>> print(round(solution.speeds[-1], 2))  # doctest: +SKIP
    680.97
    >>> print(solution.outgoing_speed_density([0.5, 1.0]).round(8))  # doctest: +SKIP
    [0.40435377 0.12262648]
    """
    r = float(check_distribution_range(restitution, "restitution"))
    q = large_speed_decay_rate(r)
    return solve_outgoing_speed_density(r, step=step, highest_speed=0.985 * UNDERFLOW_EFOLDS / q)


@dataclass(frozen=True)
class _OutgoingDensity:
    """ln P(0, v) for real v > 0, and P(0, v) e^(q v) for complex v, from a solution."""

    restitution: float
    beta: float
    q: float
    log_amplitude: complex  # ln C (real up to the solution's error), P(0, v) = C v^-beta below the solution's lowest node
    lowest: float
    largest: float  # P(0, v) is trusted up to here
    panel_edges: np.ndarray  # in s = ln v + v^(1/2)
    coefficients: np.ndarray  # Chebyshev coefficients of ln P + beta ln v + q v, per panel
    nodes: np.ndarray  # u grid of the complex Nystrom sum (empty where r > RAY_RESTITUTION)
    log_weights: np.ndarray  # ln(weight u P(0, u))
    remainder: float  # closed-form part of the lower tail, times P(0, u_0)
    # P(0, v) on the ray arg v = RAY_ANGLE where r > RAY_RESTITUTION (``_RayDensity``), else None
    ray: object = None
    # cells of the interpolant of P(0, v) e^(q v) in the wedge (``_wedge_cell``), built on use
    cells: dict = field(default_factory=dict, compare=False, repr=False)

    def log_density(self, v):
        """ln P(0, v), real v in (0, largest]."""
        v = np.asarray(v, dtype=float)
        s = coordinate_of_speed(np.maximum(v, self.lowest))
        index = np.clip(np.searchsorted(self.panel_edges, s) - 1, 0, len(self.coefficients) - 1)
        lo, hi = self.panel_edges[index], self.panel_edges[index + 1]
        t = (2.0 * s - lo - hi) / (hi - lo)
        c = self.coefficients[index]
        b1 = np.zeros_like(t)
        b2 = np.zeros_like(t)
        for k in range(c.shape[1] - 1, 0, -1):
            b1, b2 = c[:, k] + 2.0 * t * b1 - b2, b1
        smooth = c[:, 0] + t * b1 - b2
        below = v < self.lowest
        power = self.log_amplitude - self.beta * np.log(np.where(v > 0, v, 1.0))
        return np.where(below, power, smooth - self.beta * np.log(v) - self.q * v)

    def scaled_complex(self, v, slack=None, with_noise=True):
        """P(0, v) e^(q v) at complex v, |arg v| < pi/3, and a bound on its rounding error in
        units of EPSILON: from the wedge interpolant (``_wedge_cell``) where v lies in a clean
        cell of it, else from the Nystrom sum (``scaled_complex_direct``, with ``slack``).
        Without ``with_noise`` the interpolated v's bound is not computed (NaN)."""
        v = np.asarray(v, dtype=complex)
        shape = v.shape
        v = v.ravel()
        slack = np.zeros(v.size) if slack is None else np.asarray(slack, dtype=float).ravel()
        value, magnitude = np.empty(v.size, dtype=complex), np.empty(v.size)
        rho, theta = np.abs(v), np.angle(v)
        inside = (
            (rho >= WEDGE_SMALLEST_SPEED)
            & (rho <= self.largest)
            & (theta >= -1e-12)
            & (theta <= THETA_MAX + 1e-12)
        )
        sigma = coordinate_of_speed(np.where(inside, rho, 1.0))
        row = np.floor((sigma - self._wedge_origin) / WEDGE_SPEED_WIDTH).astype(int)
        direct = ~inside
        for index in set(row[inside].tolist()):
            left = inside & (row == index)  # not yet evaluated
            for layout, (width, *_) in enumerate(_WEDGE_ANGLES):
                members = left & (theta <= width + 1e-12)
                if not members.any():
                    continue
                cell = self._wedge_cell(index, layout)
                if cell is not None:
                    value[members], magnitude[members] = _evaluate_wedge_cell(
                        cell,
                        (index, layout),
                        self._wedge_origin,
                        sigma[members],
                        theta[members],
                        v[members],
                        self.beta,
                        with_noise,
                    )
                    left &= ~members
            direct |= left
        if direct.any():
            value[direct], magnitude[direct] = self.scaled_complex_direct(v[direct], slack[direct])
        return value.reshape(shape), magnitude.reshape(shape)

    def real_axis_nodes(self, v1):
        """Gauss-Legendre nodes v of int_{SMALLEST_SPEED}^{v1} dv on panels REAL_PANEL_WIDTH
        wide in s = ln v + v^(1/2) from SMALLEST_SPEED (the last one shorter), and ln of
        weight x v h(v), h(v) = e^(v/2) P(0, v): the complete panels' from a table kept for
        all F, the last one's computed."""
        lo, hi = coordinate_of_speed(SMALLEST_SPEED), coordinate_of_speed(v1)
        complete = min(
            int((hi - lo) / REAL_PANEL_WIDTH), self._real_axis_table[0].size // PANEL_NODES
        )
        v, log_vh = (part[: complete * PANEL_NODES] for part in self._real_axis_table)
        start = lo + complete * REAL_PANEL_WIDTH
        if hi > start:
            last_v, last_log_vh = self._real_axis_terms(*_panels(start, hi, REAL_PANEL_WIDTH))
            v, log_vh = np.concatenate([v, last_v]), np.concatenate([log_vh, last_log_vh])
        return v, log_vh

    def _real_axis_terms(self, s, ws):
        v = speed_of_coordinate(s)
        return v, np.log(ws * _jacobian(v) * v) + 0.5 * v + self.log_density(v)

    @functools.cached_property
    def _real_axis_table(self):
        lo, hi = coordinate_of_speed(SMALLEST_SPEED), coordinate_of_speed(self.largest)
        count = int((hi - lo) / REAL_PANEL_WIDTH)
        return self._real_axis_terms(*_panels(lo, lo + count * REAL_PANEL_WIDTH, REAL_PANEL_WIDTH))

    @functools.cached_property
    def _wedge_origin(self):
        return float(coordinate_of_speed(WEDGE_SMALLEST_SPEED))

    def _wedge_cell(self, row, layout):
        """One cell of the interpolant of P(0, v) e^(q v) in the wedge 0 <= arg v <= THETA_MAX
        (``layout`` 0: the whole angle; 1: its lower half): the Chebyshev coefficients (in
        s = ln |v| + |v|^(1/2) and arg v) of ln(P(0, v) e^(q v)) + beta ln v, and
        magnitude / |value| of the Nystrom sums at its nodes; None for a cell in which that
        ratio exceeds WEDGE_CLEAN somewhere (such v are summed directly)."""
        key = (row, layout)
        if key not in self.cells:
            self.cells[key] = self._build_wedge_cell(row, layout)
        return self.cells[key]

    def _build_wedge_cell(self, row, layout):
        width, angle_x, inverse_angle = _WEDGE_ANGLES[layout]
        sigma = self._wedge_origin + WEDGE_SPEED_WIDTH * (row + 0.5 * (_WEDGE_SPEED_X + 1.0))
        theta = width * 0.5 * (angle_x + 1.0)
        # the noisiest node first (largest |v| and arg v): a dirty cell costs one sum
        corner = speed_of_coordinate(sigma.max()) * np.exp(1j * theta.max())
        value, magnitude = self.scaled_complex_direct(np.array([corner]))
        if not magnitude[0] <= WEDGE_CLEAN * abs(value[0]):
            return None
        rho = speed_of_coordinate(sigma)
        v = rho[:, None] * np.exp(1j * theta[None, :])
        value, magnitude = (part.reshape(v.shape) for part in self.scaled_complex_direct(v))
        noise = magnitude / np.abs(value)
        if not np.all(noise <= WEDGE_CLEAN):
            return None
        log_value = np.log(value) + self.beta * np.log(v)
        return _WEDGE_INVERSE_SPEED @ log_value @ inverse_angle.T, noise

    def scaled_complex_direct(self, v, slack=None):
        """P(0, v) e^(q v) at complex v, |arg v| < pi/3, by the Nystrom sum, and the sum of the
        magnitudes of its terms (rounding errors are ~1e-16 of it: at complex v the terms
        cancel, increasingly so as Im(v)^2 / Re(v) grows).  ``slack``: per v, the e-folds by
        which its result may be less accurate (``_complex_kernel_sums``; none if None)."""
        if self.ray is not None:
            raise ValueError(
                f"r = {self.restitution}: above RAY_RESTITUTION, A(F) is taken on the ray "
                "and P(0, v) has no wedge grid (use ray.log_density)"
            )
        v = np.ascontiguousarray(np.asarray(v, dtype=complex).ravel())
        slack = np.zeros(v.size) if slack is None else np.ascontiguousarray(slack, dtype=float)
        r = self.restitution
        out = np.empty(v.size, dtype=complex)
        magnitude = np.empty(v.size)
        _complex_kernel_sums(
            v,
            r,
            self.q,
            self.nodes,
            self.log_weights,
            _TAU_X,
            _TAU_W,
            _TAU_COUNTS,
            _TAU_LIMITS,
            _HERMITE_X2,
            _HERMITE_W,
            _HERMITE_COUNTS,
            _HERMITE_LIMITS,
            slack,
            out,
            magnitude,
        )
        incoming = v / r
        tail = (
            self.remainder
            * 1.5
            / np.pi
            * incoming**-2.5
            * (1.0 + incoming)
            * np.exp(-0.5 * incoming + self.q * v)
        )
        shape = np.shape(v)
        return (out + tail / (r * r)).reshape(shape), (magnitude + np.abs(tail) / (r * r)).reshape(
            shape
        )


def _evaluate_wedge_cell(cell, key, origin, sigma, theta, v, beta, with_noise=True):
    """P(0, v) e^(q v) from a wedge cell, and the sum of the rounding errors of its nodes'
    Nystrom sums weighted by |Lagrange basis| at v (in the units of ``scaled_complex_direct``'s
    magnitude: the interpolant carries the rounding errors of all its nodes; NaN without
    ``with_noise``)."""
    coefficients, noise = cell
    width, angle_x, inverse_angle = _WEDGE_ANGLES[key[1]]
    t_speed = 2.0 * (sigma - origin) / WEDGE_SPEED_WIDTH - 2.0 * key[0] - 1.0
    t_angle = 2.0 * theta / width - 1.0
    speed = np.polynomial.chebyshev.chebvander(t_speed, WEDGE_SPEED_NODES - 1)
    angle = np.polynomial.chebyshev.chebvander(t_angle, angle_x.size - 1)
    value = np.exp(np.einsum("pj,pj->p", speed @ coefficients, angle) - beta * np.log(v))
    if not with_noise:
        return value, np.full(value.shape, np.nan)
    lagrange_speed = np.abs(speed @ _WEDGE_INVERSE_SPEED)
    lagrange_angle = np.abs(angle @ inverse_angle)
    spread = np.einsum("pj,pj->p", lagrange_speed @ noise, lagrange_angle)
    return value, np.abs(value) * spread


#: Above this s = ln v + v^(1/2), the real-axis Chebyshev panels of ``_outgoing_density`` are
#: twice ``panel_width`` wide: there they hold ln P(0, v) to 1.1e-13 of the Nystrom formula
#: at r = 0.25 and 0.99 (as panels 1 wide do; 2 wide below s = 0 they reach only 2e-11).
REAL_PANEL_GRADE = 5.0


def _outgoing_density(solution, panel_width=1.0, panel_order=20) -> _OutgoingDensity:
    r = solution.restitution
    beta = solution.small_speed_exponent
    q = large_speed_decay_rate(r)
    u0 = solution.speeds[0]
    largest = ACCURATE_RANGE * solution.speeds[-1]
    log_amplitude = float(np.log(solution.outgoing_speed_density(u0)) + beta * np.log(u0))
    # Chebyshev panels in s for ln P + beta ln v + q v (smooth, O(1))
    s_lo, s_hi = coordinate_of_speed(u0), coordinate_of_speed(largest)
    # twice as wide above s = REAL_PANEL_GRADE (v ~ 7), where ln P + beta ln v + q v is smoother
    s_mid = min(max(REAL_PANEL_GRADE, s_lo), s_hi)
    low = max(1, int(np.ceil((s_mid - s_lo) / panel_width))) if s_mid > s_lo else 0
    high = int(np.ceil((s_hi - s_mid) / (2.0 * panel_width))) if s_hi > s_mid else 0
    edges = np.unique(
        np.concatenate([np.linspace(s_lo, s_mid, low + 1), np.linspace(s_mid, s_hi, high + 1)])
    )
    count = edges.size - 1
    cheb = np.cos(np.pi * (np.arange(panel_order) + 0.5) / panel_order)
    s = 0.5 * (edges[:-1, None] + edges[1:, None]) + 0.5 * np.diff(edges)[:, None] * cheb[None, :]
    v = speed_of_coordinate(s.ravel())
    smooth = np.log(solution.outgoing_speed_density(v)) + beta * np.log(v) + q * v
    coefficients = np.array(
        [
            np.polynomial.chebyshev.chebfit(cheb, row, panel_order - 1)
            for row in smooth.reshape(count, panel_order)
        ]
    )
    if r > RAY_RESTITUTION:
        # A(F) is taken on the ray (``_ray_density``): no wedge, no complex Nystrom sum
        return _OutgoingDensity(
            r,
            beta,
            q,
            log_amplitude,
            u0,
            largest,
            edges,
            coefficients,
            np.empty(0),
            np.empty(0),
            np.nan,
            _ray_density(solution),
        )
    # the u grid of the complex Nystrom sum: the solver's rule, REFINE times finer
    step = solution.step / REFINE
    s0 = coordinate_of_speed(u0)
    s_top = coordinate_of_speed(solution.speeds[-1])
    main = speed_of_coordinate(s0 + step * np.arange(int(np.floor((s_top - s0) / step)) + 1))
    main_density = solution.outgoing_speed_density(main)
    tail_count = int(np.ceil(TAIL_EFOLDS / step))
    tail = speed_of_coordinate(s0 - step * np.arange(1, tail_count + 1))
    tail_density = main_density[0] * (tail / u0) ** -beta
    nodes = np.concatenate([tail[::-1], main])
    density = np.concatenate([tail_density[::-1], main_density])
    with np.errstate(divide="ignore"):
        log_weights = np.log(step * _jacobian(nodes) * nodes * density)
    alpha = 2.5 - beta
    remainder = (
        step
        * u0**2.5
        * np.exp(-alpha * (tail_count + 1) * step)
        / -np.expm1(-alpha * step)
        * main_density[0]
    )
    return _OutgoingDensity(
        r,
        beta,
        q,
        log_amplitude,
        u0,
        largest,
        edges,
        coefficients,
        nodes,
        log_weights,
        remainder,
        None,
    )


def _panels(lo, hi, width):
    """Gauss-Legendre nodes and weights on [lo, hi] cut into panels no wider than ``width``."""
    count = max(1, int(np.ceil((hi - lo) / width)))
    edges = np.linspace(lo, hi, count + 1)
    half = 0.5 * np.diff(edges)[:, None]
    x = (0.5 * (edges[:-1, None] + edges[1:, None]) + half * _GL_X[None, :]).ravel()
    w = (half * _GL_W[None, :]).ravel()
    return x, w
