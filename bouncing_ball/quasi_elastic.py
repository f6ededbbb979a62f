"""The quasi-elastic limit r -> 1: P(0, v), <x>, Delta x, I and the bounce chain's relaxation.

With epsilon = 1 - r (the derivation is in docs/quasi_elastic.md):

1. The return law of one flight.  A ball leaving the floor with speed u comes back with speed
   V; by eq. (kernel2) and the Kontorovich-Lebedev identity behind eq. (laplaceT) of
   ``bouncing_ball.flight_time``, ::

       E[e^(-s V) | u] = g'(c) exp[-u (g(c) - 1/2)] + O(e^(-u/2)),
       g(c) = c / 2 + (3^(1/2) / 2) (1 - c^2)^(1/2),   c = s - 1/2,                 (returnlaw)

   so every moment E[V^k | u] is a polynomial of degree k in u, up to terms O(e^(-u/2)):
   E[V | u] = u + 4/3, E[V^2 | u] = u^2 + 4u + 8/3 (Ito on v + t and v^2/2 + x), and in
   general E[V^k | u] = u^k + (2/3) k (k + 1) u^(k-1) + (2/9) k^2 (k^2 - 1) u^(k-2) + ...
   (``RETURN_SPEED_MOMENTS``).

2. The chain of outgoing speeds, u' = r V, has the stationary law u P(0, u) / I (flux
   weighted, eq. (collrate)).  Its moments m_k = M_(k+1) / M_1 then obey the closed recursion
   (1 - r^k) m_k = r^k sum_(j<k) c_kj m_j (c_kj the coefficients of u^j in E[V^k | u]), exact up
   to the flights that start at u = O(1), whose weight is O(epsilon^2).  As r -> 1,
   m_k epsilon^k -> (2/3)^k (k + 1)! (1 - k epsilon + O(epsilon^2)): the scaled speed
   w = epsilon u has the Gamma law of shape 2 and scale 2/3, w e^(-3w/2) (9/4), the stationary
   law of the diffusion dw = (4/3 - w) dtau + (4 w / 3)^(1/2) dB in tau = epsilon n (n the
   bounce count).

3. The time averages follow from the moments by the Ito identities of ``bouncing_ball.solver``
   (``time_averages``): I = M_1 = M_2 / m_1 with M_2 = r / (1 + r), <x> = (1 + r^3) I m_3 /
   (3 r^3), <x^2> = (2/3) [(1 + r^5) I m_5 / (5 r^5) - 8 <x>].

4. The bounce chain: the polynomials of degree k in u are invariant under the chain's
   operator, with eigenvalues r^k, so its second eigenvalue is r (up to O(epsilon^3)).

Everything here is an asymptotic form for r -> 1: each function is defined for 0 < r < 1 and
refuses r outside, but its accuracy, stated in its docstring as the order of the first term
left out, is useful only near r = 1 (docs/quasi_elastic.md tabulates it at 0.99, 0.999, 0.9999).
"""

from dataclasses import dataclass

import numpy as np

from .restitution import restitution_value

__all__ = [
    "RETURN_SPEED_MOMENTS",
    "QuasiElasticScaling",
    "SCALINGS",
    "TABLE_RESTITUTIONS",
    "TABLE_SCALED_SPEEDS",
    "quasi_elastic_epsilon",
    "outgoing_speed_law",
    "scaled_speed_density",
    "speed_density_first_correction",
    "quasi_elastic_form",
    "correlation_bounces",
    "relaxation_time",
    "quasi_elastic_table",
    "scaled_speed_curves",
]

#: E[V^k | u] = sum_j RETURN_SPEED_MOMENTS[k][j] u^j up to O(e^(-u/2)): the moments of the return
#: speed V of a flight that leaves the floor with speed u, from eq. (returnlaw) of the module's
#: docstring (the coefficient of u^j is listed at index j).
RETURN_SPEED_MOMENTS = (
    (1.0,),
    (4 / 3, 1.0),
    (8 / 3, 4.0, 1.0),
    (128 / 9, 16.0, 8.0, 1.0),
    (2560 / 27, 320 / 3, 160 / 3, 40 / 3, 1.0),
    (2560 / 3, 8320 / 9, 4160 / 9, 400 / 3, 20.0, 1.0),
)


