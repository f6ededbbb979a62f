"""Flight times: McKean's law with gravity against eq. (kernel3), Ito identities, equilibrium.

Every identity here is exact for the true process, so each test fails if the joint law
(its form or its units), a quadrature or the equilibrium average is wrong.
"""

import numpy as np
import pytest
from scipy import integrate, stats

from bouncing_ball import exact
from bouncing_ball import flight_time as ft
from bouncing_ball.kernel import return_speed_kernel
from bouncing_ball.solver import coordinate_of_speed, solve_outgoing_speed_density

TOLERANCE = 1e-9
SPEEDS = [1e-12, 1e-6, 1e-3, 0.05, 0.5, 2.0, 10.0, 60.0, 300.0]
PAIRS = [(1e-6, 1e-5), (0.01, 0.5), (0.3, 0.7), (1.0, 1.0), (2.0, 5.0), (10.0, 12.0), (5.0, 0.1)]


@pytest.fixture(scope="module", params=[0.25, 1 / 3, 0.5, 0.75], ids=lambda r: f"r={r:.3g}")
def solution(request):
    return solve_outgoing_speed_density(request.param)


def _time_integral(v, u, k):
    """int_0^inf dt t^k p(t, v | u) by adaptive quadrature of eq. (joint) in ln t."""
    scale = u + v

    def integrand(log_t):
        t = np.exp(log_t)
        return t ** (k + 1) * ft.joint_density(t, v, u)

    points = [np.log(min(u, v) ** 2 + v * v), np.log(scale), np.log(2.0 * scale + 1.0)]
    value, _ = integrate.quad(
        integrand, -80.0, 8.0, points=sorted(points), epsabs=0.0, epsrel=1e-13, limit=500
    )
    return value


@pytest.mark.parametrize("u, v", PAIRS)
def test_time_marginal_of_joint_law_is_kernel3(u, v):
    """int dt p(t, v | u) = v G_g(v, u), eq. (GgP) with eq. (kernel3): McKean's law, its units
    (<xi xi> = 2 delta) and eq. (0g) together."""
    assert _time_integral(v, u, 0) == pytest.approx(
        v * return_speed_kernel(v, u), rel=TOLERANCE, abs=0.0
    )


@pytest.mark.parametrize("k", [0, 1, 2, 3])
@pytest.mark.parametrize("u, v", PAIRS)
def test_time_moments_in_closed_form(u, v, k):
    """Eq. (timemoments) (the y -> tau form) against the time integral of eq. (joint)."""
    assert ft.return_time_moment(v, u, k) == pytest.approx(
        _time_integral(v, u, k), rel=TOLERANCE, abs=0.0
    )


def test_gravity_free_limit():
    """For t, u, v << 1 gravity does not matter: p -> McKean's gravity-free law."""
    t, v, u = 1e-8, 3e-5, 1e-4
    ratio = ft.joint_density(t, v, u) / ft.free_first_passage_density(t, v, u)
    assert ratio == pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize("u", SPEEDS)
def test_return_is_certain(u):
    """Eq. (normG) through the joint law, both orders: int dv int dt p = int dt int dv p = 1."""
    assert ft.conditional_moment(u, 0, 0) == pytest.approx(1.0, abs=TOLERANCE)
    t, weights = ft.flight_time_nodes(u)
    assert weights @ ft.flight_time_density(t, u) == pytest.approx(1.0, abs=TOLERANCE)


@pytest.mark.parametrize("u", SPEEDS)
def test_ito_identities(u):
    """Exact identities of the process, all moments by quadrature of eq. (timemoments)."""

    def moment(k, m):
        return ft.conditional_moment(u, k, m)

    mean_time, second_time = moment(1, 0), moment(2, 0)
    # v + t
    assert mean_time == pytest.approx(u + moment(0, 1), rel=TOLERANCE, abs=0.0)
    # v^2 + 2 x
    assert moment(0, 2) == pytest.approx(u * u + 2.0 * mean_time, rel=TOLERANCE, abs=0.0)
    # t v + t^2 / 2
    assert second_time == pytest.approx(2.0 * moment(1, 1), rel=TOLERANCE, abs=0.0)
    # (v + t)^3
    cube = moment(3, 0) - 3.0 * moment(2, 1) + 3.0 * moment(1, 2) - moment(0, 3)
    assert cube == pytest.approx(u**3 + 3.0 * second_time, rel=TOLERANCE, abs=0.0)


