"""The equilibrium distribution at any r (bouncing_ball.distribution), computed from the solver's
P(0, v), against the exact r = 1/2, 1/3 solutions (exact.py).  The checks at other r (the
solver's Ito time averages, the moment identities of P(x, v)) are in test_distribution_any_r.py."""

import warnings
from fractions import Fraction

import numpy as np
import pytest
from distribution_support import build
from scipy import integrate

from bouncing_ball import airy, distribution, exact
from bouncing_ball.workflow import solver_tables

EXACT = [Fraction(1, 2), Fraction(1, 3)]
# the checks at any r (0.15, 0.25, 0.6, 0.75, 0.9) are in test_distribution_any_r.py: each r
# costs a build of w(F) (``python -m benchmarks`` times it)


@pytest.fixture(scope="module")
def built():
    """(solution, WeightFunction) per r, built once per session (distribution_support.build)."""
    return build


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_weight_function_matches_the_exact_one(r, built):
    """w(F) of eq. (weightfunc) from the solver's P(0, v) against eq. (weightfunc2), F in [1e-3, 1e3]
    (the interpolant) and at a few F directly."""
    solution, weight = built(r)
    forces = np.geomspace(1e-3, 1e3, 41)
    expected = np.log(exact.weight_function(forces, r))
    assert np.max(np.abs(weight.log(forces) - expected)) < 1e-8
    direct = distribution.log_weight_function(np.array([0.01, 30.0]), solution)
    assert np.max(np.abs(direct - np.log(exact.weight_function([0.01, 30.0], r)))) < 1e-8


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_position_density_and_speed_squared_match_the_exact_ones(r, built):
    """P(x) of eq. (P(x)1) against eq. (P(x)2), and <v^2>_x of eq. (moment2), x in [1e-3, 100]."""
    _, weight = built(r)
    x = np.geomspace(1e-3, 100.0, 11)
    px = distribution.position_density(x, weight)
    assert np.max(np.abs(px / exact.position_density(x, r) - 1.0)) < 1e-8
    v2 = distribution.mean_speed_squared_given_position(x, weight)
    assert np.max(np.abs(v2 / exact.mean_speed_squared_given_position(x, r) - 1.0)) < 1e-8


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_bin_averages_match_the_exact_ones(r, built):
    _, weight = built(r)
    lo = np.array([0.0, 1e-3, 0.5, 10.0, 40.0])
    hi = np.array([1e-3, 0.01, 0.6, 12.0, 80.0])
    for ours, theirs in [
        (distribution.position_bin_average, exact.position_bin_average),
        (
            distribution.speed_squared_given_position_bin_average,
            exact.speed_squared_given_position_bin_average,
        ),
    ]:
        assert np.max(np.abs(ours(lo, hi, weight) / theirs(lo, hi, r) - 1.0)) < 1e-8


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_distribution_matches_the_exact_one(r, built):
    """P(x, v) by the F integral of eq. (fpsol) with the computed w against exact.distribution."""
    solution, weight = built(r)
    x, v = np.meshgrid([1e-3, 0.1, 1.0, 10.0], [-4.0, -0.5, 0.0, 0.5, 4.0], indexing="ij")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        ours = distribution.distribution(x, v, weight, solution)
        theirs = exact.distribution(x, v, r)
    assert np.max(np.abs(ours / theirs - 1.0)) < 1e-8
    # x = 0: the solver's P(0, v) and eq. (bc)
    at_wall = distribution.distribution(0.0, np.array([-2.0, 0.7]), weight, solution)
    assert np.allclose(at_wall, exact.distribution(0.0, np.array([-2.0, 0.7]), r), rtol=1e-9)


def test_tables(built):
    solution, weight = built(Fraction(1, 2))
    positions = solver_tables.position_frame(weight, np.geomspace(1e-3, 1e3, 7))
    assert list(positions.columns) == ["x", "px", "v2_given_x"]
    assert np.all(np.diff(positions["px"]) < 0.0)
    forces = solver_tables.weight_frame(weight, np.geomspace(1e-4, 1e6, 5))
    assert list(forces.columns) == ["F", "w", "log_w"]
    assert np.all(np.isfinite(forces["log_w"]))
    table, worst = solver_tables.distribution_frame(weight, solution, [0.0, 1.0], [-1.0, 1.0])
    assert len(table) == 4 and worst < 1e-8


def test_asymptotic_exponents_at_one_half(built):
    """The measured large-x form of P(x) at r = 1/2 is the paper's x^(-1/4) exp(-(2x/3)^(1/2))."""
    _, weight = built(Fraction(1, 2))
    measured = distribution.measured_exponents(weight)
    assert measured["large_x_rate"] == pytest.approx(np.sqrt(2.0 / 3.0), rel=1e-4)
    assert measured["large_x_power"] == pytest.approx(-0.25, abs=2e-3)


