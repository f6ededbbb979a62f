"""Synthetic shards with known truth for the fitter's tests (tests/unit/test_fits.py,
tests/statistical/test_fit_coverage.py)."""

import numpy as np

from bouncing_ball import fits

SHARDS = 16
CASES = {
    # side: (r whose theory is the truth, true log-prefactor and exponents, bin edges, time per shard)
    fits.SMALL_SPEED: (0.25, (np.log(0.47), 1.75), np.geomspace(1e-4, 1e-2, 21), 2.0e5),
    fits.LARGE_SPEED: (0.25, (np.log(0.6), 1.5, 2.0), np.geomspace(0.5, 4.0, 10), 2.0e5),
}


def _bins(edges):
    return edges[:-1], edges[1:]


def synthetic_shards(rng, side, truth, edges, time):
    """Poisson counts per shard and bin, with shard-to-shard fluctuations shared by all bins
    (a common factor and a common tilt), as collision cascades make them."""
    lower, upper = _bins(edges)
    rate = fits.bin_average(fits.FORMS[side], lower, upper, *truth) * 0.5 * (upper**2 - lower**2)
    tilt = np.log(np.sqrt(lower * upper) / np.sqrt(lower[0] * upper[-1]))
    z = rng.standard_normal((SHARDS, 2))
    factor = np.exp(0.05 * z[:, :1] + 0.03 * z[:, 1:] * tilt[None, :])
    counts = rng.poisson(rate[None, :] * time * factor)
    return counts, np.full(SHARDS, time)