@pytest.mark.parametrize("u", [1e-20, *SPEEDS, 1e4])
def test_closed_form_moments(u):
    """Eqs. (meanT), (meanT2) against the quadrature of the joint law."""
    assert ft.mean_flight_time_given_speed(u) == pytest.approx(
        ft.conditional_moment(u, 1, 0), rel=TOLERANCE, abs=0.0
    )
    assert ft.flight_time_second_moment_given_speed(u) == pytest.approx(
        ft.conditional_moment(u, 2, 0), rel=TOLERANCE, abs=0.0
    )


def test_closed_form_limits():
    small, large = 1e-14, 400.0
    assert ft.mean_flight_time_given_speed(small) == pytest.approx(
        3.0 * np.sqrt(2.0 * small / np.pi), rel=1e-6, abs=0.0
    )
    assert ft.flight_time_second_moment_given_speed(small) == pytest.approx(
        18.0 * np.sqrt(2.0 * small / np.pi), rel=1e-6, abs=0.0
    )
    mean = ft.mean_flight_time_given_speed(large)
    assert mean == pytest.approx(2.0 * large + 4.0 / 3.0, rel=1e-14)
    variance = ft.flight_time_second_moment_given_speed(large) - mean**2
    assert variance == pytest.approx(16.0 * large / 3.0 + 80.0 / 9.0, rel=1e-9)


@pytest.mark.parametrize("u", SPEEDS)
def test_flight_time_density_moments(u):
    """int t^k f(t | u) dt (f from the v-integral at fixed t) = E[T^k | u] (from the t-integral
    at fixed v): the two orders of the double integral of eq. (joint)."""
    t, weights = ft.flight_time_nodes(u)
    f = ft.flight_time_density(t, u)
    assert weights @ (t * f) == pytest.approx(
        ft.mean_flight_time_given_speed(u), rel=TOLERANCE, abs=0.0
    )
    second = ft.flight_time_second_moment_given_speed(u)
    assert weights @ (t * t * f) == pytest.approx(second, rel=TOLERANCE, abs=0.0)


@pytest.mark.parametrize("u", [1e-6, 0.05, 1.0, 20.0])
@pytest.mark.parametrize("x", [0.05, 0.4, 1.0, 2.5, 8.0])
def test_flight_time_density_against_adaptive_quadrature(u, x):
    t = x * (2.0 * u + u * u + 0.5)  # around the bulk of f(t | u)
    centre = 0.25 * (t + 2.0 * u)

    def integrand(log_v):
        v = np.exp(log_v)
        return v * ft.joint_density(t, v, u)

    lo, hi = np.log(1e-14 * min(centre, np.sqrt(t))), np.log(centre + 10.0 * np.sqrt(t))
    value, _ = integrate.quad(
        integrand, lo, hi, points=[np.log(centre)], epsabs=0.0, epsrel=1e-13, limit=500
    )
    assert ft.flight_time_density(t, u) == pytest.approx(value, rel=TOLERANCE, abs=0.0)


def test_equilibrium_mean_flight_time_is_inverse_collision_rate(solution):
    """<T> = 1 / I (the flights fill the time): int du u P(0, u) E[T | u] against the solver's I."""
    rate = solution.moment(1)
    assert ft.mean_flight_time(solution) * rate == pytest.approx(1.0, abs=TOLERANCE)
    assert ft.flight_time_second_moment(solution) > ft.mean_flight_time(solution) ** 2


@pytest.mark.parametrize("r", [0.5, 1 / 3])
def test_time_weighted_mean_with_exact_solution(r):
    """int du u P(0, u) E[T^2 | u] with the paper's exact P(0, v) (eq. (P(0,v))) against the
    solver's; at r = 1/2 it is 12 - 2 sqrt(3) (eq. (meanT2) integrated against e^-u / 3)."""

    def integrand(u):
        return u * exact.outgoing_speed_density(u, r) * ft.flight_time_second_moment_given_speed(u)

    value, _ = integrate.quad(integrand, 0.0, np.inf, epsabs=0.0, epsrel=1e-13, limit=200)
    solution = solve_outgoing_speed_density(r)
    assert ft.time_weighted_mean_flight_time(solution) == pytest.approx(
        value, rel=TOLERANCE, abs=0.0
    )
    if r == 0.5:
        assert value == pytest.approx(12.0 - 2.0 * np.sqrt(3.0), rel=1e-13)


