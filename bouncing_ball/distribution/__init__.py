"""The whole equilibrium distribution P(x, v) at any r, from the solver's P(0, v).

Method.  The solver (``solver.py``) gives P(0, v) on the outgoing side,
v > 0.  Everything else follows from the weight function w(F) of
eq. (weightfunc), ::

    w(F) = int_0^inf dv v phi_{1/4,F}(-v) h(v),   h(v) = e^(v/2) P(0, v),

with phi of eq. (phi) at s = 1/4.  The modules, in the order they build on each other:

- ``complex_kernel``: the kernel of eq. (kernel3) continued to complex v (compiled), the terms
  of the Nystrom formula of P(0, v) at complex v;
- ``ray_density``: P(0, v) on a ray arg v = RAY_ANGLE, solved from eq. (inteq) on that ray, for
  r near 1;
- ``outgoing_density``: P(0, v) as w(F) needs it, on the real axis and in the wedge
  0 <= arg v <= THETA_MAX (``outgoing_speed_solution``);
- ``weight_function``: w(F) by contour integrals of h(v) (``log_weight_function``), its
  small-F law w ~ F^gamma e^(-S/F) (``small_force_decay``, ``small_force_power``);
- ``interpolated_weight``: w(F) interpolated in ln F (``WeightFunction``), and an exact w(F) in
  the same form (``ClosedFormWeight``);
- ``position``: P(x) by eq. (P(x)1), int_x^inf P and <v^2>_x by eq. (moment2), moments and bin
  averages of P(x) in closed form under the F integral;
- ``phase_space``: P(x, v) by eq. (fpsol) (x > 0), and at x = 0 from P(0, v) and eq. (bc); its
  cell averages;
- ``exponents``: the asymptotic exponents of P(x), predicted and measured.

The tables of the pipeline's rule solve and their checks are the workflow's
(``bouncing_ball.workflow.solver_tables``).

Every name is importable from ``bouncing_ball.distribution`` itself.

Solving eq. (inteq) compiles the kernel on its first call (a minute), and a ``WeightFunction``
takes seconds to build, so the Examples that need them are not run as doctests; the unit and
numerical tests check the same values.  The Examples that run use the exact w(F) of r = 1/2,
eq. (weightfunc2) (``closed_form_weight_function``): every function of w here takes it as it
takes an interpolated one.

Examples
--------
P(x) of eq. (P(x)1) and its moments at r = 1/2 from the exact w(F): the paper's <x> = 6 and
Delta x = 6 3^(1/2), eq. (xandDeltax):

>>> import numpy as np
>>> from bouncing_ball import exact
>>> from bouncing_ball.distribution import closed_form_weight_function, position_averages
>>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
>>> print({name: round(value, 9) for name, value in position_averages(weight).items()})
{'normalization': 1.0, 'mean_x': 6.0, 'delta_x': 10.392304845}
"""

