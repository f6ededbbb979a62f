"""The bounce-speed chain u -> r v, v drawn from the exact return-speed law v G_g(v, u) of
eq. (kernel3), independently of the solver: many chains at once, each step by inverse
transform sampling.

The conditional law's CDF is tabulated on rows of outgoing speed U_a, uniform in
s = ln u + u^(1/2) with step ``ROW_STEP`` from 1e-6 to 150, each over ``ROW_POINTS`` return
speeds uniform in s (Simpson's cumulative rule, ``scipy.integrate.cumulative_simpson``).  A
chain at u between two rows draws from the row below or above with the weights of linear
interpolation in s (a mixture of the two laws, O(ROW_STEP^2) from the law at u); below the
lowest row, where gravity is negligible (relative O(u)), from the lowest row's law scaled to u
(the kernel is scale-free there).  Chains start at u = 1 and run ``burn_in`` steps before
they are recorded.
"""

import functools

import numpy as np
from scipy import integrate

from bouncing_ball.kernel import return_speed_density
from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate

ROW_STEP = 0.02
ROW_POINTS = 801
LOWEST_ROW, HIGHEST_ROW = 1e-6, 150.0


def _jacobian(u):
    """du / ds for s = ln u + u^(1/2)."""
    return u / (1.0 + 0.5 * np.sqrt(u))


@functools.cache
def return_law_table():
    """Rows U_a, their return-speed coordinates s_v[a, :] and CDFs[a, :] (normalised; the raw
    totals returned too, 1 to the table's accuracy by eq. (normG))."""
    s_rows = np.arange(coordinate_of_speed(LOWEST_ROW), coordinate_of_speed(HIGHEST_ROW), ROW_STEP)
    rows = speed_of_coordinate(s_rows)
    lower = coordinate_of_speed(1e-4 * rows)
    upper = coordinate_of_speed(rows + 12.0 * np.sqrt(rows) + 25.0)
    fraction = np.linspace(0.0, 1.0, ROW_POINTS)
    s_v = lower[:, None] + (upper - lower)[:, None] * fraction[None, :]
    v = speed_of_coordinate(s_v)
    density = return_speed_density(v, rows[:, None]) * _jacobian(v)
    cdf = integrate.cumulative_simpson(density, x=s_v, axis=1, initial=0.0)
    totals = cdf[:, -1].copy()
    cdf /= totals[:, None]
    return s_rows, s_v, np.maximum.accumulate(cdf, axis=1), totals


def simulate_chains(restitution, chains, steps, burn_in, seed):
    """Outgoing speeds u_n of ``chains`` independent stationary chains, shape (chains, steps)."""
    s_rows, s_v, cdf, _ = return_law_table()
    rng = np.random.default_rng(seed)
    rows, points = cdf.shape
    # one increasing array for all rows: row a's CDF shifted by 2 a
    flat = (cdf + 2.0 * np.arange(rows)[:, None]).ravel()
    u = np.ones(chains)
    record = np.empty((chains, steps))
    for n in range(burn_in + steps):
        s = coordinate_of_speed(np.maximum(u, speed_of_coordinate(s_rows[0])))
        position = (s - s_rows[0]) / ROW_STEP
        if np.any(position >= rows - 1):
            raise RuntimeError(f"a chain left the table: u = {u.max():.3g} > {HIGHEST_ROW}")
        row = np.floor(position).astype(int)
        row += rng.random(chains) < position - row
        target = rng.random(chains) + 2.0 * row
        j = np.clip(np.searchsorted(flat, target) - row * points, 1, points - 1)
        c0, c1 = cdf[row, j - 1], cdf[row, j]
        s0, s1 = s_v[row, j - 1], s_v[row, j]
        t = np.where(c1 > c0, (target - 2.0 * row - c0) / np.where(c1 > c0, c1 - c0, 1.0), 0.5)
        v = speed_of_coordinate(s0 + t * (s1 - s0))
        v = np.where(u < speed_of_coordinate(s_rows[0]), v * u / speed_of_coordinate(s_rows[0]), v)
        u = restitution * v
        if n >= burn_in:
            record[:, n - burn_in] = u
    return record