def test_summary(solution):
    row = ft.flight_time_summary(solution)
    assert row["mean_flight_time"] * row["collision_rate"] == pytest.approx(1.0, abs=TOLERANCE)
    # above r_c the time-weighted mean is <T^2> / <T>
    ratio = row["flight_time_second_moment"] / row["mean_flight_time"]
    assert row["time_weighted_mean_flight_time"] == pytest.approx(ratio, rel=TOLERANCE, abs=0.0)


def test_flights_fill_the_time_below_critical():
    """Below r_c, I = inf but int T nu(T) dT = 1 still holds; per collision the mean is 0."""
    solution = solve_outgoing_speed_density(0.1)
    assert ft.flight_rate_moment(solution, 1) == pytest.approx(1.0, abs=TOLERANCE)
    assert ft.mean_flight_time(solution) == 0.0
    assert np.isfinite(ft.time_weighted_mean_flight_time(solution))
    table = ft.flight_time_table(solution, np.geomspace(1e-6, 10.0, 5))
    assert table["density"].isna().all() and (table["rate_density"] > 0.0).all()


def _flight_rate_integrals(solution, step=0.25):
    """int nu dT and int T nu dT: the trapezoidal rule in s = ln T + T^(1/2) from 1e-16 to 300,
    continued below 1e-16 in closed form with nu ~ T^(-beta/2) (the rule extended to s = -inf)."""
    t, weights = ft.trapezoid_nodes(1e-16, 300.0, step)
    step = np.diff(coordinate_of_speed(t[:2]))[0]  # the rule's own step, <= the one asked for
    weights[0] *= 2.0  # the lowest node gets its full weight; the rule continues below it
    nu = ft.flight_rate_density(solution, t)
    beta = solution.small_speed_exponent
    return [
        weights @ (t**k * nu) + weights[0] * t[0] ** k * nu[0] / np.expm1((1 + k - beta / 2) * step)
        for k in (0, 1, 2)
    ]


def test_flight_rate_density_integrates_to_collision_rate(solution):
    """int nu(T) dT = I, int T nu(T) dT = 1 and int T^2 nu dT = int du u P(0, u) E[T^2 | u]
    (eq. (meanT2)), by integrating nu(T) itself."""
    count, time, second = _flight_rate_integrals(solution)
    assert count == pytest.approx(solution.moment(1), rel=TOLERANCE, abs=0.0)
    assert time == pytest.approx(1.0, rel=TOLERANCE, abs=0.0)
    assert second == pytest.approx(ft.flight_rate_moment(solution, 2), rel=TOLERANCE, abs=0.0)


@pytest.mark.parametrize("t", [1e-20, 1e-10, 1e-3, 1.0, 30.0])
def test_flight_rate_density_against_adaptive_quadrature(t):
    """nu(T) of eq. (rate) against adaptive quadrature in ln u with the solver's Nystrom P(0, u);
    below u = 1e-7 T^(1/2) the integrand is the power law u^(5/2 - beta) (in ln u)."""
    solution = solve_outgoing_speed_density(0.25)

    def integrand(log_u):
        u = np.exp(np.atleast_1d(log_u))
        rate = u * u * solution.outgoing_speed_density(u)
        return (rate * ft.flight_time_density(t, u))[0]

    lo = np.log(1e-7 * np.sqrt(t))
    hi = np.log(solution.speeds[-1])
    peak = np.log(max(np.sqrt(t), 0.5 * t))
    value, _ = integrate.quad(integrand, lo, hi, points=[peak], epsabs=0.0, epsrel=1e-12, limit=400)
    value += integrand(lo) / (2.5 - solution.small_speed_exponent)
    assert ft.flight_rate_density(solution, t) == pytest.approx(value, rel=TOLERANCE, abs=0.0)


def test_short_time_constant_against_gravity_free_law():
    """C_beta of eq. (short) (hypergeometric form) = int du u^(1 - beta) f_0(1 | u)."""
    for beta in (0.4, 1.5, 2.2):

        def integrand(log_u, beta=beta):
            u = np.exp(log_u)
            return u ** (2.0 - beta) * ft.free_flight_time_density(1.0, u)

        value, _ = integrate.quad(integrand, -60.0, 4.0, epsabs=0.0, epsrel=1e-12, limit=400)
        assert ft.short_time_constant(beta) == pytest.approx(value, rel=1e-7, abs=0.0)