from ..kernel import TAIL as KERNEL_TAIL
from ..kernel import TAU_NODES
from .complex_kernel import (
    _HERMITE_COUNTS,
    _HERMITE_LIMITS,
    _HERMITE_W,
    _HERMITE_X2,
    _TAU_COUNTS,
    _TAU_LIMITS,
    _TAU_W,
    _TAU_X,
    SKIP_EFOLDS,
    TAU_HERMITE_LIMITS,
    TAU_HERMITE_NODES,
    TAU_LOOSE_GAP,
    TAU_RULE_LIMITS,
    TAU_RULE_NODES,
    _complex_kernel_sums,
    _principal_sqrt,
    _tau_hermite_rules,
    _tau_rules,
)
from .exponents import (
    _local_slope,
    exponents_table,
    measured_exponents,
    predicted_exponents,
)
from .interpolated_weight import (
    LARGE_PANEL_WIDTH,
    LARGEST_FORCE,
    NOISE_TOLERANCE,
    PANEL_CHEBYSHEV_NODES,
    PANEL_WIDTH,
    SMALL_FORCE_DEGREE,
    SMALL_PANEL_WIDTH,
    ClosedFormWeight,
    WeightFunction,
    _accurate,
    _smallest_force,
    closed_form_weight_function,
    interpolated_weight_function,
)
from .outgoing_density import (
    _GL_W,
    _GL_X,
    _WEDGE_ANGLES,
    _WEDGE_INVERSE_SPEED,
    _WEDGE_SPEED_X,
    ACCURATE_RANGE,
    PANEL_NODES,
    REAL_PANEL_WIDTH,
    REFINE,
    SMALLEST_SPEED,
    THETA_MAX,
    WEDGE_ANGLE_NODES,
    WEDGE_CLEAN,
    WEDGE_LOW_ANGLE_NODES,
    WEDGE_SMALLEST_SPEED,
    WEDGE_SPEED_NODES,
    WEDGE_SPEED_WIDTH,
    _chebyshev_nodes_and_inverse,
    _evaluate_wedge_cell,
    _outgoing_density,
    _OutgoingDensity,
    _panels,
    outgoing_speed_solution,
)
from .phase_space import (
    CELL_SPEED_NODES,
    DISTRIBUTION_NOISE,
    FORCE_CHECK_NODES,
    FORCE_CHECK_PHASE,
    FORCE_RULE_GRID,
    FORCE_RULE_MARGIN,
    FORCE_RULE_NODES,
    FORCE_RULE_PHASE,
    _distribution_integrand,
    _force_range,
    _force_rule_sum,
    distribution,
    distribution_by_force_integral,
    distribution_by_force_rule,
    distribution_cell_average,
    distribution_with_error,
)
from .position import (
    FORCE_EFOLDS,
    FORCE_PANEL_SIGMAS,
    FORCE_PANEL_WIDTH,
    LARGEST_LOG_FORCE,
    LARGEST_POSITION,
    LARGEST_VELOCITY,
    SMALLEST_POSITION,
    SMALLEST_WEIGHT_FORCE,
    _check_bins,
    _force_nodes,
    _laplace,
    _log_bin_laplace,
    _log_laplace,
    _total_decay,
    mean_speed_squared_given_position,
    position_averages,
    position_bin_average,
    position_density,
    position_moment,
    position_tail,
    speed_squared_given_position_bin_average,
)
from .ray_density import (
    _RAY_GL,
    _RAY_GL_W,
    _RAY_GL_X,
    _RAY_HERMITE_W,
    _RAY_HERMITE_X2,
    NEGLIGIBLE_EFOLDS,
    RAY_ANGLE,
    RAY_NEGLIGIBLE_EFOLDS,
    RAY_REACH,
    RAY_REFINE,
    RAY_RESTITUTION,
    _k,
    _ray_density,
    _ray_log_kernel,
    _ray_operator,
    _ray_operator_band,
    _ray_sums,
    _RayDensity,
    _w,
    _x,
)
from .weight_function import (
    _KERNEL_TRANSFORMS,
    _RAY_PANEL_W,
    _RAY_PANEL_X,
    CONTOUR_SLACK_MARGIN,
    EPSILON,
    KERNEL_TRANSFORM_NODES,
    KERNEL_TRANSFORM_WIDTH,
    LARGEST_KERNEL_FORCE,
    LARGEST_SLACK,
    OMEGA,
    RAY_PANEL_NODES,
    RAY_PANEL_TURN,
    ROUNDING,
    _airy_mellin,
    _compute_kernel_transform_table,
    _contour,
    _kernel_transform_table,
    _kernel_transforms,
    _log_contour_part,
    _log_kernel_transform,
    _log_psi,
    _log_psi_omega,
    _log_ray_contour_part,
    _log_sum,
    _log_weight_with_noise,
    _psi,
    _ray_contour_nodes,
    _ray_log_integrand,
    _real_segment_terms,
    _small_speed_slope,
    _split_point,
    log_weight_function,
    small_force_decay,
    small_force_power,
    weight_function,
)

__all__ = [
    "SMALLEST_POSITION",
    "LARGEST_POSITION",
    "LARGEST_VELOCITY",
    "SMALLEST_WEIGHT_FORCE",
    "THETA_MAX",
    "WEDGE_CLEAN",
    "PANEL_CHEBYSHEV_NODES",
    "NOISE_TOLERANCE",
    "CELL_SPEED_NODES",
    "DISTRIBUTION_NOISE",
    "outgoing_speed_solution",
    "small_force_decay",
    "small_force_power",
    "log_weight_function",
    "weight_function",
    "WeightFunction",
    "interpolated_weight_function",
    "closed_form_weight_function",
    "ClosedFormWeight",
    "position_density",
    "position_tail",
    "mean_speed_squared_given_position",
    "position_moment",
    "position_averages",
    "position_bin_average",
    "speed_squared_given_position_bin_average",
    "distribution_by_force_integral",
    "distribution_cell_average",
    "distribution_with_error",
    "distribution",
    "predicted_exponents",
    "measured_exponents",
    "exponents_table",
]