@dataclass(frozen=True)
class QuasiElasticScaling:
    """A quantity ~ limit epsilon^exponent (1 + first epsilon + second epsilon^2 + ...), r -> 1.

    Parameters
    ----------
    exponent : int
        The power of epsilon = 1 - r.
    limit : float
        The limit of quantity / epsilon^exponent.
    first : float
        The first correction's coefficient.
    second : float
        The next coefficient, the size of what the first-order form leaves out (it sets the
        tolerances of the tests against the solver).
    """

    exponent: int
    limit: float
    first: float
    second: float


#: The expansions of docs/quasi_elastic.md: the collision rate I (eq. (collrate)), <x> and
#: Delta x (eq. (xandDeltax)), the correlation length of the bounce chain in bounces and that
#: length times the mean time between collisions 1/I, and the slowest relaxation time of the
#: process in time, 1 / gamma (``time_relaxation``).  I's second coefficient is 1/4 from the
#: moment recursion plus 1 from the flights that start at u = O(1); those of the bounce chain
#: follow from its second eigenvalue r + 2 epsilon^3 + ...; that of 1 / gamma is the solver's
#: (0.709 over 0.9 <= r <= 0.99), not derived.
SCALINGS = {
    "collision_rate": QuasiElasticScaling(1, 3 / 8, 1 / 2, 5 / 4),
    "mean_x": QuasiElasticScaling(-2, 16 / 9, -1.0, 4 / 3),
    "delta_x": QuasiElasticScaling(-2, 16 * np.sqrt(2.0) / 9, -1.0, 229 / 120),
    "correlation_bounces": QuasiElasticScaling(-1, 1.0, -1 / 2, 23 / 12),
    "bounce_chain_time": QuasiElasticScaling(-2, 8 / 3, -1.0, 7 / 6),
    "relaxation_time": QuasiElasticScaling(-2, 64 / 9, -1.0, 0.71),
}

#: The r of the quasi-elastic table (``quasi_elastic_table``).
TABLE_RESTITUTIONS = (0.99, 0.999, 0.9999)
#: The scaled speeds w = (1 - r) v at which the table compares (1 - r)^-3 P(0, v) with its limit.
TABLE_SCALED_SPEEDS = (0.5, 1.0, 4.0)


def quasi_elastic_epsilon(restitution) -> float:
    """epsilon = 1 - r, the distance from the elastic limit.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        The restitution coefficient r, 0 < r < 1, read as ``restitution.parse_restitution`` reads it.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If r is not a number in (0, 1) (naming ``restitution``).

    Examples
    --------
    >>> from bouncing_ball.quasi_elastic import quasi_elastic_epsilon
    >>> quasi_elastic_epsilon(0.75)
    0.25
    """
    return 1.0 - _restitution(restitution)


def _restitution(restitution) -> float:
    """r as a float, parsed as every entry point of the library parses it
    (``restitution.parse_restitution``: "1/3", np.float32(0.99) as 0.99), 0 < r < 1."""
    return restitution_value(restitution, "restitution")


def _scaled_speeds(w) -> np.ndarray:
    w = np.asarray(w, dtype=float)
    if not np.all(np.isfinite(w)) or np.any(w < 0.0):
        raise ValueError("scaled speed w must be finite and >= 0")
    return w


def outgoing_speed_law(w):
    """The limiting law of w = (1 - r) u, u the outgoing speed of a bounce: (9/4) w e^(-3w/2).

    The stationary law of the bounce chain is flux weighted, u P(0, u) / I (eq. (collrate));
    as r -> 1 the law of w tends to the Gamma law of shape 2 and scale 2/3 (normalised:
    int dw = 1, mean 4/3).  Its first correction is a rescaling: the moments of
    (1 - r) u / r equal those of this law up to O(epsilon^2).

    Parameters
    ----------
    w : array_like
        Scaled speeds, finite and >= 0.

    Returns
    -------
    numpy.ndarray
        The density in w.

    Raises
    ------
    ValueError
        If a w is negative or not finite.

    Examples
    --------
    >>> from scipy.integrate import quad
    >>> from bouncing_ball.quasi_elastic import outgoing_speed_law
    >>> print(round(quad(outgoing_speed_law, 0, float("inf"))[0], 12))
    1.0
    """
    w = _scaled_speeds(w)
    return 2.25 * w * np.exp(-1.5 * w)


