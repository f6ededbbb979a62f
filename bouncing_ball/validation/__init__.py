"""The simulation held against the exact solutions and the solver: z-scores and residuals.

Pure functions on the tables the workflow writes; the figures (Figs. 5-7),
results/tables/moments.{csv,md} and results/tables/validation.{csv,md} are
drawn from them.  The modules:

- ``moments``: the time averages against the exact values and the solver
  (results/tables/moments);
- ``sign_flip``: the sign-flip test of a chi^2/n over bins, from the shards' deviations;
- ``checks``: the validation table's checks of P(0, v), P(x), <v^2>_x and the fits
  (results/tables/validation);
- ``position_asymptotics``: the asymptotics of P(x) for any r
  (results/tables/position_asymptotics);
- ``against_equilibrium``: ``compare``, an equilibrium object against a simulation's result.

Every name is importable from ``bouncing_ball.validation`` itself.
"""

from .against_equilibrium import (
    COMPARE_COLUMNS,
    COMPARED_SCALARS,
    compare,
)
from .checks import (
    POSITION_RANGE,
    QUALITY_SCALED_SPEEDS,
    VALIDATION_CHECKS,
    VALIDATION_COLUMNS,
    exact_outgoing_speed_residuals,
    fit_checks,
    outgoing_speed_checks,
    outgoing_speed_residuals,
    position_checks,
    quality_speeds,
    validation_markdown,
    validation_rows,
    validation_table,
)
from .moments import (
    INDEPENDENT_ESTIMATOR,
    MOMENT_COLUMNS,
    PAPER_VALUES,
    QUANTITIES,
    SYMBOLS,
    independent_estimate,
    kernel3_estimate,
    moment_rows,
    moments_markdown,
    moments_table,
    value_with_error,
)
from .position_asymptotics import (
    POSITION_EXPONENTS,
    position_asymptotics_markdown,
    position_asymptotics_table,
)
from .sign_flip import (
    SIGN_FLIP_SEED,
    SIGN_FLIPS,
    order_free_mean,
    ratio_deviations,
    shard_ratios,
    sign_flip_test,
)

__all__ = [
    "compare",
    "moment_rows",
    "moments_table",
    "moments_markdown",
    "value_with_error",
    "independent_estimate",
    "kernel3_estimate",
    "INDEPENDENT_ESTIMATOR",
    "outgoing_speed_residuals",
    "exact_outgoing_speed_residuals",
    "sign_flip_test",
    "order_free_mean",
    "ratio_deviations",
    "shard_ratios",
    "outgoing_speed_checks",
    "position_checks",
    "fit_checks",
    "validation_rows",
    "validation_table",
    "validation_markdown",
    "position_asymptotics_table",
    "position_asymptotics_markdown",
    "MOMENT_COLUMNS",
    "PAPER_VALUES",
    "QUANTITIES",
    "SYMBOLS",
    "SIGN_FLIPS",
    "SIGN_FLIP_SEED",
    "POSITION_RANGE",
    "QUALITY_SCALED_SPEEDS",
    "quality_speeds",
    "VALIDATION_CHECKS",
    "VALIDATION_COLUMNS",
    "POSITION_EXPONENTS",
    "COMPARED_SCALARS",
    "COMPARE_COLUMNS",
]
