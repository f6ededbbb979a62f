"""The sign-flip test of a chi^2/n over bins from the shards' deviations, and the per-shard
ratios it is computed from."""

import numbers

import numpy as np

__all__ = [
    "sign_flip_test",
    "order_free_mean",
    "ratio_deviations",
    "shard_ratios",
    "SIGN_FLIPS",
    "SIGN_FLIP_SEED",
]

# exact, fits and histograms (scipy, numba) are imported by the functions that use them: the
# moments and position tables need none of them


# the sign-flip test of the chi^2/n rows: this many random flips, from a fixed seed, so that
# the table is the same on every machine
SIGN_FLIPS = 10_000
SIGN_FLIP_SEED = 20061121
_FLIPS_PER_BLOCK = 1000  # flips evaluated at once (memory: block x bins)
# the unit roundoff of a float64: a rounded +, -, x or / is exact times (1 + e), |e| <= u
_UNIT_ROUNDOFF = float(np.finfo(float).eps) / 2.0
# the bits of a float64's significand: every integer of magnitude <= 2^52 is exact
_SIGNIFICAND_BITS = 53


def order_free_mean(values):
    """The mean along the last axis, the same bits for any order of the values.

    The values are sorted and then added one by one in ascending order (``numpy.cumsum``
    is sequential), so neither their order nor the machine changes the rounding (numpy's
    pairwise sum depends on the order).  The sum is off by at most (m - 1) u sum abs(x)
    (u = 2^-53, m values).

    Parameters
    ----------
    values : array_like, shape (..., m), m >= 1
        The values; not NaN, and not infinities of both signs.

    Returns
    -------
    numpy.ndarray or float
        The means, shape (...).

    Raises
    ------
    ValueError
        Where there is no value along the last axis.

    Examples
    --------
    >>> from bouncing_ball.validation import order_free_mean
    >>> print(order_free_mean([0.1, 0.2, 0.3]) == order_free_mean([0.3, 0.1, 0.2]))
    True
    """
    values = np.asarray(values, dtype=float)
    if values.ndim == 0 or values.shape[-1] == 0:
        raise ValueError(
            f"values: need at least one value along the last axis, got shape {values.shape}"
        )
    return np.cumsum(np.sort(values, axis=-1), axis=-1)[..., -1] / values.shape[-1]


def _integer_deviations(deviations):
    """Each bin's deviations as integers whose every signed sum over shards is exact.

    Bin b is scaled by a power of 2 (exactly) so that its largest |deviation| lies in
    [2^(51 - c), 2^(52 - c)), c = ceil(log2(shards)), and rounded to the nearest integer
    (half to even: -d gives -q).  A sum of the shards' integers times +-1 is then an integer
    of magnitude <= shards x 2^(52 - c) <= 2^52, exact in float64 whatever the order of the
    additions (a BLAS kernel's blocking, fused multiply-adds and threads).  z^2 of a bin does
    not change when the bin is scaled; the rounding moves each deviation by at most
    2^(c - 53) of the bin's largest, the size of the rounding of the float sum it replaces.
    """
    headroom = (deviations.shape[0] - 1).bit_length()  # ceil(log2(shards))
    _, exponents = np.frexp(np.max(np.abs(deviations), axis=0))
    return np.rint(np.ldexp(deviations, _SIGNIFICAND_BITS - 1 - headroom - exponents))


def _z_squared(signs, integers, squares):
    """z^2 of every bin under each sign pattern (rows of ``signs``), ``sign_flip_test``.

    With T = sum_k s_k q_k (exact: ``_integer_deviations``) and S = sum_k q_k^2,
    z^2 = (n - 1) n m^2 / (S - n m^2) at m = T / n is (n - 1) T^2 / (n S - T^2): a function
    of T^2, so patterns whose T agree up to sign give the same bits.  Where n S - T^2
    rounds to <= 0 (every s_k q_k equal, the exact z^2 infinite, or within rounding of it),
    z^2 is inf.
    """
    n = integers.shape[0]
    total_squared = np.square(signs @ integers)
    with np.errstate(divide="ignore"):
        return (n - 1) * total_squared / np.maximum(n * squares - total_squared, 0.0)


