"""Asymptotic theory of P(0, v): the exponents beta(r), m(r), q(r) and r_c.

P(0, v) ~ v^(-beta) for v -> 0, eqs. (asym1), (asym2); P(0, v) ~ v^(-m) e^(-q v)
for v -> infinity, eqs. (asym3)-(asym6).
"""

import numpy as np
import pandas as pd

# eq. (rc): beta(r_c) = 2
CRITICAL_RESTITUTION = float(np.exp(-np.pi / np.sqrt(3.0)))


def _log_restitution_of_beta(beta):
    """ln r as a function of beta, from eq. (asym2) with the root beta = 2 divided out.

    In log form eq. (asym2) reads (beta - 2) ln r = ln[2 sin((2 beta + 1) pi / 6)],
    which holds at beta = 2 for every r (both sides vanish).  Dividing by
    beta - 2 removes that spurious root; at beta = 2 the quotient is the
    derivative, (pi / 3) cot(5 pi / 6) = -pi / sqrt(3) = ln r_c.
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
    """beta(r) of eq. (asym2): the physical root in (0, 5/2), P(0, v) ~ v^-beta at small v."""
    from scipy import optimize  # here: the jobs that need only r_c do not load scipy

    r = _restitution(restitution)
    target = np.log(r)
    # ln r(beta) decreases from 0 at beta = 0 to -infinity at beta = 5/2
    return optimize.brentq(
        lambda beta: _log_restitution_of_beta(beta) - target, 0.0, 2.5 - 1e-15, xtol=1e-15
    )


def large_speed_decay_rate(restitution) -> float:
    """q(r) of eqs. (asym4), (asym6): P(0, v) ~ v^-m e^(-q v) at large v."""
    r = _restitution(restitution)
    if r >= 0.5:
        return 1.5 * (1.0 - r) / (1.0 - r + r * r)
    return 0.5 / r


def large_speed_exponent(restitution) -> float:
    """m(r) of eqs. (asym4)-(asym6)."""
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
    """beta, m, q of eqs. (asym2)-(asym6) for each r: columns r, beta, m, q."""
    r = np.asarray(restitutions, dtype=float)
    return pd.DataFrame(
        {
            "r": r,
            "beta": [small_speed_exponent(x) for x in r],
            "m": [large_speed_exponent(x) for x in r],
            "q": [large_speed_decay_rate(x) for x in r],
        }
    )
