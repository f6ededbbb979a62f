"""Asymptotic theory of P(0, v): the exponents beta(r), m(r), q(r) and r_c.

P(0, v) ~ v^(-beta) for v -> 0, eqs. (asym1), (asym2); P(0, v) ~ v^(-m) e^(-q v)
for v -> infinity, eqs. (asym3)-(asym6).
"""

import numpy as np

__all__ = [
    "CRITICAL_RESTITUTION",
    "small_speed_exponent",
    "large_speed_exponent",
    "large_speed_decay_rate",
    "exponents_table",
]

#: r_c = exp(-pi / sqrt(3)) = 0.163..., eq. (rc): beta(r_c) = 2.  Below r_c the collision rate
#: I is infinite (P(0, v) ~ v^-beta is not integrable against v at v = 0).
CRITICAL_RESTITUTION = float(np.exp(-np.pi / np.sqrt(3.0)))


def _log_restitution_of_beta(beta):
    """ln r as a function of beta, from eq. (asym2) with the root beta = 2 divided out.

    In log form eq. (asym2) reads (beta - 2) ln r = ln[2 sin((2 beta + 1) pi / 6)],
    which holds at beta = 2 for every r (both sides vanish).  Dividing by
    beta - 2 removes that root: a genuine mode, v^-2, a constant density of bounces per unit
    ln v, which carries a net flux of ln(r / r_c) bounces per bounce through every small speed
    (from v = 0 above r_c, into it below), so a steady state holds none of it
    (docs/methods.md#asymptotic-theory).  At beta = 2 the quotient is the derivative,
    (pi / 3) cot(5 pi / 6) = -pi / sqrt(3) = ln r_c.
    """
    if abs(beta - 2.0) < 1e-7:
        return -np.pi / np.sqrt(3.0) + (beta - 2.0) * (-(np.pi**2) / 9.0) * 2.0  # + O((beta-2)^2)
    return np.log(2.0 * np.sin((2.0 * beta + 1.0) * np.pi / 6.0)) / (beta - 2.0)


def _restitution(restitution) -> float:
    """r as a float, refused unless 0 < r < 1 (the exponents are defined there only)."""
    r = float(restitution)
    if not 0.0 < r < 1.0:
        raise ValueError(f"restitution must lie in (0, 1), got {restitution}")
    return r


def small_speed_exponent(restitution) -> float:
    """The exponent beta(r) of P(0, v) ~ v^-beta at small v, eqs. (asym1), (asym2).

    The physical root of eq. (asym2) in (0, 5/2) (the equation holds at beta = 2 for every r;
    that root, the v^-2 mode with a net flux of bounces through v = 0, is divided out).

    Parameters
    ----------
    restitution : float
        The restitution coefficient r, 0 < r < 1.

    Returns
    -------
    float
        beta(r): 1 at r = 1/2, 2 at r = r_c (eq. (rc)), growing as r falls.

    Raises
    ------
    ValueError
        If r is not in (0, 1).

    Examples
    --------
    >>> from bouncing_ball.asymptotics import small_speed_exponent, CRITICAL_RESTITUTION
    >>> print(round(small_speed_exponent(0.5), 12), round(small_speed_exponent(1 / 3), 12))
    1.0 1.5
    >>> print(round(small_speed_exponent(CRITICAL_RESTITUTION), 9))
    2.0
    """
    from scipy import optimize  # here: the jobs that need only r_c do not load scipy

    r = _restitution(restitution)
    target = np.log(r)
    # ln r(beta) decreases from 0 at beta = 0 to -infinity at beta = 5/2
    return optimize.brentq(
        lambda beta: _log_restitution_of_beta(beta) - target, 0.0, 2.5 - 1e-15, xtol=1e-15
    )