# the default config's P(x, v) grid (config/config.yaml, solver: positions, speeds)
RULE_POSITIONS = [0.012589, 0.12589, 1.2589]
RULE_SPEEDS = np.linspace(-4.0, 6.0, 101)


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_force_rule_meets_its_error_estimate(r):
    """The fixed rule of eq. (fpsol) with the exact w(F) of eq. (weightfunc2) against
    exact.distribution_by_force_integral (quad, with its own error estimate): the difference is
    within the sum of the two estimates (plus rounding, 1e-15 of the largest value at that x),
    and within 1e-10 relative wherever P(x, v) is above DISTRIBUTION_NOISE of that largest
    value."""
    weight = distribution.closed_form_weight_function(
        float(r), lambda f: np.log(exact.weight_function(f, r))
    )
    for x in RULE_POSITIONS:
        ours, estimate = distribution.distribution_by_force_rule(x, RULE_SPEEDS, weight)
        theirs, their_error = np.array(
            [exact.distribution_by_force_integral(x, v, r) for v in RULE_SPEEDS]
        ).T
        peak = np.max(theirs)
        assert np.all(np.abs(ours - theirs) <= estimate + their_error + 1e-15 * peak)
        above = theirs > distribution.DISTRIBUTION_NOISE * peak
        assert np.max(np.abs(ours[above] / theirs[above] - 1.0)) < 1e-10


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_distribution_table_matches_the_exact_one(r, built):
    """P(x, v) on the default config's grid from the computed w(F) against exact.distribution:
    within DISTRIBUTION_NOISE (1e-10) of its largest value at that x, and the quadrature's own
    error estimate within 1e-12 of it (the rest is w's)."""
    solution, weight = built(r)
    table, _ = solver_tables.distribution_frame(weight, solution, RULE_POSITIONS, RULE_SPEEDS)
    ours = table["pxv"].to_numpy().reshape(len(RULE_POSITIONS), -1)
    x, v = np.meshgrid(RULE_POSITIONS, RULE_SPEEDS, indexing="ij")
    theirs = exact.distribution(x, v, r)
    peak = theirs.max(axis=1, keepdims=True)
    assert np.max(np.abs(ours - theirs) / peak) < distribution.DISTRIBUTION_NOISE
    _, errors = distribution.distribution_with_error(x, v, weight, solution)
    assert np.max(errors / peak) < 1e-12


_HERMITE = (
    distribution._HERMITE_X2,
    distribution._HERMITE_W,
    distribution._HERMITE_COUNTS,
    distribution._HERMITE_LIMITS,
)
_NO_HERMITE = (np.zeros((1, 1)), np.zeros((1, 1)), np.zeros(1, dtype=np.int64), np.zeros((2, 0)))


def _kernel_sums(density, v, tau_x, tau_w, counts, limits, slack=0.0, hermite=_HERMITE):
    """The complex Nystrom sums at v with the given tau rules (Gauss-Legendre, then the
    Gauss-Hermite ``hermite``) and slack, and the sums of their terms' magnitudes
    (distribution._complex_kernel_sums)."""
    out, magnitude = np.empty(v.size, dtype=complex), np.empty(v.size)
    distribution._complex_kernel_sums(
        v, density.restitution, density.q, density.nodes, density.log_weights,
        tau_x, tau_w, counts, limits, *hermite, np.full(v.size, slack), out, magnitude,
    )  # fmt: skip
    return out, magnitude


def _tau_integrand_part(x2, z0):
    """g(x^2 / z0) of the tau integral z0^(-1/2) int_0^inf e^(-x^2) g(x^2 / z0) dx."""
    t2 = x2 / z0
    return (1.0 + z0 + x2) / ((1.0 + t2) ** 2 * np.sqrt(2.0 + t2))


