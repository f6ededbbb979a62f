"""P(0, v) on the ray arg v = RAY_ANGLE, solved from eq. (inteq) with u on the same ray (r near 1).

Near r = 1 (r > RAY_RESTITUTION) the wedge contour of A(F) in eq. (weightfunc)
(``weight_function``) fails: its sums at complex v cancel like exp(c abs(v) theta^2) with
abs(v) ~ q / F, and its integrand on the radial leg rises above the result.  A(F) is then 2 Re
of the integral along one ray from v = 0, arg v = RAY_ANGLE, with P(0, v) on the ray solved from
eq. (inteq) with u on the same ray (``_RayDensity``, a sparse band operator; docs/distribution.md,
"Where it degrades").
"""

import cmath
import math
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse import linalg as sparse_linalg

from ..asymptotics import large_speed_decay_rate
from ..jit import njit
from ..kernel import TAIL as KERNEL_TAIL
from ..kernel import _full_geometry
from ..solver import (
    TAIL_EFOLDS,
    UNDERFLOW_EFOLDS,
    _jacobian,
    coordinate_of_speed,
    speed_of_coordinate,
)
from .complex_kernel import _HERMITE_W, _HERMITE_X2, TAU_HERMITE_NODES, _principal_sqrt

__all__ = []


NEGLIGIBLE_EFOLDS = 60.0


#: The angle of the ray of P(0, v) and of the contour of A(F) where r > RAY_RESTITUTION.  From
#: v = 0 along this ray the integrand of A(F), e^(Phi(F v) / F) with
#: Phi(w) = (1/2 - q) w - (2/3) (omega (1/4 - w))^(3/2), has its largest modulus at v = 0
#: (Re Phi(0) = 1/12) for every q <= q(0.999) (at arg v <= 0.7 it rises above that where
#: r >= 0.99, by e^(0.02 / F) at 0.5): the sum cancels by e^((S + 1/12) / F) only.
RAY_ANGLE = 0.8


#: Above this r, A(F) is taken along the ray (``_RayDensity``) instead of the wedge contour.
RAY_RESTITUTION = 0.9


#: The ray's nodes reach RAY_REACH / q (P(0, v) ~ e^(-RAY_REACH cos(RAY_ANGLE)) there); the
#: values are used up to half of it (the truncated operator spoils the top of its grid).
RAY_REACH = 400.0


RAY_REFINE = 2  # the ray's grid is this many times finer than the solver's


#: An entry of the ray's operator whose Gaussian bound is below e^-RAY_NEGLIGIBLE_EFOLDS
#: (~1e-39) of its row's largest is dropped: the operator is a band where rho is large (the
#: return speed of a flight leaving at u spreads over ~(4 u / 3)^(1/2)), solved as sparse.
RAY_NEGLIGIBLE_EFOLDS = 90.0


_RAY_GL = tuple(np.polynomial.legendre.leggauss(count) for count in (20, 40, 64))


_RAY_GL_X = np.zeros((3, 64))


_RAY_GL_W = np.zeros((3, 64))


for _k, (_x, _w) in enumerate(_RAY_GL):
    _RAY_GL_X[_k, : _x.size], _RAY_GL_W[_k, : _x.size] = 0.5 * (_x + 1.0), 0.5 * _w


_RAY_HERMITE_X2 = _HERMITE_X2[-1, : TAU_HERMITE_NODES[-1]].copy()


_RAY_HERMITE_W = _HERMITE_W[-1, : TAU_HERMITE_NODES[-1]].copy()


