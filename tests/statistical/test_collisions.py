"""The collision step on its own: the return-speed law at small speed.

A particle leaving x = 0 with a speed u << 1 hardly feels gravity before it
returns, so its return speed follows McKean's law for the gravity-free
randomly accelerated particle, the small-speed limit of v G_g(v, u) of
eq. (kernel1): the ratio w = v/u has density (3 / 2 pi) w^(3/2) / (1 + w^3).
This checks eq. (criterion), the minimum step and the placement of the
collision on the step's mean path together.  300,000 launches at u = 1e-5, c = 5, a fixed seed;
the launches that have not returned by 1e4 u^2 (about one in ten, the law's w^(-3/2) tail)
count as w = infinity.
"""

import functools

import numpy as np
import pytest
from numba import njit
from scipy import integrate, stats

from bouncing_ball.free_flight import (
    cubic_slope,
    first_crossing_time,
    free_flight_step,
    hermite_cubic,
    largest_safe_step,
)


@njit
def _return_speed_ratios(u, c, divisor, n, seed):
    np.random.seed(seed)
    ratios = np.full(n, np.nan)
    delta = 0.5 * (u / divisor) ** 2
    for i in range(n):
        x, v, t = 0.0, u, 0.0
        while t < 1e4 * u * u:  # returns take a time of order u^2
            dt = largest_safe_step(x, v, c) + delta
            x1, v1 = free_flight_step(
                x, v, dt, np.random.standard_normal(), np.random.standard_normal()
            )
            if x1 < 0.0:
                a0, a1, a2, a3 = hermite_cubic(x, v, x1, v1, dt)
                tau = first_crossing_time(a0, a1, a2, a3, dt, x1)
                ratios[i] = abs(cubic_slope(a1, a2, a3, tau)) / u
                break
            x, v, t = x1, v1, t + dt
    return ratios


LAUNCHES = 300_000


@functools.cache
def _ratios():
    """w = v/u of every launch, NaN where it has not returned."""
    return _return_speed_ratios(1e-5, 5.0, 500.0, LAUNCHES, 7)


def _mckean_probability(lo, hi):
    value, _ = integrate.quad(lambda w: 1.5 / np.pi * w**1.5 / (1.0 + w**3), lo, hi)
    return value


def test_return_speed_follows_mckean_law():
    """chi^2 of 10 bins of w at the 1e-3 level: a shape check.  Smallest error rejected: w
    scaled by 1.02 (non-centrality 71 on 9 degrees of freedom: rejected with probability
    0.9999; scaled by 1.01, with probability 0.4 only, for which see the score test)."""
    ratios = _ratios()
    edges = np.array([0.0, 0.03, 0.1, 0.3, 0.6, 1.0, 1.5, 2.5, 5.0, 10.0, np.inf])
    observed = np.histogram(ratios[np.isfinite(ratios)], edges)[0]
    expected = LAUNCHES * np.array(
        [_mckean_probability(a, b) for a, b in zip(edges[:-1], edges[1:])]
    )
    # the few launches that have not returned by 1e4 u^2 belong to the open bin
    observed[-1] += int(np.sum(~np.isfinite(ratios)))
    chi2 = float(np.sum((observed - expected) ** 2 / expected))
    p_value = stats.chi2.sf(chi2, len(expected) - 1)
    assert p_value > 1e-3, (
        f"chi^2 = {chi2:.1f} for {len(expected) - 1} dof; {observed} vs {expected.round()}"
    )


def test_return_speed_scale_agrees_with_mckean_law():
    """The score of the scale of w under McKean's law, d/ds ln(f(w/s)/s) at s = 1, which is
    5/2 - 3 w^3 / (1 + w^3) for f(w) ~ w^(3/2) / (1 + w^3): its mean over the launches is 0
    within 3 standard errors (its variance is the Fisher information 5/8; a launch that has
    not returned, w -> infinity, scores -1/2).  Smallest error rejected: w scaled by 1.01, a
    shift of the mean score by 0.0062, z = 4.3."""
    w = _ratios()
    score = np.full(len(w), -0.5)
    returned = np.isfinite(w)
    score[returned] = 2.5 - 3.0 * w[returned] ** 3 / (1.0 + w[returned] ** 3)
    error = score.std(ddof=1) / np.sqrt(len(score))
    assert error == pytest.approx(np.sqrt(0.625 / LAUNCHES), rel=0.05)  # the Fisher information
    z = score.mean() / error
    assert abs(z) < 3.0, f"mean score {score.mean():.5f} +- {error:.5f}, z = {z:.2f}"