def scaled_speed_density(w):
    """The limit of (1 - r)^-3 P(0, w / (1 - r)) as r -> 1: (27/32) e^(-3w/2).

    P(0, v) under the paper's normalisation, eq. (normalization): I (1 - r)^-1 times the law
    of ``outgoing_speed_law`` divided by w, with I ~ (3/8) (1 - r).  It satisfies the momentum
    balance M_2 = int v^2 P(0, v) dv = r / (1 + r) -> 1/2 and the energy balance
    M_3 = 2 r^2 / (1 - r^2) ~ 1 / epsilon of ``bouncing_ball.solver``.  With the first
    correction, (1 - r)^-3 P(0, w / (1 - r)) = (27/32) e^(-3w/2)
    [1 + epsilon (5/2 - 3w/2) + O(epsilon^2)] (``speed_density_first_correction``), uniformly
    for w in compact subsets of (0, inf); the O(epsilon^2) term grows like 1/w as w -> 0, where
    P(0, v) crosses over to the v^-beta of eq. (asym1) at v ~ 1, and like w^2 as w -> inf.

    Parameters
    ----------
    w : array_like
        Scaled speeds, finite and >= 0.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError
        If a w is negative or not finite.

    Examples
    --------
    The momentum balance M_2 -> 1/2:

    >>> from scipy.integrate import quad
    >>> from bouncing_ball.quasi_elastic import scaled_speed_density
    >>> print(round(quad(lambda w: w**2 * scaled_speed_density(w), 0, float("inf"))[0], 12))
    0.5
    """
    w = _scaled_speeds(w)
    return (27.0 / 32.0) * np.exp(-1.5 * w)


def speed_density_first_correction(w):
    """p1(w) = 5/2 - 3w/2: (1 - r)^-3 P(0, w / (1 - r)) = limit (1 + epsilon p1(w) + O(epsilon^2)).

    The limit is ``scaled_speed_density``.  -3w/2 is the first correction of the decay rate
    q(r) = (3/2) epsilon (1 + epsilon + O(epsilon^2)) of eq. (asym4); 5/2 = 1/2 from I and 2
    from the outgoing law's rescaling by 1/r.

    Parameters
    ----------
    w : array_like
        Scaled speeds, finite and >= 0.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError
        If a w is negative or not finite.

    Examples
    --------
    >>> from bouncing_ball.quasi_elastic import speed_density_first_correction
    >>> print(speed_density_first_correction([0.0, 1.0]))
    [2.5 1. ]
    """
    w = _scaled_speeds(w)
    return 2.5 - 1.5 * w


def quasi_elastic_form(name: str, restitution, order: int = 1) -> float:
    """The quasi-elastic form of a quantity of ``SCALINGS`` at r, to order 0 or 1 in epsilon.

    limit epsilon^exponent (order 0) or limit epsilon^exponent (1 + first epsilon) (order 1),
    epsilon = 1 - r.  The relative error is O(epsilon) at order 0 and O(epsilon^2) at order 1,
    about ``SCALINGS[name].second`` epsilon^2: an asymptotic form, useful near r = 1 only.

    Parameters
    ----------
    name : str
        One of ``SCALINGS``: ``"collision_rate"`` (I, eq. (collrate)), ``"mean_x"`` and
        ``"delta_x"`` (<x>, Delta x, eq. (xandDeltax)), ``"correlation_bounces"``
        (``correlation_bounces``), ``"bounce_chain_time"`` (that length times 1/I).
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1: a decimal, a numpy float or a fraction string such as "1/3".
    order : int
        0 or 1.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If name is not in SCALINGS, r is not in (0, 1) or order is not 0 or 1.

    Examples
    --------
    >>> from bouncing_ball.quasi_elastic import quasi_elastic_form
    >>> print(round(quasi_elastic_form("collision_rate", 0.99), 10))
    0.00376875
    >>> print(round(quasi_elastic_form("mean_x", 0.99, order=0), 6))
    17777.777778
    """
    if name not in SCALINGS:
        raise ValueError(f"name must be one of {sorted(SCALINGS)}, got {name!r}")
    if order not in (0, 1):
        raise ValueError(f"order must be 0 or 1, got {order!r}")
    epsilon = quasi_elastic_epsilon(restitution)
    scaling = SCALINGS[name]
    value = scaling.limit * epsilon**scaling.exponent
    return float(value * (1.0 + scaling.first * epsilon) if order == 1 else value)