@njit(cache=True)
def _ray_log_kernel(rho_v, rho_u, ray, gl_x, gl_w, hermite_x2, hermite_w):
    """ln G_g(V, u) of eq. (kernel3) for V = rho_v ray, u = rho_u ray on one ray (|ray| = 1,
    |arg ray| < pi/2): with both on the ray z0 -> ray z0, the exponent -> ray exponent and tau1
    stays real (kernel._full_geometry of rho_v, rho_u).  The tau integral: to infinity along
    arg tau = -arg(ray)/2 by Gauss-Hermite (12 nodes, |z0| > TAIL^2) where Re(z0 tau1^2) >
    TAIL^2, else Gauss-Legendre on [0, tau1] with 20, 40 or 64 nodes as |z0| tau1^2 (the
    radians its phase turns, times 1/sin(arg ray)) is below 3, 15 or above."""
    exponent, z0_real, tau1 = _full_geometry(rho_v, rho_u)
    if tau1 <= 0.0:
        return complex(-np.inf, 0.0)
    z0 = ray * z0_real
    size = z0_real * tau1 * tau1
    if z0.real * tau1 * tau1 > KERNEL_TAIL * KERNEL_TAIL:
        acc = 0.0 + 0.0j
        inverse_z0 = 1.0 / z0
        for k in range(hermite_x2.size):
            t2 = hermite_x2[k] * inverse_z0
            one_t2 = 1.0 + t2
            acc += hermite_w[k] * (
                (1.0 + z0 + hermite_x2[k]) / (one_t2 * one_t2 * _principal_sqrt(2.0 + t2))
            )
        integral = acc / _principal_sqrt(z0)
    else:
        rule = 0 if size < 3.0 else (1 if size < 15.0 else 2)
        acc = 0.0 + 0.0j
        for k in range(gl_x.shape[1]):
            if gl_w[rule, k] == 0.0:
                break
            tau = tau1 * gl_x[rule, k]
            t2 = tau * tau
            one_t2 = 1.0 + t2
            acc += gl_w[rule, k] * (
                cmath.exp(-z0 * t2) * (1.0 + z0 * one_t2) / (one_t2 * one_t2 * math.sqrt(2.0 + t2))
            )
        integral = tau1 * acc
    return (
        math.log(math.sqrt(3.0) / math.pi)
        + ray * exponent
        + cmath.log(integral)
        - 2.0 * cmath.log(z0)
    )


@njit(cache=True)
def _ray_operator_band(
    rho_v, rho_u, log_columns, log_rows, floor, cut, ray, gl_x, gl_w, hermite_x2, hermite_w
):
    """The entries M_ij = exp(ln G_g(rho_v_i ray, rho_u_j ray) + log_columns_j - log_rows_i)
    that matter, as a CSR matrix (indptr, indices, data) and each row's largest Gaussian bound.

    The bound of M_ij is its level ray.real (-(3/4) (v - u)^2 / ((v + u)/2 + z0)) (the kernel's
    Gaussian, ``kernel._full_geometry``) + Re(log_columns_j - log_rows_i).  Row i keeps the
    contiguous j from the node nearest to rho_v_i outward both ways, and stops on a side where
    the level of every further entry is below the row's largest level (at least floor_i) by
    cut: the Gaussian falls away from u = v on both sides (width ~ (4 u / 3)^(1/2), so the rows
    of large rho keep a band) and the column factor beyond is at most its running maximum."""
    count_v = rho_v.size
    count_u = rho_u.size
    columns = log_columns.real
    ahead = np.empty(count_u)  # max of columns[j:]
    behind = np.empty(count_u)  # max of columns[:j + 1]
    ahead[count_u - 1] = columns[count_u - 1]
    for j in range(count_u - 2, -1, -1):
        ahead[j] = max(columns[j], ahead[j + 1])
    behind[0] = columns[0]
    for j in range(1, count_u):
        behind[j] = max(columns[j], behind[j - 1])
    lo = np.empty(count_v, dtype=np.int64)
    hi = np.empty(count_v, dtype=np.int64)
    best = np.empty(count_v)
    for i in range(count_v):
        start = np.searchsorted(rho_u, rho_v[i])  # rho_u[j] >= rho_v[i] from here
        top = floor[i]
        lo[i] = start
        for j in range(start - 1, -1, -1):  # u < v: the Gaussian falls as j decreases
            exponent, _, _ = _full_geometry(rho_v[i], rho_u[j])
            top = max(top, ray.real * exponent + columns[j] - log_rows[i].real)
            if ray.real * exponent + behind[j] - log_rows[i].real < top - cut:
                break
            lo[i] = j
        hi[i] = start - 1
        for j in range(start, count_u):  # u >= v: the Gaussian falls as j increases
            exponent, _, _ = _full_geometry(rho_v[i], rho_u[j])
            top = max(top, ray.real * exponent + columns[j] - log_rows[i].real)
            if ray.real * exponent + ahead[j] - log_rows[i].real < top - cut:
                break
            hi[i] = j
        best[i] = top
    indptr = np.zeros(count_v + 1, dtype=np.int64)
    for i in range(count_v):
        indptr[i + 1] = indptr[i] + max(0, hi[i] - lo[i] + 1)
    indices = np.empty(indptr[-1], dtype=np.int64)
    data = np.zeros(indptr[-1], dtype=np.complex128)
    for i in range(count_v):
        k = indptr[i]
        for j in range(lo[i], hi[i] + 1):
            indices[k] = j
            exponent, _, _ = _full_geometry(rho_v[i], rho_u[j])
            level = ray.real * exponent + columns[j] - log_rows[i].real
            if level >= best[i] - cut and level >= -UNDERFLOW_EFOLDS:
                log_g = _ray_log_kernel(rho_v[i], rho_u[j], ray, gl_x, gl_w, hermite_x2, hermite_w)
                data[k] = cmath.exp(log_g + log_columns[j] - log_rows[i])
            k += 1
    return indptr, indices, data, best


