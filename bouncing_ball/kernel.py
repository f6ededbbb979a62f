"""The first-return kernel G_g(v, u) of eqs. (kernel1)-(kernel3), in a stable form.

v G_g(v, u) dv is the probability that a particle leaving x = 0 with speed
u > 0 first comes back to x = 0 with speed in [v, v + dv].

Eq. (kernel3) as printed,

    G = (3 / 2 pi) (v u)^(1/2) e^((v+u)/2) int_0^1 dy e^(-z) (z^-3 + z^-2),
    z^2 = v^2 - v u + u^2 + 3 v u y^2,

overflows through e^((v+u)/2), cancels it against e^(-z), and for large
v, u its integrand is a spike of width ~ (v + u)^(-1/2) at y = 0.  It is
rewritten here exactly, in three steps:

1. y -> z: dy = z dz / ((3 v u)^(1/2) (z^2 - z0^2)^(1/2)), z0^2 = v^2 - v u + u^2,
   so the factor (v u)^(1/2) cancels and z runs from z0 to v + u;
2. z = z0 (1 + tau^2) turns (z^2 - z0^2)^(-1/2) dz into
   2 dtau / (2 + tau^2)^(1/2), with tau from 0 to
   tau1 = ((v + u) / z0 - 1)^(1/2) <= 1;
3. the exponent splits exactly as
   (v + u) / 2 - z = -(3/4) (v - u)^2 / ((v + u) / 2 + z0) - z0 tau^2,
   both terms <= 0, so nothing overflows and nothing cancels.

The result,

    G = (sqrt(3) / pi) z0^-2 exp[-(3/4) (v - u)^2 / ((v + u) / 2 + z0)]
        * int_0^tau1 dtau exp(-z0 tau^2) (1 + z0 (1 + tau^2))
                         / ((1 + tau^2)^2 (2 + tau^2)^(1/2)),

has a smooth integrand on a finite interval.  For large z0 the factor
exp(-z0 tau^2) confines it to tau < TAIL / sqrt(z0); the upper limit is cut
there (the part beyond is below exp(-TAIL^2) = 1e-18 of the whole), so a
fixed Gauss-Legendre rule resolves it for every v, u.  tau1^2 is evaluated as
3 v u / ((v + u + z0) z0), which keeps its digits when u << v or v << u, and
z0^2 as (v - u)^2 + v u.

The kernel is numba-compiled: ``return_speed_kernel`` and ``return_speed_kernel_matrix``
compile on their first call (seconds), so their Examples are not run as doctests; the unit
tests (``tests/unit/test_kernel.py``) check the same values.

Examples
--------
For u << v the kernel approaches ``kernel_small_u_limit``:

>>> from bouncing_ball.kernel import kernel_small_u_limit
>>> print(kernel_small_u_limit([1.0, 2.0], 1e-4).round(8))
[0.00579194 0.00093152]
"""

import math

import numpy as np

from .jit import njit, prange

__all__ = [
    "TAU_NODES",
    "TIME_MOMENT_TAU_NODES",
    "TAIL",
    "SMALLEST_OUTGOING_SPEED",
    "return_speed_kernel",
    "return_speed_kernel_matrix",
    "return_speed_density",
    "kernel_small_u_limit",
]

#: Gauss-Legendre order of the tau integral: 2e-13 of a 64-node rule
#: (``tests/unit/test_kernel.py``); the continuation to complex v (bouncing_ball.distribution)
#: uses the same rule.
TAU_NODES = 20
#: The same tau integral weighted by powers of the flight time, eq. (timemoments) (k up to 3:
#: bouncing_ball.flight_time), takes a few more nodes.
TIME_MOMENT_TAU_NODES = 24
#: exp(-TAIL^2) ~ 1e-18: the cut of the tau integral for large z0.
TAIL = 6.4
#: The smallest outgoing speed u of the return-speed density v G_g(v, u): the density peaks
#: near v = u at about 0.24 / u, which stays a double (with room for its logs) down to here.
SMALLEST_OUTGOING_SPEED = 1e-300

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(TAU_NODES)
_NODES = 0.5 * (_NODES + 1.0)  # on [0, 1]
_WEIGHTS = 0.5 * _WEIGHTS