def correlation_bounces(restitution) -> float:
    """The correlation length of the bounce chain in bounces, -1 / ln r, as r -> 1.

    The chain of outgoing speeds u_n maps polynomials of degree k in u to polynomials of degree
    k (eq. (returnlaw) of the module's docstring), with eigenvalue r^k: its second eigenvalue is
    r up to O(epsilon^3) (the flights that start at u = O(1) add 2 epsilon^3), so correlations
    decay as r^n and the length is -1 / ln r = 1/epsilon - 1/2 + O(epsilon), to a relative
    O(epsilon^2) (the chain's own length is 1/epsilon - 1/2 + (23/12) epsilon + ...,
    ``SCALINGS["correlation_bounces"]``).

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1, as for ``quasi_elastic_form``.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If r is not in (0, 1).

    Examples
    --------
    >>> from bouncing_ball.quasi_elastic import correlation_bounces
    >>> print(round(correlation_bounces(0.99), 6))
    99.499162
    """
    return float(-1.0 / np.log(_restitution(restitution)))


def relaxation_time(restitution) -> float:
    """The relaxation time in the paper's time units, 64 / (9 epsilon^2), to leading order.

    In continuous time the scaled speed w = epsilon u of the current flight follows the bounce
    chain's diffusion slowed by the flight time 2u: in s = epsilon^2 t / 2 its generator is
    (2/3) d^2/dw^2 + (4 / (3w) - 1) d/dw, which the ground-state transform turns into a
    hydrogen-like problem with levels (3/8) (1 - 1/n^2), n = 1, 2, ...  The slowest decay is
    n = 2: the rate 9 epsilon^2 / 64 in t.  It is not the bounce count times the mean flight
    time (``SCALINGS["bounce_chain_time"]``, 8 / (3 epsilon^2)): long flights carry the slow
    mode.  Relative error O(epsilon): the first correction, -epsilon, is the tilted bounce
    operator's (``time_relaxation``; ``SCALINGS["relaxation_time"]``, docs/quasi_elastic.md).

    Parameters
    ----------
    restitution : float
        r, 0 < r < 1.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If r is not in (0, 1).

    Examples
    --------
    >>> from bouncing_ball.quasi_elastic import relaxation_time
    >>> print(round(relaxation_time(0.99), 3))
    71111.111
    """
    epsilon = quasi_elastic_epsilon(restitution)
    return 64.0 / (9.0 * epsilon**2)


def _solver_rows(restitution) -> list:
    """(quantity, scaled solver value, limit, predicted c1, c2) of the solver at r."""
    from .equilibrium import Equilibrium

    epsilon = quasi_elastic_epsilon(restitution)
    equilibrium = Equilibrium(restitution)
    rows = []
    for name in ("collision_rate", "mean_x", "delta_x"):
        scaling = SCALINGS[name]
        scaled = getattr(equilibrium, name) / epsilon**scaling.exponent
        rows.append((name, scaled, scaling.limit, scaling.first, scaling.second))
    w = np.asarray(TABLE_SCALED_SPEEDS)
    scaled = np.asarray(equilibrium.p0v(w / epsilon)) / epsilon**3
    limits, firsts = scaled_speed_density(w), speed_density_first_correction(w)
    for point, value, limit, first in zip(w, scaled, limits, firsts, strict=True):
        rows.append((f"P(0, v) at w = {point:g}", value, limit, first, np.nan))
    return rows