def _ray_operator(rho_v, rho_u, log_columns, tail_u, tail_columns, log_rows, ray):
    """The scaled Nystrom operator of eq. (inteq) on the ray (``_ray_density``), sparse: the
    entries within e^-RAY_NEGLIGIBLE_EFOLDS of their row's largest Gaussian bound
    (``_ray_operator_band``), with the lower tail's (u = tail_u, below the lowest node) summed
    into column 0."""
    args = (ray, _RAY_GL_X, _RAY_GL_W, _RAY_HERMITE_X2, _RAY_HERMITE_W)
    rows = np.ascontiguousarray(log_rows)
    count = rho_v.size
    indptr, indices, data, best = _ray_operator_band(
        rho_v,
        rho_u,
        np.ascontiguousarray(log_columns),
        rows,
        np.full(count, -np.inf),
        RAY_NEGLIGIBLE_EFOLDS,
        *args,
    )
    operator = sparse.csr_matrix((data, indices, indptr), shape=(count, rho_u.size))
    indptr, indices, data, _ = _ray_operator_band(
        rho_v,
        tail_u,
        np.ascontiguousarray(tail_columns),
        rows,
        best,
        RAY_NEGLIGIBLE_EFOLDS,
        *args,
    )
    tail = sparse.csr_matrix((data, indices, indptr), shape=(count, tail_u.size))
    column = sparse.csr_matrix(
        (
            np.asarray(tail.sum(axis=1)).ravel(),
            np.zeros(count, dtype=np.int64),
            np.arange(count + 1),
        ),
        shape=(count, rho_u.size),
    )
    return operator + column


@njit(cache=True)
def _ray_sums(rho_v, rho_u, log_columns, shift, ray, gl_x, gl_w, hermite_x2, hermite_w):
    """sum_j exp(ln G_g(rho_v_i ray, rho_u_j ray) + log_columns_j + shift_i), skipping the terms whose
    Gaussian bound is below e^-(NEGLIGIBLE_EFOLDS + 20) of the largest (the sums are the same
    to 1e-16 with 70 e-folds)."""
    out = np.zeros(rho_v.size, dtype=np.complex128)
    levels = np.empty(rho_u.size)
    for i in range(rho_v.size):
        best = -np.inf
        for j in range(rho_u.size):
            exponent, z0, tau1 = _full_geometry(rho_v[i], rho_u[j])
            levels[j] = ray.real * exponent + log_columns[j].real + math.log(tau1 + 1e-300)
            best = max(best, levels[j])
        total = 0.0 + 0.0j
        for j in range(rho_u.size):
            if levels[j] < best - (NEGLIGIBLE_EFOLDS + 20.0):
                continue
            log_g = _ray_log_kernel(rho_v[i], rho_u[j], ray, gl_x, gl_w, hermite_x2, hermite_w)
            total += cmath.exp(log_g + log_columns[j] + shift[i])
        out[i] = total
    return out