def large_speed_decay_rate(restitution) -> float:
    """The decay rate q(r) of P(0, v) ~ v^-m e^(-q v) at large v, eqs. (asym4), (asym6).

    Parameters
    ----------
    restitution : float
        The restitution coefficient r, 0 < r < 1.

    Returns
    -------
    float
        q(r) = 3 (1 - r) / (2 (1 - r + r^2)) for r >= 1/2 (eq. (asym4)), 1 / (2 r) below
        (eq. (asym6)); q and dq/dr are continuous at r = 1/2.

    Raises
    ------
    ValueError
        If r is not in (0, 1).

    Examples
    --------
    >>> from bouncing_ball.asymptotics import large_speed_decay_rate
    >>> print(large_speed_decay_rate(0.5), large_speed_decay_rate(0.25))
    1.0 2.0
    """
    r = _restitution(restitution)
    if r >= 0.5:
        return 1.5 * (1.0 - r) / (1.0 - r + r * r)
    return 0.5 / r


def large_speed_exponent(restitution) -> float:
    """The power m(r) of P(0, v) ~ v^-m e^(-q v) at large v, eqs. (asym4)-(asym6).

    Parameters
    ----------
    restitution : float
        The restitution coefficient r, 0 < r < 1.

    Returns
    -------
    float
        m(r) = 1 - ln r / ln(x / r) with x of eq. (asym5) for r > 1/2 (eq. (asym4)), 1 at
        r = 1/2 (x(1/2) = 0 in eq. (asym5): the limit r -> 1/2 from above), 3/2 below
        (eq. (asym6)): m jumps at r = 1/2.  Above 1/2, m -> 1 only logarithmically,
        m(1/2 + delta) = 1 - ln 2 / ln(3 / (16 delta)) to relative order delta.  Near 1/2 the
        form v^-m e^(-q v) holds only beyond a crossover speed ~ (r - 1/2)^-2:
        1 / (1/(2r) - q) above 1/2 (the end-point term v^(-3/2) e^(-v/(2r)) competes; 83 at
        r = 0.55, 7.6e3 at 0.505) and (1/(2r) - 1)^-2 below (81 at r = 0.45); below it
        P(0, v) looks like the r = 1/2 form (docs/methods.md#asymptotic-theory).

    Raises
    ------
    ValueError
        If r is not in (0, 1).

    Examples
    --------
    >>> from bouncing_ball.asymptotics import large_speed_exponent
    >>> print(large_speed_exponent(0.25), large_speed_exponent(0.5))
    1.5 1.0
    """
    r = _restitution(restitution)
    if r < 0.5:
        return 1.5
    if r == 0.5:
        return 1.0  # x(1/2) = 0 in eq. (asym5): the limit r -> 1/2 from above
    q = large_speed_decay_rate(r)
    half_minus_q = 0.5 - q
    x = 0.5 + 0.5 * np.sqrt(3.0) * half_minus_q / np.sqrt(1.0 - half_minus_q**2)  # eq. (asym5)
    return 1.0 - np.log(r) / np.log(x / r)


def exponents_table(restitutions):
    """The exponents beta, m, q of eqs. (asym2)-(asym6) for each r, as a table (Figs. 1, 2).

    Parameters
    ----------
    restitutions : array_like of float
        Restitution coefficients, each in (0, 1).

    Returns
    -------
    pandas.DataFrame
        Columns r, beta (``small_speed_exponent``), m (``large_speed_exponent``) and q
        (``large_speed_decay_rate``), one row per r in the order given.

    Examples
    --------
    >>> from bouncing_ball.asymptotics import exponents_table
    >>> print(exponents_table([0.25, 0.5]).round(6).to_string(index=False))
       r  beta   m   q
    0.25  1.75 1.5 2.0
    0.50  1.00 1.0 1.0
    """
    r = np.asarray(restitutions, dtype=float)
    import pandas as pd  # here: the jobs that need only the exponents do not load pandas

    return pd.DataFrame(
        {
            "r": r,
            "beta": [small_speed_exponent(x) for x in r],
            "m": [large_speed_exponent(x) for x in r],
            "q": [large_speed_decay_rate(x) for x in r],
        }
    )