def quasi_elastic_table(restitutions=TABLE_RESTITUTIONS):
    """The solver's scaled quantities against their quasi-elastic limits.

    For each r: I / epsilon, <x> epsilon^2, Delta x epsilon^2 (``Equilibrium(r)``, eqs.
    (collrate), (xandDeltax)) and epsilon^-3 P(0, w / epsilon) at ``TABLE_SCALED_SPEEDS``,
    each with its limit, the measured first coefficient c1 = (scaled / limit - 1) / epsilon and
    the predicted c1 and c2 (c2 not derived for P(0, v): NaN).  Measured c1 should differ from
    the predicted by c2 epsilon + O(epsilon^2).

    Parameters
    ----------
    restitutions : sequence of float, str or fractions.Fraction
        Each r as ``Equilibrium`` takes it, in the solver's range; the comparison means something near 1.

    Returns
    -------
    pandas.DataFrame
        Columns r, quantity, scaled, limit, c1_measured, c1_predicted, c2_predicted.

    Raises
    ------
    ValueError
        If an r is outside (0, 1) or outside the solver's range.

    Examples
    --------
    Solves eq. (inteq) at each r (so not run as a doctest); ``python -m
    bouncing_ball.quasi_elastic`` prints this table:

    >>> from bouncing_ball.quasi_elastic import quasi_elastic_table
    >>> quasi_elastic_table([0.99])  # doctest: +SKIP
    """
    import pandas as pd

    records = []
    for r in restitutions:
        epsilon = quasi_elastic_epsilon(r)
        for name, scaled, limit, first, second in _solver_rows(r):
            records.append(
                {
                    "r": _restitution(r),
                    "quantity": name,
                    "scaled": float(scaled),
                    "limit": float(limit),
                    "c1_measured": float((scaled / limit - 1.0) / epsilon),
                    "c1_predicted": float(first),
                    "c2_predicted": float(second),
                }
            )
    return pd.DataFrame.from_records(records)


def scaled_speed_curves(restitutions, scaled_speeds, quadrature_step=None):
    """The solver's P(0, v) in the quasi-elastic scaling, beside its limit and first correction.

    For each r, epsilon^-3 P(0, w / epsilon) (``Equilibrium(r).p0v``, eq. (inteq)) at the
    scaled speeds w = epsilon v, the limit (27/32) e^(-3w/2) (``scaled_speed_density``), and
    the measured first coefficient (scaled / limit - 1) / epsilon beside the predicted
    p1(w) = 5/2 - 3w/2 (``speed_density_first_correction``): the curves collapse onto the limit
    as r -> 1, and their departure from it onto p1.

    Parameters
    ----------
    restitutions : sequence of float or str
        Each r in the solver's range (``restitution.SOLVER_RESTITUTION_RANGE``).
    scaled_speeds : array_like
        w = (1 - r) v, positive and finite.
    quadrature_step : float, optional
        The solver's step (``Equilibrium``'s default if None).

    Returns
    -------
    pandas.DataFrame
        Columns r, epsilon, w, scaled_p0v, limit, c1_measured, c1_predicted.

    Raises
    ------
    ValueError
        If an r is outside the solver's range, or a w is not positive and finite.

    Examples
    --------
    >>> from bouncing_ball.quasi_elastic import scaled_speed_curves
    >>> curves = scaled_speed_curves([0.999], [1.0])  # doctest: +SKIP
    """
    import pandas as pd

    from .equilibrium import Equilibrium

    w = np.asarray(scaled_speeds, dtype=float)
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w) & (w > 0.0)):
        raise ValueError(f"scaled_speeds: positive and finite w = (1 - r) v, got {scaled_speeds!r}")
    options = {} if quadrature_step is None else {"quadrature_step": quadrature_step}
    frames = []
    for r in restitutions:
        equilibrium = Equilibrium(r, **options)
        epsilon = quasi_elastic_epsilon(equilibrium.r)
        scaled = np.asarray(equilibrium.p0v(w / epsilon)) / epsilon**3
        limit = scaled_speed_density(w)
        frames.append(
            pd.DataFrame(
                {
                    "r": equilibrium.r,
                    "epsilon": epsilon,
                    "w": w,
                    "scaled_p0v": scaled,
                    "limit": limit,
                    "c1_measured": (scaled / limit - 1.0) / epsilon,
                    "c1_predicted": speed_density_first_correction(w),
                }
            )
        )
    return pd.concat(frames, ignore_index=True)


if __name__ == "__main__":
    print(quasi_elastic_table().to_markdown(index=False, floatfmt=".6g"))