@pytest.mark.parametrize("tier, tolerance", [(0, 2e-15), (1, 1e-8)])
def test_tau_hermite_rules_meet_their_limits(tier, tolerance):
    """Each Gauss-Hermite rule of the tau integral (distribution.TAU_HERMITE_NODES) from its
    limit |z0| (TAU_HERMITE_LIMITS[tier]) up, |arg z0| <= pi/2, against a 160-node rule: within
    ~1e-15 of the integral in tier 0, 1e-8 in tier 1."""
    nodes, weights = np.polynomial.hermite.hermgauss(160)
    nodes, weights = nodes[80:], weights[80:]
    for k, limit in enumerate(distribution.TAU_HERMITE_LIMITS[tier]):
        if not np.isfinite(limit):
            continue
        size = distribution.TAU_HERMITE_NODES[k]
        x2, w = distribution._HERMITE_X2[k, :size], distribution._HERMITE_W[k, :size]
        for z0 in np.outer([limit, 1.5 * limit, 3.0 * limit, 30.0 * limit], np.exp(
            1j * np.linspace(-0.5 * np.pi, 0.5 * np.pi, 31)
        )).ravel():  # fmt: skip
            ours = np.sum(w * _tau_integrand_part(x2, z0))
            reference = np.sum(weights * _tau_integrand_part(nodes**2, z0))
            assert abs(ours / reference - 1.0) < tolerance, (tier, size, z0)


@pytest.mark.parametrize("r", [0.25, 0.75])
def test_tau_rules_match_the_kernels_rule(r, built):
    """The complex Nystrom sums of P(0, v) e^(q v) with the tau rules TAU_RULE_NODES chosen by
    eps (TAU_RULE_LIMITS) and TAU_HERMITE_NODES by |z0| (TAU_HERMITE_LIMITS) against the same
    sums with 64-node Gauss-Legendre for every term (the kernel's TAU_NODES = 20 leave ~1e-13
    where the Gaussian is cut at TAIL): within 1e-14 of the sum of the terms' magnitudes, over
    the wedge 0 <= arg v <= THETA_MAX."""
    solution, _ = built(r)
    density = distribution._outgoing_density(solution)
    rho = np.geomspace(distribution.WEDGE_SMALLEST_SPEED, 0.3 * density.largest, 12)
    theta = np.linspace(0.0, distribution.THETA_MAX, 4)
    v = np.ascontiguousarray((rho[:, None] * np.exp(1j * theta[None, :])).ravel())
    ours, magnitude = _kernel_sums(
        density,
        v,
        distribution._TAU_X,
        distribution._TAU_W,
        distribution._TAU_COUNTS,
        distribution._TAU_LIMITS,
    )
    count = 64
    nodes, weights = np.polynomial.legendre.leggauss(count)
    reference, _ = _kernel_sums(
        density,
        v,
        0.5 * (nodes[None, :] + 1.0),
        0.5 * weights[None, :],
        np.array([count]),
        np.zeros((2, 0)),
        hermite=_NO_HERMITE,
    )
    assert np.max(np.abs(ours - reference) / magnitude) < 1e-14


@pytest.mark.parametrize("r", [0.25, 0.75])
def test_slack_sums_meet_their_accuracy(r, built):
    """A Nystrom sum with the largest slack (distribution.LARGEST_SLACK) against the full one:
    within 1e-4 of its value, over the wedge 0 <= arg v <= THETA_MAX (where it is used, its
    contour node is at least CONTOUR_SLACK_MARGIN + LARGEST_SLACK = 36 e-folds, 2e-16, below the
    largest term: below 1e-19 of it)."""
    solution, _ = built(r)
    density = distribution._outgoing_density(solution)
    rho = np.geomspace(distribution.WEDGE_SMALLEST_SPEED, 0.3 * density.largest, 12)
    theta = np.linspace(0.0, distribution.THETA_MAX, 4)
    v = np.ascontiguousarray((rho[:, None] * np.exp(1j * theta[None, :])).ravel())
    rules = (distribution._TAU_X, distribution._TAU_W, distribution._TAU_COUNTS)
    full, magnitude = _kernel_sums(density, v, *rules, distribution._TAU_LIMITS)
    loose, _ = _kernel_sums(
        density, v, *rules, distribution._TAU_LIMITS, slack=distribution.LARGEST_SLACK
    )
    assert np.max(np.abs(loose - full) / np.maximum(np.abs(full), 1e-16 * magnitude)) < 1e-4


def test_airy_function_from_bessel_functions_is_scipys():
    """airy_ai (Bessel functions where |z| > 10) against scipy's airy, relative to the
    envelope |z|^(-1/4) on the oscillating side and to Ai where it decays: within 10 rounding errors of the phase (2/3) |z|^(3/2), which neither can beat."""
    from scipy import special

    z = np.concatenate([np.linspace(-3000.0, -10.0, 2001), np.linspace(-10.0, 60.0, 701)])
    ours, theirs = airy.airy_ai(z), special.airy(z)[0]
    envelope = np.where(z < 0.0, np.maximum(np.abs(z), 1.0) ** -0.25, np.abs(theirs))
    phase = (2.0 / 3.0) * np.abs(z) ** 1.5
    assert np.all(np.abs(ours - theirs) <= 10.0 * np.finfo(float).eps * (1.0 + phase) * envelope)
