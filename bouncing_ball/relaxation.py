"""How fast the bounce-speed chain forgets: the second eigenvalue of the operator of eq. (inteq).

The chain.  A particle leaving x = 0 with speed u first returns with a speed between v and
v + dv with probability v G_g(v, u) dv (eq. (inteq)'s kernel, eq. (kernel3)), and leaves
again with u' = r v, eq. (restitution).  So the outgoing speeds u_n of successive bounces
form a Markov chain with the transition density

    p(u' | u) = r^-2 u' G_g(u' / r, u),          int du' p(u' | u) = 1   (eq. (normG)).

Its forward operator (K f)(u') = int du p(u' | u) f(u) acts on densities of u; its backward
operator (Q h)(u) = int du' p(u' | u) h(u') = E[h(u_{n+1}) | u_n = u] on functions, the
transpose of K.  Eq. (inteq) is the stationarity of the flux-weighted density f(u) = u P(0, u)
(the outgoing flux of speed u at the floor): with A the operator of the solver,

    (A P)(v) = r^-2 int du u G_g(v / r, u) P(u),     K = D A D^-1,   D = multiplication by u,

so K and A have the same spectrum, and A P = P is K f = f.  The solver's Nystrom matrix
(``solver._scaled_operator``: A_ij = r^-2 G_g(u_i / r, u_j) u_j w_j on nodes uniform in
s = ln u + u^(1/2), with the built-in power law below the lowest node) is one discretisation of
all three: its eigenvalue nearest 1 is the stationary one (1 in the continuum limit), its left
eigenvector x gives the backward eigenfunctions at the nodes, h(u_i) = x_i / (w_i u_i).

The relaxation.  In the stationary chain the autocorrelation of h(u_n) decays, at large lags
k, as the largest modulus of the rest of the spectrum to the power k.  Two parts compete:

- the isolated eigenvalues, with eigenfunctions at the speeds of gravity's scale; the matrix
  gives them, converged in the step and the lowest node like the solution itself;
- the continuum of deep low-speed cascades.  At u -> 0 gravity drops out, the kernel is
  scale-free (G_g(v, u) -> G_0, homogeneous of degree -2), and u^-b is an eigenfunction of A
  there with eigenvalue

      Phi(b) = r^(b - 2) / (2 sin((2 b + 1) pi / 6)),       -1/2 < b < 5/2,

  the function whose roots Phi = 1 are eq. (asym2) (b = beta) and b = 2 (the conservation of
  probability).  A chain started at a depth y = -ln u returns to u ~ 1 only after ~y bounces;
  weighing the depths with the stationary f ~ u^(1 - beta) and the large deviations of the
  random walk of ln u_n, bounded functions decorrelate as lambda_c^k (times a power of k), with
  the continuum edge lambda_c = min Phi(b) over b between beta and 2 (the log-convex Phi is
  below 1 there).  A finite matrix discretises this continuum as a band of real eigenvalues
  below lambda_c that creeps up to it as the lowest node goes down.

The relaxation eigenvalue is the larger of the two: the matrix's second eigenvalue where it
lies above lambda_c (an isolated eigenvalue: r above a crossover near 0.6), else lambda_c.  The
correlation length in bounces is n_c = -1 / ln lambda, and n_c <T> the time of n_c bounces (the
relaxation of the process in time is ``time_relaxation``'s).

Below r_c (beta >= 2, eq. (rc)) Phi < 1 between 2 and beta means ln u_n drifts to -infinity:
the chain has no stationary law (f = u P(0, u) is not integrable, I = infinity), the speeds
collapse to 0 in infinitely many bounces of vanishing total time, and no relaxation of the
chain is defined; the functions here refuse those r.

Examples
--------
The continuum edge at r = 1/2 (beta = 1): min over 1 <= b <= 2 of 2^(2 - b) / (2 sin((2 b + 1)
pi / 6)):

>>> from bouncing_ball.relaxation import continuum_edge
>>> print(round(continuum_edge(0.5), 6))
0.814364
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy import linalg, optimize

from .asymptotics import CRITICAL_RESTITUTION, small_speed_exponent
from .restitution import SOLVER_RESTITUTION_RANGE, check_solver_range
from .solver import (
    DEFAULT_STEP,
    FINER_LOWEST_SPEED,
    FINER_STEP,
    _jacobian,
    _scaled_operator,
)

__all__ = [
    "RELAXATION_COLUMNS",
    "scale_free_eigenvalue",
    "continuum_edge",
    "BounceChainRelaxation",
    "bounce_chain_relaxation",
    "relaxation_accuracy",
    "second_eigenfunction",
]


#: The columns of rule solve's summary on the relaxation of the bounce chain
#: (``Equilibrium.summary``); NaN below r_c, where they are not defined.
RELAXATION_COLUMNS = (
    "relaxation_eigenvalue",
    "relaxation_eigenvalue_accuracy",
    "continuum_edge",
    "correlation_bounces",
    "bounce_chain_time",
)


def _chain_restitution(restitution) -> float:
    """r as a float, refused outside the solver's range and at or below r_c."""
    r = float(check_solver_range(restitution, "restitution"))
    if r <= CRITICAL_RESTITUTION:
        raise ValueError(
            f"restitution {r:.6g} is at or below r_c = {CRITICAL_RESTITUTION:.6f} "
            "(eq. (rc)): there the outgoing speeds of successive bounces collapse to 0 (ln u_n "
            "drifts down, I is infinite and u P(0, u) is not a normalisable law of the chain), "
            "so the bounce chain has no relaxation eigenvalue, correlation length or relaxation "
            "time; they are defined for r_c < r <= "
            f"{SOLVER_RESTITUTION_RANGE[1]}"
        )
    return r