def _statistics(z_squared):
    """chi^2 per bin (``order_free_mean``) and the largest z^2 of each row of z^2."""
    return order_free_mean(z_squared), z_squared.max(axis=-1)


def sign_flip_test(deviations, flips=SIGN_FLIPS, seed=SIGN_FLIP_SEED):
    """The sign-flip test of shard-level deviations from a prediction.

    chi^2 per bin of the deviations, and the p-values of chi^2 and of the largest z^2 against
    their sign-flip null distributions.

    Parameters
    ----------
    deviations : array_like, shape (shards, bins)
        Each shard's deviation from the prediction: its estimate minus the prediction (shards
        of equal time) or its share of the merged estimate's deviation
        (``ratio_deviations``); finite, shards >= 2, bins >= 1, and in every bin the shards'
        deviations must differ by more than the rounding of their sum (else z has no
        scatter to be measured against).
    flips : int
        How many random sign patterns are drawn, >= 1.
    seed : int
        Seed of ``numpy.random.default_rng`` for the signs.

    Returns
    -------
    chi2_per_bin, p_chi2, p_worst : float
        z of a bin is the deviations' mean over its standard error from the scatter between
        the shards (the jackknife's, for a mean over shards); chi2_per_bin is the mean of z^2
        over the bins.  The null takes the shards as independent and each shard's deviation
        vector as symmetric about 0; then flipping the signs of whole shards leaves the joint
        distribution unchanged: the flipped statistics are the null distribution, and it
        carries the correlations between bins (shared shards, the normalisation, cascades of
        collisions filling neighbouring bins).  Independence gives a zero mean, not symmetry:
        where a shard's deviation is skewed (rare bins fed by cascades, a few shards holding
        most of a bin's content) the null is approximate, the more so the fewer the shards and
        the rarer the bin, and the worst-bin p more than the chi^2 p.

        p = (1 + the number of flipped statistics >= the observed one) / (1 + flips): a
        flipped statistic equal to the observed one counts.  Every sum over shards is exact
        (each bin's deviations are first rounded to integers of at most 52 - ceil(log2
        shards) bits, a change of the size of a float sum's rounding), so statistics whose
        z^2 agree bin by bin in exact arithmetic have the same bits and tie: flipping every
        sign leaves z^2 alone, so the all-flipped pattern ties with the observed statistic
        and counts, and so do patterns that differ only on shards with equal or zero
        deviations.  With n shards there are 2^(n - 1) distinct statistics and p is never much
        below 2^(1 - n).

        The same deviations give the same bits on every machine, for any BLAS kernel and
        thread count (the sums are exact), and for any order of the bins (the mean over bins
        is ``order_free_mean``); the signs come from the seeded PCG64.

    Raises
    ------
    ValueError
        Where ``deviations`` is not a finite (shards >= 2, bins >= 1) array, a bin's
        deviations agree to within rounding, or ``flips`` is not an integer >= 1.

    Examples
    --------
    Two bins, deviations of alternating sign over four shards: no deviation on average.

    >>> import numpy as np
    >>> from bouncing_ball.validation import sign_flip_test
    >>> deviations = np.array([[1.0, 0.5], [-1.0, -0.5], [1.0, -0.5], [-1.0, 0.5]])
    >>> chi2, p_chi2, p_worst = sign_flip_test(deviations)
    >>> print(chi2, p_chi2, p_worst)
    0.0 1.0 1.0
    """
    deviations = np.asarray(deviations, dtype=float)
    if deviations.ndim != 2 or deviations.shape[0] < 2 or deviations.shape[1] < 1:
        raise ValueError(
            f"deviations: need a (shards, bins) array with shards >= 2 and bins >= 1, "
            f"got shape {deviations.shape}"
        )
    if not np.all(np.isfinite(deviations)):
        raise ValueError("deviations: need finite values")
    if isinstance(flips, bool) or not isinstance(flips, numbers.Integral) or flips < 1:
        raise ValueError(f"flips: need an integer >= 1, got {flips!r}")
    flips = int(flips)
    n = deviations.shape[0]
    integers = _integer_deviations(deviations)
    squares = np.zeros(integers.shape[1])
    for shard in integers:  # a fixed order: the same bits on every machine
        squares += shard * shard
    total_squared = np.square(integers.sum(axis=0))  # exact
    # n S - T^2 is exact up to (n + 2) u n S: below that z^2 is not resolved
    unresolved = np.flatnonzero(
        n * squares - total_squared <= (n + 2) * _UNIT_ROUNDOFF * n * squares
    )
    if len(unresolved):
        raise ValueError(
            f"deviations: in bin(s) {unresolved.tolist()} the shards' deviations agree to "
            "within rounding: no scatter between the shards to measure z against"
        )
    chi2, worst = _statistics(_z_squared(np.ones((1, n)), integers, squares))
    rng = np.random.default_rng(seed)
    chi2_above = worst_above = 0
    for block in range(0, flips, _FLIPS_PER_BLOCK):
        signs = rng.choice([-1.0, 1.0], size=(min(_FLIPS_PER_BLOCK, flips - block), n))
        chi2_null, worst_null = _statistics(_z_squared(signs, integers, squares))
        chi2_above += int(np.sum(chi2_null >= chi2))
        worst_above += int(np.sum(worst_null >= worst))
    return float(chi2[0]), (1 + chi2_above) / (1 + flips), (1 + worst_above) / (1 + flips)


