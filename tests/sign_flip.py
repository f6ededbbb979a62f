"""A sign-flip test over shards, shared by the tests that hold simulations against predictions."""

import numpy as np


def sign_flip_p_values(deviations, flips=4000, seed=0):
    """p-values of chi^2 and of max |z| for shard-level deviations from a prediction.

    ``deviations`` is (shards, bins): each shard's estimate minus the exact
    value.  The statistics use the standard error of the mean over shards,
    as the merged tables do.  Under the null the shards are independent and
    each deviation vector is symmetric about 0, so flipping the sign of whole
    shards leaves the statistics' distribution unchanged: that distribution
    is the reference, and it carries the correlations between bins (collisions
    at low speed come in cascades that fill neighbouring bins together).
    """
    n = deviations.shape[0]
    squares = (deviations**2).sum(axis=0)

    def statistics(signs):
        mean = signs @ deviations / n
        variance = (squares - n * mean**2) / (n - 1)
        z_squared = mean**2 / (variance / n)
        return z_squared.mean(axis=-1), z_squared.max(axis=-1)

    chi2, worst = statistics(np.ones(n))
    signs = np.random.default_rng(seed).choice([-1.0, 1.0], size=(flips, n))
    chi2_null, worst_null = statistics(signs)
    return (
        float(chi2),
        (1 + np.sum(chi2_null >= chi2)) / (1 + flips),
        (1 + np.sum(worst_null >= worst)) / (1 + flips),
    )