def scale_free_eigenvalue(b, restitution) -> np.ndarray:
    """Phi(b) = r^(b - 2) / (2 sin((2 b + 1) pi / 6)): the eigenvalue of u^-b at u -> 0.

    There the kernel is scale-free and r^-2 int du u G_0(v / r, u) u^-b = Phi(b) v^-b;
    Phi(b) = 1 is eq. (asym2), with roots b = beta(r) and b = 2.

    Parameters
    ----------
    b : array_like
        Exponents, -1/2 < b < 5/2 (where the integral converges).
    restitution : float
        r, 0 < r < 1.

    Returns
    -------
    numpy.ndarray
        Phi(b), the shape of ``b``.

    Raises
    ------
    ValueError
        If a b lies outside (-1/2, 5/2) or r outside (0, 1).

    Examples
    --------
    >>> from bouncing_ball.relaxation import scale_free_eigenvalue
    >>> print(scale_free_eigenvalue([1.0, 2.0], 0.5).round(12))
    [1. 1.]
    """
    b = np.asarray(b, dtype=float)
    r = float(restitution)
    if not 0.0 < r < 1.0:
        raise ValueError(f"restitution must lie in (0, 1), got {restitution}")
    if np.any(~((b > -0.5) & (b < 2.5))):
        raise ValueError("b: the scale-free eigenvalue is defined for -1/2 < b < 5/2")
    return np.exp((b - 2.0) * math.log(r)) / (2.0 * np.sin((2.0 * b + 1.0) * np.pi / 6.0))


def continuum_edge(restitution) -> float:
    """lambda_c = min Phi(b) over b between beta(r) and 2: the top of the chain's continuum.

    The decay per bounce of correlations carried by deep low-speed cascades (the module's
    docstring); ln Phi is convex, so the minimum is found to rounding by a bounded search.

    Parameters
    ----------
    restitution : float or str
        r, r_c < r <= 0.9999 (``restitution.SOLVER_RESTITUTION_RANGE`` above r_c).

    Returns
    -------
    float
        lambda_c in (0, 1): 1 at r -> r_c, 1/2 at r -> 1.

    Raises
    ------
    ValueError
        Naming r, at or below r_c (no stationary chain) or outside the solver's range.

    Examples
    --------
    >>> from bouncing_ball.relaxation import continuum_edge
    >>> print(round(continuum_edge(0.9999), 6))
    0.50005
    """
    r = _chain_restitution(restitution)
    beta = small_speed_exponent(r)
    result = optimize.minimize_scalar(
        lambda b: (b - 2.0) * math.log(r) - math.log(2.0 * math.sin((2.0 * b + 1.0) * math.pi / 6)),
        bounds=(beta, 2.0),
        method="bounded",
        options={"xatol": 1e-10},
    )
    return float(math.exp(result.fun))


