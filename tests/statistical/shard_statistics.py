"""CI-sized simulations and the statistics that hold them against predictions (shared by tests)."""

from concurrent.futures import ProcessPoolExecutor

import numpy as np
from default_settings import DEFAULT_SETTINGS as DEFAULT_CONFIG_SETTINGS

from bouncing_ball.estimators import outgoing_speed_density, outgoing_speed_histogram
from bouncing_ball.restitution import restitution_label
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

# the exact-result tests hold the simulation to the settings users run: the default config's
DEFAULT_SETTINGS = DEFAULT_CONFIG_SETTINGS.replace(equilibration_time=200.0, max_steps=10**12)
CRITERION_C = DEFAULT_SETTINGS.criterion_c


def _shard(arguments):
    r, shard, recorded_time, seed, floor, criterion_c, changes = arguments
    settings = DEFAULT_SETTINGS.replace(
        shard_time=recorded_time, criterion_c=criterion_c, min_step_floor=floor, **changes
    )
    return simulate_shard(
        float(r), shard_seed_sequence(seed, restitution_label(r), shard), settings
    )


def simulate_shards(
    shard_times, shards, seed, min_step_floor=0.0, criterion_c=CRITERION_C, **changes
):
    """{r: [ShardTallies]} for {r: recorded time per shard}, two processes, the default config's c
    (or ``criterion_c``) and delta rule (with a floor on delta if ``min_step_floor`` > 0), and
    the default config's other settings but ``changes`` (e.g. velocity_bins)."""
    jobs = [
        (r, k, time, seed, min_step_floor, criterion_c, changes)
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
