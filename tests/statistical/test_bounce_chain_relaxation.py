"""The relaxation eigenvalue of the bounce-speed chain against the chain itself.

The chain u -> r v is run with v drawn from the exact return-speed law (``bounce_chain``,
which does not use the solver).  For the backward eigenfunction h of the second eigenvalue
lambda (E[h(u_{n+1}) | u_n] = lambda h(u_n)), the stationary chain has, at every lag k,

    E[h(u_n) h(u_{n+k})] = lambda^k E[h(u_n)^2]

exactly.  The statistic D_k = h(u_n) h(u_{n+k}) - lambda^k h(u_n)^2, averaged over each chain,
has mean 0; its z-score over the independent chains is held to |z| < Z_LIMIT at each lag and
r (4.5: a family false-alarm probability below 1e-4 for the 20 z-scores).  Seeds are fixed, so
the outcome is deterministic.  The test asserts its power before it compares: the standard
error of the lag-1 correlation is below ``LAG_ONE_ERROR``, so an eigenvalue off by
Z_LIMIT x LAG_ONE_ERROR is rejected.
"""

import numpy as np
import pytest
from bounce_chain import simulate_chains
from scipy.interpolate import CubicSpline

from bouncing_ball.relaxation import bounce_chain_relaxation, second_eigenfunction
from bouncing_ball.solver import coordinate_of_speed

CHAINS, STEPS = 2500, 300
LAGS = range(1, 11)
Z_LIMIT = 4.5
LAG_ONE_ERROR = 1e-3
SEED = 35


@pytest.fixture(scope="module", params=[0.75, 0.9])
def chain(request):
    r = request.param
    relaxation = bounce_chain_relaxation(r)
    burn_in = int(30 * relaxation.correlation_bounces)
    speeds = simulate_chains(r, CHAINS, STEPS, burn_in, seed=[SEED, int(1000 * r)])
    nodes, h, value = second_eigenfunction(r)
    eigenfunction = CubicSpline(coordinate_of_speed(nodes), h)(coordinate_of_speed(speeds))
    return relaxation, value, eigenfunction


def _z_scores(eigenfunction, value):
    scores, errors = [], []
    squares = eigenfunction**2
    for k in LAGS:
        per_chain = (
            eigenfunction[:, :-k] * eigenfunction[:, k:] - value**k * squares[:, :-k]
        ).mean(axis=1)
        error = per_chain.std(ddof=1) / np.sqrt(per_chain.size)
        scores.append(per_chain.mean() / error)
        errors.append(error / squares[:, :-k].mean())  # of the correlation at lag k
    return np.array(scores), np.array(errors)


def test_the_autocorrelation_decays_as_the_relaxation_eigenvalue(chain):
    relaxation, value, eigenfunction = chain
    # the eigenvalue with its eigenfunction (LAPACK's eig) and alone (eigvals): the same to
    # LAPACK's rounding, a few ulps of the matrix's norm
    assert relaxation.isolated and value == pytest.approx(relaxation.eigenvalue, rel=1e-12)
    scores, errors = _z_scores(eigenfunction, value)
    assert errors[0] <= LAG_ONE_ERROR
    assert np.all(np.abs(scores) < Z_LIMIT), dict(zip(LAGS, scores.round(2)))