@dataclass(frozen=True)
class BounceChainRelaxation:
    """The relaxation of the bounce-speed chain at one r, from the solver's matrix.

    Parameters
    ----------
    restitution : float
        r.
    step : float
        The solver's trapezoidal step in s = ln u + u^(1/2).
    lowest_speed : float
        The matrix's lowest node.
    leading_eigenvalue : float
        The matrix's eigenvalue nearest 1 (1 in the continuum limit; the solver's).
    matrix_eigenvalue : complex
        The matrix's eigenvalue of largest modulus besides the leading one.
    continuum_edge : float
        lambda_c (``continuum_edge``).

    Attributes
    ----------
    isolated : bool
        Whether ``matrix_eigenvalue`` lies above the continuum: then it is the relaxation
        eigenvalue; else the continuum edge is.
    eigenvalue : float
        The relaxation eigenvalue lambda: abs(matrix_eigenvalue) if isolated, else lambda_c.
    oscillating : bool
        Whether the isolated eigenvalue is complex or negative (correlations then alternate
        or rotate in sign while their modulus decays as lambda^k).
    correlation_bounces : float
        n_c = -1 / ln lambda.
    """

    restitution: float
    step: float
    lowest_speed: float
    leading_eigenvalue: float
    matrix_eigenvalue: complex
    continuum_edge: float

    @property
    def isolated(self) -> bool:
        return abs(self.matrix_eigenvalue) > self.continuum_edge

    @property
    def eigenvalue(self) -> float:
        return float(abs(self.matrix_eigenvalue)) if self.isolated else self.continuum_edge

    @property
    def oscillating(self) -> bool:
        value = self.matrix_eigenvalue
        return self.isolated and (abs(value.imag) > 1e-9 * abs(value) or value.real < 0.0)

    @property
    def correlation_bounces(self) -> float:
        return -1.0 / math.log(self.eigenvalue)


def _eigen(restitution, step, lowest_speed, vectors=True):
    """The solver's matrix at (r, step, lowest node), its nodes, eigenvalues and left
    eigenvectors (None without ``vectors``: the eigenvalues alone cost a fraction of it); the
    leading eigenvalue (nearest 1) first, the rest by decreasing modulus."""
    r, beta, speeds, log_scale, scaled = _scaled_operator(restitution, step, lowest_speed, None)
    if vectors:
        values, left = linalg.eig(scaled, left=True, right=False, check_finite=False)
    else:
        values, left = linalg.eigvals(scaled, check_finite=False), None
    leading = int(np.argmin(np.abs(values - 1.0)))
    rest = [i for i in np.argsort(-np.abs(values)) if i != leading]
    order = np.array([leading, *rest])
    return r, beta, speeds, log_scale, values[order], None if left is None else left[:, order]


def _checked_step(step) -> float:
    step = float(step)
    if not 0.0 < step <= 0.5:
        raise ValueError(f"step = {step}: the quadrature step must lie in (0, 0.5]")
    return step