@njit(cache=True)
def _full_geometry(v, u):
    """For v, u > 0: the Gaussian's exponent -(3/4) (v - u)^2 / ((v + u) / 2 + z0), z0 and the
    upper limit tau1 of the stable form above.

    Every quantity is formed from s = max(v, u) and the scaled (v / s)^(1/2), (u / s)^(1/2),
    (v - u) / s, so that nothing over- or underflows for any finite v, u > 0 (z0^2 and v u
    themselves overflow above ~1e154 and underflow below ~1e-154)."""
    scale = max(v, u)
    root = math.sqrt(scale)
    a = math.sqrt(v) / root  # (v / s)^(1/2)
    b = math.sqrt(u) / root
    difference = (v - u) / scale
    z = math.hypot(difference, a * b)  # z0 / s, in [3^(1/2) / 2, 1]
    tau1 = math.sqrt(3.0) * a * b / (math.sqrt(a * a + b * b + z) * math.sqrt(z))
    exponent = -0.75 * scale * difference * difference / (0.5 * (a * a + b * b) + z)
    return exponent, scale * z, tau1


@njit(cache=True)
def _geometry(v, u):
    """For v, u > 0: the exponent and z0 of ``_full_geometry`` and the upper limit of tau,
    min(tau1, TAIL / z0^(1/2)), where the Gaussian exp(-z0 tau^2) has fallen below e^-TAIL^2."""
    exponent, z0, tau1 = _full_geometry(v, u)
    return exponent, z0, min(tau1, TAIL / math.sqrt(z0))


@njit(cache=True)
def _kernel_parts(v, u, nodes, weights):
    """The factors of G_g(v, u) = (3^(1/2) / pi) e^exponent (upper / z0) (total / z0) for
    v, u > 0 (``_geometry``) and the tau integral ``total``."""
    exponent, z0, upper = _geometry(v, u)
    total = 0.0
    for k in range(nodes.size):
        tau = upper * nodes[k]
        t2 = tau * tau
        one_t2 = 1.0 + t2
        total += weights[k] * (
            math.exp(-z0 * t2) * (1.0 + z0 * one_t2) / (one_t2 * one_t2 * math.sqrt(2.0 + t2))
        )
    return exponent, z0, upper, total


@njit(cache=True)
def _kernel(v, u, nodes, weights):
    """G_g(v, u) (0 where v <= 0 or u <= 0; it underflows to 0 where it is below ~1e-308)."""
    if v <= 0.0 or u <= 0.0:
        return 0.0
    exponent, z0, upper, total = _kernel_parts(v, u, nodes, weights)
    return (math.sqrt(3.0) / math.pi) * math.exp(exponent) * (upper / z0) * (total / z0)


@njit(cache=True)
def _log_speed_weighted_kernel(v, u, nodes, weights):
    """ln(v G_g(v, u)) (-inf where v <= 0 or u <= 0): finite wherever v G_g is positive, also
    where G_g itself underflows (v, u above ~1e154)."""
    if v <= 0.0 or u <= 0.0:
        return -np.inf
    exponent, z0, upper, total = _kernel_parts(v, u, nodes, weights)
    if upper <= 0.0:  # (v u)^(1/2) / s underflows: v / u or u / v beyond 1e-616
        return -np.inf
    return (
        math.log(math.sqrt(3.0) / math.pi)
        + exponent
        + math.log(upper)
        + math.log(total)
        + math.log(v / z0)
        - math.log(z0)
    )


@njit(cache=True)
def _speed_weighted_kernel_pairs(v, u, nodes, weights):
    out = np.empty(v.size)
    for i in range(v.size):
        out[i] = math.exp(_log_speed_weighted_kernel(v[i], u[i], nodes, weights))
    return out


@njit(cache=True, parallel=False)
def _kernel_matrix(v, u, nodes, weights):
    out = np.empty((v.size, u.size))
    for i in prange(v.size):
        for j in range(u.size):
            out[i, j] = _kernel(v[i], u[j], nodes, weights)
    return out


@njit(cache=True)
def _kernel_pairs(v, u, nodes, weights):
    out = np.empty(v.size)
    for i in range(v.size):
        out[i] = _kernel(v[i], u[i], nodes, weights)
    return out


