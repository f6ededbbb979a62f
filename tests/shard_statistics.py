"""CI-sized simulations and the statistics that hold them against predictions (shared by tests)."""

from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import yaml

from bouncing_ball.bins import LogBins
from bouncing_ball.histograms import outgoing_speed_density, outgoing_speed_histogram
from bouncing_ball.restitution import restitution_label
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

# the exact-result tests hold the simulation to the settings users run: the default config's
DEFAULT_SIMULATION = yaml.safe_load(
    (Path(__file__).resolve().parents[1] / "config" / "config.yaml").read_text()
)["simulation"]
CRITERION_C = float(DEFAULT_SIMULATION["criterion_c"])
MIN_STEP_DIVISOR = float(DEFAULT_SIMULATION["min_step_divisor"])
SPEED_BINS = LogBins(1e-4, 1e2, 10)
POSITION_BINS = LogBins(1e-3, 1e3, 5)


def _shard(arguments):
    r, shard, recorded_time, seed, floor, criterion_c = arguments
    return simulate_shard(
        restitution=float(r),
        seed_sequence=shard_seed_sequence(seed, restitution_label(r), shard),
        recorded_time=recorded_time,
        equilibration_time=200.0,
        criterion_c=criterion_c,
        min_step_divisor=MIN_STEP_DIVISOR,
        max_steps=10**12,
        speed_bins=SPEED_BINS,
        position_bins=POSITION_BINS,
        min_step_floor=floor,
    )


def simulate_shards(shard_times, shards, seed, min_step_floor=0.0, criterion_c=CRITERION_C):
    """{r: [ShardTallies]} for {r: recorded time per shard}, two processes, the default config's c
    (or ``criterion_c``) and delta rule (with a floor on delta if ``min_step_floor`` > 0)."""
    jobs = [
        (r, k, time, seed, min_step_floor, criterion_c)
        for r, time in shard_times.items()
        for k in range(shards)
    ]
    with ProcessPoolExecutor(2) as pool:
        results = list(pool.map(_shard, jobs))
    return {r: [s for (rr, *_), s in zip(jobs, results) if rr == r] for r in shard_times}


def outgoing_speed_bins(shards, minimum_count=100):
    """Bin edges and each shard's P(0,v) in the finite bins with at least ``minimum_count`` collisions."""
    table = outgoing_speed_histogram(shards)
    usable = (
        (table["count"] >= minimum_count) & np.isfinite(table.v_hi) & (table.v_lo > 0)
    ).to_numpy()
    lower, upper = table.v_lo.to_numpy()[usable], table.v_hi.to_numpy()[usable]
    per_shard = np.stack(
        [outgoing_speed_density(s.speed_counts[usable], s.time, lower, upper) for s in shards]
    )
    return lower, upper, per_shard


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
