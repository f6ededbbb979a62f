"""From summed shard tallies to P(0,v), P(x), <v^2>_x, P(x,v), the flights and the moments.

Every estimate is a function of the shards' summed tallies (``tallies.ShardTallies``); its
standard error comes from the scatter between shards by the delete-one jackknife
(``jackknife``: for a ratio of sums over shards of equal time it is the standard error of the
mean of the per-shard estimates).  ``control_variate_adjusted`` lowers the variance of any such
estimate with the shards' martingale control variates (``control_variate_rate``: of a rate);
the tables keep both estimates, plain and ``*_controlled``.  The modules:

- ``jackknife``: the delete-one jackknife over shards;
- ``control_variates``: the martingale control variates, and the return-law and flight-law
  predictions used as controls;
- ``histograms``: the tables of P(0, v), P(x), <v^2>_x, P(x, v), the flights and the return
  speeds;
- ``moments``: the time averages I, <x>, Delta x, <T>, <T^2>;
- ``autocorrelation``: the log outgoing speed's autocorrelation over bounces and the bounce
  chain's decay rate.

Every name is importable from ``bouncing_ball.estimators`` itself.

Examples
--------
Two shards of time 2 on one speed bin per decade, built by hand (``tallies``): 4 and 2
collisions, so I = 6 / 4 = 1.5 collisions per unit time, and the jackknife error is the
standard error of the mean of the shards' rates 2 and 1:

>>> from bouncing_ball.bins import LinearBins, LogBins
>>> from bouncing_ball.settings import ShardSettings
>>> from bouncing_ball.tallies import SCALAR_INDEX, ShardTallies
>>> from bouncing_ball.estimators import outgoing_speed_histogram, position_moments_summary
>>> settings = ShardSettings(
...     shard_time=2.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
...     max_steps=100, speed_bins=LogBins(0.1, 10.0, 1), position_bins=LogBins(0.1, 10.0, 1),
...     velocity_bins=LinearBins(-1.0, 1.0, 1.0), flight_time_bins=LogBins(0.1, 10.0, 1),
... )
>>> def shard(speed_counts, int_x, int_x2):
...     arrays = ShardTallies.loop_arrays(settings)
...     arrays["speed_counts"][:] = speed_counts
...     for name, value in (("time", 2.0), ("collisions", sum(speed_counts)),
...                         ("int_x", int_x), ("int_x2", int_x2)):
...         arrays["scalars"][SCALAR_INDEX[name]] = value
...     return ShardTallies.from_loop(settings, arrays)
>>> shards = [shard([0, 1, 3, 0], 1.0, 1.0), shard([0, 1, 1, 0], 2.0, 3.0)]
>>> summary = position_moments_summary(shards, restitution=0.5)
>>> print(summary[["collision_rate", "collision_rate_err", "mean_x", "mean_x_err"]].to_string())
   collision_rate  collision_rate_err  mean_x  mean_x_err
0             1.5                 0.5    0.75        0.25

Two shards are too few for the control variates: the ``*_controlled`` columns are NaN.

>>> print(summary["collision_rate_controlled"].isna().all())
True
>>> p0v = outgoing_speed_histogram(shards)
>>> print(p0v[["v_lo", "v_hi", "p0v", "count"]].round(6).to_string())
   v_lo  v_hi       p0v  count
0   0.0   0.1  0.000000      0
1   0.1   1.0  1.010101      2
2   1.0  10.0  0.020202      4
3  10.0   inf       NaN      0
"""

from .autocorrelation import (
    RESOLVED_CORRELATION,
    bounce_autocorrelation,
    bounce_chain_decay,
)
from .control_variates import (
    RETURN_LAW_POINTS,
    control_variate_adjusted,
    control_variate_rate,
    flight_law_prediction,
    moment_controls,
    return_law_prediction,
    shard_controls,
)
from .histograms import (
    distribution_histogram,
    flight_time_histogram,
    outgoing_speed_density,
    outgoing_speed_histogram,
    outside_fractions,
    position_histogram,
    return_speed_table,
)
from .jackknife import (
    deviations_from_mean,
    jackknife,
)
from .moments import (
    CONTROLLED_MOMENTS,
    position_moments_summary,
)

__all__ = [
    "CONTROLLED_MOMENTS",
    "jackknife",
    "deviations_from_mean",
    "shard_controls",
    "moment_controls",
    "outgoing_speed_density",
    "RETURN_LAW_POINTS",
    "return_law_prediction",
    "flight_law_prediction",
    "outgoing_speed_histogram",
    "position_histogram",
    "distribution_histogram",
    "flight_time_histogram",
    "return_speed_table",
    "outside_fractions",
    "position_moments_summary",
    "control_variate_rate",
    "control_variate_adjusted",
    "RESOLVED_CORRELATION",
    "bounce_autocorrelation",
    "bounce_chain_decay",
]