def return_speed_kernel(v, u):
    """G_g(v, u) of eq. (kernel3) for arrays v, u (broadcast), in the stable form above.

    v G_g(v, u) dv is the probability that a particle leaving the floor with speed u first
    returns with speed in [v, v + dv]; int_0^inf v G_g(v, u) dv = 1, eq. (normG).

    Parameters
    ----------
    v : array_like
        Return speeds (0 where v <= 0).
    u : array_like
        Outgoing speeds (0 where u <= 0); broadcast against ``v``.

    Returns
    -------
    numpy.ndarray
        G_g(v, u), the broadcast shape.

    Examples
    --------
    Compiles on its first call (so not run as a doctest):

    >>> from bouncing_ball.kernel import return_speed_kernel
    >>> print(return_speed_kernel([1.0, 2.0], [[0.5], [1.0]]).round(8))  # doctest: +SKIP
    [[0.46453837 0.08424588]
     [0.42936793 0.13643782]]
    """
    v, u = np.broadcast_arrays(np.asarray(v, dtype=float), np.asarray(u, dtype=float))
    flat = _kernel_pairs(
        np.ascontiguousarray(v.ravel()), np.ascontiguousarray(u.ravel()), _NODES, _WEIGHTS
    )
    return flat.reshape(v.shape)


def return_speed_density(v, u):
    """v G_g(v, u) of eq. (kernel3), the density of the return speed, for arrays v, u.

    The density of the return speed v of a particle that leaves the floor with speed u
    (v and u broadcast).

    Computed as exp of its logarithm (``_log_speed_weighted_kernel``), so it is finite for
    every finite v, u and 0 only where it underflows (below ~1e-308): G_g itself underflows
    where v, u exceed ~1e154 while v G_g ~ 1 / (v + u) does not.

    Parameters
    ----------
    v : array_like
        Return speeds (0 where v <= 0), finite.
    u : array_like
        Outgoing speeds (0 where u <= 0), finite; broadcast against ``v``.

    Returns
    -------
    numpy.ndarray
        v G_g(v, u), the broadcast shape; int_0^inf v G_g(v, u) dv = 1, eq. (normG).

    Examples
    --------
    Compiles on its first call (so not run as a doctest):

    >>> from bouncing_ball.kernel import return_speed_density
    >>> print(return_speed_density([1.0, 2.0], 1.0).round(8))  # doctest: +SKIP
    [0.42936793 0.27287564]
    """
    v, u = np.broadcast_arrays(np.asarray(v, dtype=float), np.asarray(u, dtype=float))
    flat = _speed_weighted_kernel_pairs(
        np.ascontiguousarray(v.ravel()), np.ascontiguousarray(u.ravel()), _NODES, _WEIGHTS
    )
    return flat.reshape(v.shape)


def return_speed_kernel_matrix(v, u):
    """The matrix G_g(v_i, u_j) of eq. (kernel3) for 1-d arrays v, u.

    The kernel of the integral equation eq. (inteq) on a grid of speeds.

    Parameters
    ----------
    v : array_like
        Return speeds v_i, 1-d.
    u : array_like
        Outgoing speeds u_j, 1-d.

    Returns
    -------
    numpy.ndarray
        G_g(v_i, u_j), shape (v.size, u.size).

    Examples
    --------
    Compiles on its first call (so not run as a doctest):

    >>> from bouncing_ball.kernel import return_speed_kernel_matrix
    >>> print(return_speed_kernel_matrix([1.0, 2.0], [0.5, 1.0]).round(8))  # doctest: +SKIP
    [[0.46453837 0.42936793]
     [0.08424588 0.13643782]]
    """
    return _kernel_matrix(
        np.ascontiguousarray(v, dtype=float), np.ascontiguousarray(u, dtype=float), _NODES, _WEIGHTS
    )


def kernel_small_u_limit(v, u):
    """Leading form of G_g(v, u) for u << v: (3 / 2 pi) u^(1/2) v^(-5/2) (1 + v) e^(-v/2).

    From eq. (kernel3) at u -> 0 (z -> v for every y).  The relative
    correction is O(u max(1, 1 / v)) (the exponent (v + u) / 2 - z moves by O(u)).

    Parameters
    ----------
    v : array_like
        Return speeds, v > 0.
    u : array_like
        Outgoing speeds, 0 < u << v; broadcast against ``v``.

    Returns
    -------
    numpy.ndarray
        The leading form of G_g(v, u), the broadcast shape.

    Examples
    --------
    >>> from bouncing_ball.kernel import kernel_small_u_limit
    >>> print(kernel_small_u_limit([1.0, 2.0], 1e-4).round(8))
    [0.00579194 0.00093152]
    """
    v = np.asarray(v, dtype=float)
    return 1.5 / np.pi * np.sqrt(u) * v**-2.5 * (1.0 + v) * np.exp(-0.5 * v)