def bounce_chain_relaxation(restitution, step=DEFAULT_STEP, lowest_speed=None):
    """The relaxation eigenvalue of the bounce-speed chain and its correlation length in bounces.

    From the eigenvalues of the solver's Nystrom matrix of eq. (inteq) (the same matrix
    ``solver.solve_outgoing_speed_density`` takes the stationary eigenvector of) and the
    continuum edge of the module's docstring.

    Parameters
    ----------
    restitution : float or str
        r, r_c < r <= 0.9999 (the solver's range above r_c, eq. (rc)).
    step : float, optional
        The trapezoidal step in s = ln u + u^(1/2), 0 < step <= 0.5.
    lowest_speed : float, optional
        The matrix's lowest node (``solver.default_lowest_speed``; at most that).

    Returns
    -------
    BounceChainRelaxation

    Raises
    ------
    ValueError
        Naming the argument: r at or below r_c (the chain collapses) or outside the solver's
        range, a step or node the solver refuses.

    Examples
    --------
    Builds the matrix (compiling the kernel on its first call), so not run as a doctest:

    >>> from bouncing_ball.relaxation import bounce_chain_relaxation
    >>> relaxation = bounce_chain_relaxation(0.9)  # doctest: +SKIP
    >>> print(relaxation.isolated, round(relaxation.eigenvalue, 6))  # doctest: +SKIP
    True 0.901761
    """
    r = _chain_restitution(restitution)
    step = _checked_step(step)
    _, beta, speeds, _, values, _ = _eigen(restitution, step, lowest_speed, vectors=False)
    return BounceChainRelaxation(
        restitution=r,
        step=step,
        lowest_speed=float(speeds[0]),
        leading_eigenvalue=float(values[0].real),
        matrix_eigenvalue=complex(values[1]),
        continuum_edge=continuum_edge(restitution),
    )


def relaxation_accuracy(relaxation) -> float:
    """The error estimate of the relaxation eigenvalue: its change against a finer matrix.

    The finer matrix has step x 0.8 and lowest node x 1e-4 (as ``solver.accuracy_estimate``'s
    finer solve), which moves a discretised continuum up towards lambda_c and an isolated
    eigenvalue by its discretisation error.

    Parameters
    ----------
    relaxation : BounceChainRelaxation

    Returns
    -------
    float
        abs(lambda - lambda_finer).

    Examples
    --------
    Builds two matrices, so not run as a doctest:

    >>> from bouncing_ball.relaxation import bounce_chain_relaxation, relaxation_accuracy
    >>> relaxation_accuracy(bounce_chain_relaxation(0.9)) < 1e-8  # doctest: +SKIP
    True
    """
    finer = bounce_chain_relaxation(
        relaxation.restitution,
        step=FINER_STEP * relaxation.step,
        lowest_speed=FINER_LOWEST_SPEED * relaxation.lowest_speed,
    )
    return float(abs(relaxation.eigenvalue - finer.eigenvalue))


def second_eigenfunction(restitution, step=DEFAULT_STEP):
    """The backward eigenfunction h of the matrix's second eigenvalue, at the solver's nodes.

    E[h(u_{n+1}) | u_n = u] = lambda_2 h(u): from the left eigenvector x of the matrix,
    h(u_i) = x_i / (w_i u_i) (the module's docstring), normalised to max abs(h) = 1 over the
    nodes with u >= 1e-3 and real (the chain's second eigenvalue is real where it is
    isolated).

    Parameters
    ----------
    restitution : float or str
        r, r_c < r <= 0.9999.
    step : float, optional
        The trapezoidal step, 0 < step <= 0.5.

    Returns
    -------
    tuple
        (the nodes u_i, h(u_i), lambda_2) with lambda_2 the matrix's eigenvalue (real part).

    Raises
    ------
    ValueError
        As ``bounce_chain_relaxation``.

    Examples
    --------
    Builds the matrix, so not run as a doctest:

    >>> from bouncing_ball.relaxation import second_eigenfunction
    >>> speeds, h, value = second_eigenfunction(0.9)  # doctest: +SKIP
    >>> print(round(value, 6))  # doctest: +SKIP
    0.901761
    """
    _chain_restitution(restitution)
    step = _checked_step(step)
    _, beta, speeds, log_scale, values, left = _eigen(restitution, step, None)
    x = left[:, 1].real * np.exp(-log_scale)  # left eigenvector of S^-1 A S is S x
    h = x / (step * _jacobian(speeds) * speeds)
    h = h / h[speeds >= 1e-3][np.argmax(np.abs(h[speeds >= 1e-3]))]
    return speeds, h, float(values[1].real)