@pytest.mark.parametrize("r", [0.1, 0.5, 0.9])
def test_short_time_asymptote(r):
    solution = solve_outgoing_speed_density(r)
    t = np.array([1e-12, 1e-8, 1e-4])
    relative = ft.flight_rate_density(solution, t) / ft.short_flight_rate_density(solution, t) - 1
    assert np.all(np.abs(relative) < 2.0 * np.sqrt(t) + 1e-7)


@pytest.mark.parametrize("r", [0.25, 0.5, 0.75, 0.9])
def test_long_time_asymptote(r):
    """Eq. (long1) below r = 0.618, eq. (long2) above: the relative error falls with T."""
    solution = solve_outgoing_speed_density(r)
    t = np.array([100.0, 300.0, 1000.0])
    relative = np.abs(
        ft.flight_rate_density(solution, t) / ft.long_flight_rate_density(solution, t) - 1
    )
    assert np.all(np.diff(relative) < 0.0) and relative[-1] < 0.02


def test_return_speed_bins():
    solution = solve_outgoing_speed_density(0.5)
    u_edges = np.geomspace(1e-2, 10.0, 7)
    v_lower = np.concatenate([[0.0], np.geomspace(1e-3, 30.0, 9)])
    v_upper = np.concatenate([np.geomspace(1e-3, 30.0, 9), [np.inf]])
    cells = ft.return_speed_bin_probabilities(
        solution.outgoing_speed_density, u_edges[:-1], u_edges[1:], v_lower, v_upper
    )
    assert np.all(cells >= 0.0)
    np.testing.assert_allclose(cells.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    # one cell and the underflow bin against a brute-force product rule
    u = np.geomspace(u_edges[3], u_edges[4], 801)
    flux = u * solution.outgoing_speed_density(u)
    for j in (0, 5):
        lo = v_lower[j] if v_lower[j] > 0 else v_upper[j] * 1e-20
        v = np.geomspace(lo, v_upper[j], 1601)
        inner = integrate.simpson(v * return_speed_kernel(v[None, :], u[:, None]), x=v, axis=1)
        expected = integrate.simpson(flux * inner, x=u) / integrate.simpson(flux, x=u)
        assert cells[3, j] == pytest.approx(expected, rel=1e-6, abs=0.0)


def _simulated_flights(u, count, dt, seed):
    """Flight times and return speeds by the exact Gaussian step of (x, v) (eqs. (xstep),
    (vstep)), the crossing placed by linear interpolation within the step."""
    rng = np.random.default_rng(seed)
    x, v = np.zeros(count), np.full(count, u)
    times, speeds = np.full(count, np.nan), np.full(count, np.nan)
    active, step = np.arange(count), 0
    while active.size:
        r, s = rng.standard_normal((2, active.size))
        xa, va = x[active], v[active]
        x_new = xa + va * dt - 0.5 * dt * dt + dt * np.sqrt(dt / 6.0) * (s + np.sqrt(3.0) * r)
        v_new = va - dt + np.sqrt(2.0 * dt) * r
        hit = x_new < 0.0
        fraction = xa[hit] / (xa[hit] - x_new[hit])
        times[active[hit]] = dt * (step + fraction)
        speeds[active[hit]] = -(va[hit] + fraction * (v_new[hit] - va[hit]))
        x[active], v[active] = x_new, v_new
        active, step = active[~hit], step + 1
    return times, speeds


def test_monte_carlo_flight_times():
    """4000 simulated flights from u = 1: chi^2 of the T histogram (20 equiprobable bins) against
    f(t | u), and z-scores of the means of T and v."""
    u = 1.0
    times, speeds = _simulated_flights(u, 4000, 2e-3, 20261123)
    edges = np.concatenate([[0.0], np.quantile(times, np.linspace(0.0, 1.0, 21)[1:-1]), [np.inf]])
    t, weights = ft.flight_time_nodes(u, step=0.02)
    f = ft.flight_time_density(t, u) * weights
    expected = np.array([f[(t >= a) & (t < b)].sum() for a, b in zip(edges[:-1], edges[1:])])
    counts = np.histogram(times, edges)[0]
    chi2 = np.sum((counts - times.size * expected) ** 2 / (times.size * expected))
    assert stats.chi2.sf(chi2, edges.size - 2) > 1e-3
    for sample, mean in (
        (times, ft.mean_flight_time_given_speed(u)),
        (speeds, ft.conditional_moment(u, 0, 1)),
    ):
        assert abs(sample.mean() - mean) < 4.0 * sample.std() / np.sqrt(sample.size)