@dataclass(frozen=True)
class _RayDensity:
    """P(0, v) on the ray v = rho e^(i RAY_ANGLE), solved from eq. (inteq) with u on the same
    ray (the u contour of the Nystrom formula rotated: no cancelling sum), normalised by the
    momentum balance M_2 = r / (1 + r) with its contour rotated onto the ray."""

    restitution: float
    beta: float
    q: float
    ray: complex
    log_amplitude: (
        complex  # ln C (real up to the solution's error), P(0, v) = C v^-beta below the lowest node
    )
    nodes: np.ndarray  # rho_j of the ray's grid (with the lower tail's nodes first)
    log_columns: np.ndarray  # ln(r^-2 u_j du_j P(0, u_j)), u_j = rho_j ray
    largest: float  # the ray's P(0, v) is used up to |v| = largest
    eigenvalue: complex
    panel_edges: np.ndarray  # in s, of the Chebyshev interpolant of ln(P e^(q v) v^beta)
    coefficients: np.ndarray
    #: relative error estimate of P(0, v) from ``log_density``: the interpolant against the
    #: Nystrom formula between its nodes, and |eigenvalue - 1| of the discrete operator
    error: float = np.nan

    def log_density(self, rho):
        """ln P(0, rho ray) for 0 < rho <= largest (complex): the interpolant from the lowest
        node up, the power law C v^-beta below."""
        rho = np.asarray(rho, dtype=float)
        s = coordinate_of_speed(rho)
        index = np.clip(np.searchsorted(self.panel_edges, s) - 1, 0, len(self.coefficients) - 1)
        lo, hi = self.panel_edges[index], self.panel_edges[index + 1]
        t = (2.0 * s - lo - hi) / (hi - lo)
        smooth = np.polynomial.chebyshev.chebval(t, self.coefficients[index].T, tensor=False)
        v = rho * self.ray
        power = self.log_amplitude - self.beta * np.log(v)
        return np.where(s < self.panel_edges[0], power, smooth - self.beta * np.log(v) - self.q * v)

    def nystrom(self, rho):
        """P(0, rho ray) e^(q rho ray) (rho ray)^beta by the Nystrom formula on the ray."""
        rho = np.ascontiguousarray(rho, dtype=float)
        v = rho * self.ray
        shift = self.q * v + self.beta * np.log(v)
        return _ray_sums(
            rho / self.restitution,
            self.nodes,
            self.log_columns,
            np.ascontiguousarray(shift),
            self.ray,
            _RAY_GL_X,
            _RAY_GL_W,
            _RAY_HERMITE_X2,
            _RAY_HERMITE_W,
        )


#: The Chebyshev panels of the ray's ln(P e^(q v) v^beta) in s: RAY_PANEL_WIDTH wide,
#: RAY_PANEL_ORDER nodes each.  Against the Nystrom formula on the ray from the lowest node to
#: ``largest`` (3000 points) they hold it to 8e-14 at r = 0.5, 0.95, 0.99 and 0.999, as panels
#: half as wide do (6e-14 to 9e-14: the formula's own rounding), at two thirds of the cost.
RAY_PANEL_WIDTH = 2.0


RAY_PANEL_ORDER = 20