def ratio_deviations(numerators, denominators, reference):
    """Each shard's share of the deviation of a ratio estimate from a reference.

    For the estimate sum_k numerators_k / sum_k denominators_k the share of shard k is
    (numerators_k - reference x denominators_k) / sum_k denominators_k.  The shares add up to
    the estimate minus the reference; to first order they are what the delete-one jackknife
    sees of each shard, so ``sign_flip_test`` of them gives the merged table's z to first
    order.

    Parameters
    ----------
    numerators, denominators : array_like, shape (shards, bins)
        Each shard's numerator and denominator (``shard_ratios``).
    reference : array_like, shape (bins,)
        The prediction.

    Returns
    -------
    numpy.ndarray, shape (shards, bins)

    Examples
    --------
    >>> from bouncing_ball.validation import ratio_deviations
    >>> shares = ratio_deviations([[3.0], [5.0]], [[1.0], [3.0]], [1.5])
    >>> print(shares.ravel(), shares.sum(), 8.0 / 4.0 - 1.5)
    [0.375 0.125] 0.5 0.5
    """
    numerators = np.asarray(numerators, dtype=float)
    denominators = np.asarray(denominators, dtype=float)
    return (numerators - np.asarray(reference, dtype=float) * denominators) / denominators.sum(
        axis=0
    )


def shard_ratios(shards) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each shard's numerator and denominator of the estimates the validation checks.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards of one r (with the same bins).

    Returns
    -------
    dict
        Keyed as the merged tables' columns, each a pair of (shards x bins) arrays, bins as
        in the merged tables: ``p0v``, the collisions over the time times int_bin v dv
        (eq. (collrate), ``estimators.outgoing_speed_density``); ``px``, the time spent in
        the x bin over the time times the bin's width; ``v2_given_x``, the integral of
        v^2 dt in the bin over the time spent there (eq. (moment2)).
    """
    from ..estimators import outgoing_speed_density

    speeds, heights = shards[0].speed_bins, shards[0].position_bins
    times = np.array([s.time for s in shards], dtype=float)[:, None]
    in_bin = np.stack([s.position_time for s in shards])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        per_speed = 1.0 / outgoing_speed_density(1.0, 1.0, speeds.lower, speeds.upper)
        return {
            "p0v": (np.stack([s.speed_counts for s in shards]), times * per_speed),
            "px": (in_bin, times * (heights.upper - heights.lower)),
            "v2_given_x": (np.stack([s.position_v2_time for s in shards]), in_bin),
        }