def _ray_density(solution, panel_width=RAY_PANEL_WIDTH, panel_order=RAY_PANEL_ORDER) -> _RayDensity:
    """Solve eq. (inteq) on the ray arg v = RAY_ANGLE (``_RayDensity``): the solver's rule in
    s = ln rho + rho^(1/2), RAY_REFINE times finer, from its lowest node u_0 (with the power law
    below, as the solver) to RAY_REACH / q; the eigenvector of eigenvalue nearest 1 by inverse
    iteration on the operator scaled by u^-beta e^(-q u), a sparse band (``_ray_operator``) with
    a sparse LU, normalised by the momentum balance rotated onto the ray; then
    ln(P e^(q v) v^beta) on Chebyshev panels in s from the Nystrom formula on the ray."""
    r = solution.restitution
    beta = solution.small_speed_exponent
    q = large_speed_decay_rate(r)
    ray = complex(np.exp(1j * RAY_ANGLE))
    step = solution.step / RAY_REFINE
    u0 = solution.speeds[0]
    s0 = coordinate_of_speed(u0)
    count = int(np.floor((coordinate_of_speed(RAY_REACH / q) - s0) / step)) + 1
    rho = speed_of_coordinate(s0 + step * np.arange(count))
    tail_count = int(np.ceil(TAIL_EFOLDS / step))
    tail = speed_of_coordinate(s0 - step * np.arange(1, tail_count + 1))[::-1]
    log_scale = -beta * (np.log(rho) + 1j * RAY_ANGLE) - q * rho * ray  # ln(u^-beta e^(-q u))
    log_measure = 2j * RAY_ANGLE - 2.0 * np.log(r)  # r^-2 u du = r^-2 ray^2 rho drho
    main_columns = log_measure + np.log(step * _jacobian(rho) * rho) + log_scale
    tail_columns = (
        log_measure
        + np.log(step * _jacobian(tail) * tail)
        - beta * np.log(tail / u0)
        + log_scale[0]
    )
    operator = _ray_operator(rho / r, rho, main_columns, tail, tail_columns, log_scale, ray)
    factors = sparse_linalg.splu((operator - sparse.identity(count, format="csc")).tocsc())
    y = np.ones(count, dtype=complex)
    for _ in range(3):
        y = factors.solve(y)
        y /= y[np.argmax(np.abs(y))]
    eigenvalue = complex(np.vdot(y, operator @ y) / np.vdot(y, y))
    # normalised by the momentum balance M_2 = r / (1 + r) (solver.py) with its v contour
    # rotated onto the ray: int du u^2 P(0, u) along the ray, the solver's rule and lower tail
    log_p = np.log(y) + log_scale
    top = np.max(log_p.real)
    moment = np.sum(step * _jacobian(rho) * rho**2 * np.exp(log_p - top)) + (
        step * np.exp(log_p[0] - top) * u0**3 / np.expm1((3.0 - beta) * step)
    )
    log_p = log_p - top - np.log(moment * ray**3) + np.log(r / (1.0 + r))
    log_p0 = log_p[0]
    log_amplitude = log_p0 + beta * (np.log(u0) + 1j * RAY_ANGLE)
    nodes = np.concatenate([tail, rho])
    log_columns = np.concatenate(
        [tail_columns - log_scale[0] + log_p0, main_columns - log_scale + log_p]
    )
    largest = 0.5 * rho[-1]
    s_hi = coordinate_of_speed(largest)
    panels = max(1, int(np.ceil((s_hi - s0) / panel_width)))
    edges = np.linspace(s0, s_hi, panels + 1)
    cheb = np.cos(np.pi * (np.arange(panel_order) + 0.5) / panel_order)
    s = 0.5 * (edges[:-1, None] + edges[1:, None]) + 0.5 * np.diff(edges)[:, None] * cheb[None, :]
    density = _RayDensity(
        r, beta, q, ray, log_amplitude, nodes, log_columns, largest, eigenvalue, edges, None
    )
    values = density.nystrom(speed_of_coordinate(s.ravel()))
    logs = np.log(values).reshape(s.shape)
    logs.imag = np.unwrap(logs.imag, axis=1)
    coefficients = np.array(
        [np.polynomial.chebyshev.chebfit(cheb, row, panel_order - 1) for row in logs]
    )
    density = _RayDensity(
        r, beta, q, ray, log_amplitude, nodes, log_columns, largest, eigenvalue, edges, coefficients
    )
    probes = speed_of_coordinate(0.5 * (edges[:-1] + edges[1:]) + 0.37 * np.diff(edges))
    deviation = np.abs(
        np.exp(
            density.log_density(probes)
            - np.log(density.nystrom(probes))
            + q * probes * ray
            + beta * np.log(probes * ray)
        )
        - 1.0
    )
    error = float(max(np.max(deviation), abs(eigenvalue - 1.0)))
    return _RayDensity(
        r,
        beta,
        q,
        ray,
        log_amplitude,
        nodes,
        log_columns,
        largest,
        eigenvalue,
        edges,
        coefficients,
        error,
    )
