"""The comparison of simulation, solver and exact results: z-scores, residuals, the paper's numbers."""

from fractions import Fraction
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from bouncing_ball import exact
from bouncing_ball.bins import LogBins
from bouncing_ball.estimators import outgoing_speed_histogram, position_histogram
from bouncing_ball.tallies import RATE_CONTROLS
from bouncing_ball.validation import (
    PAPER_VALUES,
    SIGN_FLIP_SEED,
    VALIDATION_CHECKS,
    fit_checks,
    moment_rows,
    moments_markdown,
    moments_table,
    outgoing_speed_checks,
    outgoing_speed_residuals,
    quality_speeds,
    ratio_deviations,
    shard_ratios,
    sign_flip_test,
    validation_markdown,
    validation_rows,
    validation_table,
    value_with_error,
)
from bouncing_ball.validation.checks import MINIMUM_BIN_COUNT


@pytest.mark.parametrize("restitution", exact.EXACT_RESTITUTIONS)
def test_the_paper_numbers_are_the_exact_values_rounded(restitution):
    """eq. (xandDeltax) as printed (6, 10.4, 1/3; 3.89, 7.68, 3/4) is the exact result to its last digit."""
    computed = exact.position_moments(restitution)
    for quantity, printed in PAPER_VALUES[restitution].items():
        digits = {10.4: 1, 3.89: 2, 7.68: 2}.get(printed)  # 6, 1/3, 3/4 are exact
        tolerance = (
            1e-10 if digits is None else 0.5 * 10.0**-digits
        )  # 1e-10: the quadrature of P(x)
        assert abs(computed[quantity] - printed) <= tolerance, quantity


def _summary(values, errors):
    return pd.Series({**values, **{f"{key}_err": errors[key] for key in errors}})


def test_z_is_against_the_exact_value_where_there_is_one_and_the_solver_otherwise():
    simulated = _summary(
        {"mean_x": 6.02, "delta_x": 10.3, "collision_rate": 0.3330},
        {"mean_x": 0.01, "delta_x": 0.05, "collision_rate": 0.0002},
    )
    solved = pd.Series({"mean_x": 6.0 + 1e-9, "delta_x": 6 * 3**0.5, "collision_rate": 1 / 3})
    exact_row = pd.Series({"mean_x": 6.0, "delta_x": 6 * 3**0.5, "collision_rate": 1 / 3})
    rows = moments_table(
        moment_rows("0.5", Fraction(1, 2), simulated, solved, exact_row)
    ).set_index("quantity")
    assert (rows.reference == "exact").all()
    assert rows.loc["mean_x", "z"] == pytest.approx(2.0)
    assert rows.loc["collision_rate", "z"] == pytest.approx((0.3330 - 1 / 3) / 0.0002)
    assert rows.loc["delta_x", "paper"] == 10.4
    other = moments_table(moment_rows("0.6", Fraction(3, 5), simulated, solved)).set_index(
        "quantity"
    )
    assert (
        (other.reference == "solver").all()
        and other.paper.isna().all()
        and other.exact.isna().all()
    )
    assert other.loc["mean_x", "z"] == pytest.approx((6.02 - 6.0 - 1e-9) / 0.01)
    infinite = moment_rows(
        "0.1", Fraction(1, 10), simulated, pd.Series({**solved, "collision_rate": np.inf})
    )
    assert np.isnan(infinite[2]["z"])  # below r_c the solver's I is infinite: no z
    markdown = moments_markdown(
        moments_table(moment_rows("0.5", Fraction(1, 2), simulated, solved, exact_row))
    )
    assert "6.020 ± 0.010" in markdown and "+2.00 (vs exact)" in markdown
    assert (rows.estimator == "plain").all()  # the summary has no controlled estimate


def test_the_table_shows_the_estimator_fixed_in_advance_whatever_the_errors():
    """simulation is the martingale-controlled estimate of every quantity, even where the
    plain or the eq. (kernel3) one has the smaller error; the plain one only where the
    martingale one is NaN (too few shards).  The eq. (kernel3) estimate has its own columns
    and z, filled only where the summary says its controls are in use."""
    simulated = _summary(
        {
            "mean_x": 6.02,
            "mean_x_martingale": 6.001,
            "mean_x_controlled": 6.03,
            "delta_x": 10.3,
            "delta_x_martingale": 10.2,
            "delta_x_controlled": 10.25,
            "collision_rate": 0.3330,
            "collision_rate_martingale": np.nan,
            "collision_rate_controlled": 0.3331,
        },
        {
            "mean_x": 0.01,
            "mean_x_martingale": 0.002,
            "mean_x_controlled": 0.001,
            "delta_x": 0.05,
            "delta_x_martingale": 0.06,
            "delta_x_controlled": 0.01,
            "collision_rate": 0.0002,
            "collision_rate_martingale": np.nan,
            "collision_rate_controlled": 0.0001,
        },
    )
    solved = pd.Series({"mean_x": 6.0, "delta_x": 6 * 3**0.5, "collision_rate": 1 / 3})
    rows = moments_table(
        moment_rows("0.6", Fraction(3, 5), {**simulated, "kernel3_controls": True}, solved)
    ).set_index("quantity")
    assert rows.loc["mean_x", ["simulation", "simulation_err", "estimator"]].tolist() == [
        6.001,
        0.002,
        "martingale",
    ]
    assert rows.loc["mean_x", "z"] == pytest.approx(0.5)
    assert rows.loc["mean_x", "kernel3_z"] == pytest.approx(30.0)
    assert rows.loc["delta_x", "estimator"] == "martingale"  # its error is the larger
    assert rows.loc["delta_x", "simulation"] == 10.2
    assert rows.loc["collision_rate", "estimator"] == "plain"
    assert rows.loc["collision_rate", "kernel3_controlled"] == 0.3331
    markdown = moments_markdown(
        moments_table(
            moment_rows("0.6", Fraction(3, 5), {**simulated, "kernel3_controls": True}, solved)
        )
    )
    assert "| martingale " in markdown and "eq. (kernel3)" in markdown
    without = moments_table(
        moment_rows("0.6", Fraction(3, 5), {**simulated, "kernel3_controls": False}, solved)
    )
    assert without.kernel3_controlled.isna().all() and without.kernel3_z.isna().all()


@pytest.mark.parametrize(
    "value, error, text",
    [
        (3.42796, 0.00302, "3.4280 ± 0.0030"),
        (0.113779, 2.2e-5, "0.113779 ± 0.000022"),
        (4357.9, 12.3, "4358 ± 12"),
        (6.0, float("nan"), "6"),
    ],
)
def test_a_value_is_shown_to_the_second_digit_of_its_error(value, error, text):
    assert value_with_error(value, error) == text


def _simulated_bins(restitution, sigma, rng, lo=1e-3, hi=10.0, per_decade=10):
    """Bins of P(0, v) like a merged table: exact bin averages plus Gaussian noise of
    relative size ``sigma``, with under- and overflow bins and one empty bin."""
    edges = np.geomspace(lo, hi, int(round(per_decade * np.log10(hi / lo))) + 1)
    truth = exact.outgoing_speed_bin_average(edges[:-1], edges[1:], restitution)
    errors = sigma * truth
    frame = pd.DataFrame(
        {
            "v_lo": edges[:-1],
            "v_hi": edges[1:],
            "v": np.sqrt(edges[:-1] * edges[1:]),
            "p0v": truth + errors * rng.standard_normal(len(truth)),
            "p0v_err": errors,
            "count": 1000,
            "p0v_controlled": truth + errors / 3 * rng.standard_normal(len(truth)),
            "p0v_controlled_err": errors / 3,
        }
    )
    frame.loc[5, ["p0v", "p0v_err", "count", "p0v_controlled", "p0v_controlled_err"]] = [
        0.0,
        np.nan,
        0,
        0.0,
        np.nan,
    ]
    edge_rows = pd.DataFrame(
        {
            "v_lo": [0.0, hi],
            "v_hi": [lo, np.inf],
            "v": [lo / 2, np.inf],
            "p0v": [1.0, np.nan],
            "p0v_err": [0.1, np.nan],
            "count": [10, 0],
            "p0v_controlled": [1.0, np.nan],
            "p0v_controlled_err": [0.1, np.nan],
        }
    )
    return pd.concat([edge_rows.iloc[:1], frame, edge_rows.iloc[1:]], ignore_index=True), truth


@pytest.mark.parametrize("restitution", exact.EXACT_RESTITUTIONS)
def test_residuals_against_the_exact_curve_are_standard_normal(restitution):
    """With the exact P(0, v) as 'solver' output, residuals of noisy bin averages are N(0, 1):
    their mean and mean square are within 4 standard errors of 0 and 1 (2000 bins)."""
    rng = np.random.default_rng(7)
    speeds = np.geomspace(1e-4, 50.0, 401)
    curve = pd.DataFrame({"v": speeds, "p0v": exact.outgoing_speed_density(speeds, restitution)})
    residuals = []
    for _ in range(50):
        simulated, _ = _simulated_bins(restitution, 0.01, rng)
        table = outgoing_speed_residuals(simulated, curve)
        assert (
            len(table) == len(simulated) - 3
        )  # the empty, underflow and overflow bins are left out
        residuals.append(table.residual.to_numpy())
    z = np.concatenate(residuals)
    assert abs(z.mean()) < 4.0 / np.sqrt(len(z))
    assert abs((z**2).mean() - 1.0) < 4.0 * np.sqrt(2.0 / len(z))


def test_a_one_percent_error_in_the_curve_shows_in_the_residuals():
    """The same test fails when the reference is off by 1% (the residuals shift by 1 sigma)."""
    rng = np.random.default_rng(8)
    restitution = Fraction(1, 2)
    speeds = np.geomspace(1e-4, 50.0, 401)
    curve = pd.DataFrame(
        {"v": speeds, "p0v": 1.01 * exact.outgoing_speed_density(speeds, restitution)}
    )
    simulated, _ = _simulated_bins(restitution, 0.01, rng)
    z = outgoing_speed_residuals(simulated, curve).residual.to_numpy()
    assert z.mean() == pytest.approx(-1.0, abs=4.0 / np.sqrt(len(z)))


def test_bins_beyond_the_curve_are_left_out():
    rng = np.random.default_rng(9)
    simulated, _ = _simulated_bins(Fraction(1, 3), 0.01, rng, lo=1e-5, hi=100.0)
    speeds = np.geomspace(1e-4, 50.0, 401)
    curve = pd.DataFrame({"v": speeds, "p0v": exact.outgoing_speed_density(speeds, Fraction(1, 3))})
    table = outgoing_speed_residuals(simulated, curve)
    assert table.v_lo.min() >= 1e-4 and table.v_hi.max() <= 50.0
    assert (
        len(table) == ((simulated.v_lo >= 1e-4) & (simulated.v_hi <= 50.0)).sum()
    )  # empty bin: below 1e-4


def test_a_curve_that_underflows_is_used_up_to_its_last_positive_value():
    """Below r ~ 0.035 the solver's P(0, v) ~ exp(-v / (2r)) is 0 at the top of its grid:
    bins there are left out instead of failing the fit and Fig. 7 (r = 0.03)."""
    from bouncing_ball import solver

    speeds = np.geomspace(1e-4, 50.0, 401)
    density = solver.solve_outgoing_speed_density(0.03).outgoing_speed_density(speeds)
    assert density[-1] == 0.0 and density[0] > 0.0
    edges = np.geomspace(1e-4, 1e2, 61)
    simulated = pd.DataFrame(
        {
            "v_lo": edges[:-1],
            "v_hi": edges[1:],
            "v": np.sqrt(edges[:-1] * edges[1:]),
            "p0v": 1.0,
            "p0v_err": 0.1,
            "count": 100,
        }
    )
    table = outgoing_speed_residuals(simulated, pd.DataFrame({"v": speeds, "p0v": density}))
    last_positive = speeds[density > 0][-1]
    assert len(table) > 0 and table.v_hi.max() <= last_positive < edges[-1]
    assert np.isfinite(table.residual).all()


def _position_bins(restitution, sigma, rng, lo=1e-3, hi=1e3, per_decade=5):
    """A merged position table: exact bin averages of P(x) and <v^2>_x plus Gaussian noise
    of relative size ``sigma``, with under- and overflow bins."""
    edges = np.geomspace(lo, hi, int(round(per_decade * np.log10(hi / lo))) + 1)
    px = exact.position_bin_average(edges[:-1], edges[1:], restitution)
    v2 = exact.speed_squared_given_position_bin_average(edges[:-1], edges[1:], restitution)
    n = len(px)
    frame = pd.DataFrame(
        {
            "x_lo": np.r_[0.0, edges[:-1], hi],
            "x_hi": np.r_[lo, edges[1:], np.inf],
            "x": np.r_[lo / 2, np.sqrt(edges[:-1] * edges[1:]), np.inf],
            "px": np.r_[1.0, px * (1.0 + sigma * rng.standard_normal(n)), np.nan],
            "px_err": np.r_[0.1, sigma * px, np.nan],
            "v2_given_x": np.r_[1.0, v2 * (1.0 + sigma * rng.standard_normal(n)), np.nan],
            "v2_given_x_err": np.r_[0.1, sigma * v2, np.nan],
        }
    )
    return frame


def _fits_table(joint_p=0.4, chi2=1.1):
    rows = []
    for side, names in (
        ("small_speed", ["prefactor", "beta"]),
        ("large_speed", ["prefactor", "m", "q"]),
    ):
        for source in ("simulation", "solver"):
            for fit in ("fixed_exponents", "free_exponents"):
                for name in names:
                    rows.append(
                        {
                            "source": source,
                            "window": side,
                            "fit": fit,
                            "parameter": name,
                            # the solver's free fit gives the theory's exponents: the
                            # form holds over the window
                            "value": 1.0 if source == "solver" and name != "prefactor" else 1.02,
                            "error": 0.03,
                            "theory": np.nan if name == "prefactor" else 1.0,
                            "joint_p_value": joint_p if fit == "free_exponents" else np.nan,
                            "chi2_per_dof": chi2 if source == "simulation" else 0.0,
                            "dof": 10,
                            "v_min": 1e-4 if side == "small_speed" else 2.0,
                            "v_max": 1e-2 if side == "small_speed" else 10.0,
                        }
                    )
    return pd.DataFrame(rows)


def _by_check(rows):
    return validation_table(rows).set_index("check")


@pytest.mark.parametrize("restitution", exact.EXACT_RESTITUTIONS)
def test_validation_of_noisy_exact_bins_gives_chi2_near_one(restitution):
    """Bins of P(0, v) and P(x), <v^2>_x with Gaussian errors about the exact bin averages of
    eqs. (P(0,v)), (P(x)2), (moment2): chi^2/n within 4 standard errors of 1, every
    z within 5, reference 'exact', and the under-, overflow and empty bins left out."""
    rng = np.random.default_rng(11)
    p0v, _ = _simulated_bins(restitution, 0.01, rng, lo=1e-4, hi=100.0)
    position = _position_bins(restitution, 0.01, rng)
    outside = {"p0v": {"below": 1e-6, "above": 0.0, "outside": 1e-6, "counts": "collisions"}}
    rows = _by_check(
        validation_rows(
            "label", restitution, p0v, position, _fits_table(), shards=16, outside=(outside,) * 2
        )
    )
    assert list(rows.index) == list(VALIDATION_CHECKS)
    assert (rows.r_label == "label").all() and (rows.r == float(restitution)).all()
    speeds = rows.loc["p0v_chi2_per_bin"]
    assert speeds.reference == "exact" and speeds.bins == len(p0v) - 3
    assert np.isnan(speeds.p_sign_flip)  # no shards' tallies given: no p
    assert abs(speeds.value - 1.0) < 4.0 * np.sqrt(2.0 / speeds.bins)
    assert abs(rows.loc["p0v_worst_bin", "value"]) < 5.0
    assert rows.loc["p0v_largest_relative_error", "value"] == pytest.approx(0.01, rel=0.05)
    for quantity in ("px", "v2_given_x"):
        row = rows.loc[f"{quantity}_chi2_per_bin"]
        assert row.reference == "exact"
        assert row.bins == 23  # x from 1e-3 to 10^1.6 <= 50 at 5 bins per decade
        assert abs(row.value - 1.0) < 4.0 * np.sqrt(2.0 / row.bins)


def test_validation_reports_a_planted_five_sigma_bin_as_the_worst_with_its_place():
    rng = np.random.default_rng(12)
    restitution = Fraction(1, 3)
    p0v, _ = _simulated_bins(restitution, 0.01, rng, lo=1e-4, hi=100.0)
    p0v.loc[20, "p0v"] += 5.0 * p0v.loc[20, "p0v_err"] - (
        p0v.loc[20, "p0v"]
        - exact.outgoing_speed_bin_average(p0v.loc[20, "v_lo"], p0v.loc[20, "v_hi"], restitution)
    )
    position = _position_bins(restitution, 0.01, rng)
    position.loc[10, "v2_given_x"] -= 6.0 * position.loc[10, "v2_given_x_err"]
    rows = _by_check(validation_rows("0.333333", restitution, p0v, position, _fits_table(), 16))
    assert rows.loc["p0v_worst_bin", "value"] == pytest.approx(5.0)
    assert rows.loc["p0v_worst_bin", "bin_centre"] == p0v.loc[20, "v"]
    assert rows.loc["v2_given_x_worst_bin", "value"] < -5.0
    assert rows.loc["v2_given_x_worst_bin", "bin_centre"] == position.loc[10, "x"]
    assert rows.loc["p0v_chi2_per_bin", "value"] > 25.0 / rows.loc["p0v_chi2_per_bin", "bins"]


def test_validation_relative_error_names_the_worst_bin_and_counts_empty_bins_as_infinite():
    rng = np.random.default_rng(13)
    p0v, _ = _simulated_bins(Fraction(1, 2), 0.01, rng)  # bins 1e-3 .. 10, row 5 empty
    inside = p0v[(p0v.v >= 0.01) & (p0v.v <= 5.0)].index
    p0v.loc[inside[3], "p0v_err"] = 0.2 * p0v.loc[inside[3], "p0v"]
    rows = _by_check(outgoing_speed_checks(p0v, Fraction(1, 2), shards=8))
    row = rows.loc["p0v_largest_relative_error"]
    assert row.value == pytest.approx(0.2) and row.bin_centre == p0v.loc[inside[3], "v"]
    assert row.bins == len(inside)
    p0v.loc[inside[5], ["p0v", "p0v_err"]] = [0.0, np.nan]
    assert (
        _by_check(outgoing_speed_checks(p0v, Fraction(1, 2), 8)).loc[
            "p0v_largest_relative_error", "value"
        ]
        == np.inf
    )


def test_validation_names_the_same_bin_of_equal_worst_values_in_any_order_of_the_bins():
    """Two empty bins in 0.01 <= v <= 5 (infinite relative errors, an exact tie): the row
    names the one of the smaller v, with the bins in order and reversed."""
    rng = np.random.default_rng(16)
    p0v, _ = _simulated_bins(Fraction(1, 2), 0.01, rng)
    inside = p0v.index[(p0v.v >= 0.01) & (p0v.v <= 5.0)]
    p0v.loc[[inside[8], inside[4]], ["p0v", "p0v_err"]] = [0.0, np.nan]
    for table in (p0v, p0v.iloc[::-1].reset_index(drop=True)):
        row = _by_check(outgoing_speed_checks(table, Fraction(1, 2), shards=8)).loc[
            "p0v_largest_relative_error"
        ]
        assert row.value == np.inf and row.bin_centre == p0v.loc[inside[4], "v"]


def _collision_counted_bins(restitution, collisions, rng, lo=1e-4, hi=1e3):
    """Bins of P(0, v) ~ v^-beta e^(-q v) from Poisson counts of ``collisions`` collisions
    (a bin's collisions come at the rate v P(0, v) dv, eq. (collrate)), with the errors of the
    counts; an empty bin has p0v 0 and no error, as in a merged table."""
    from bouncing_ball import fits

    (beta,) = fits.theory_exponents(fits.SMALL_SPEED, float(restitution))
    q = fits.theory_exponents(fits.LARGE_SPEED, float(restitution))[1]
    edges = np.geomspace(lo, hi, int(round(10 * np.log10(hi / lo))) + 1)
    lower, upper = edges[:-1], edges[1:]
    shape = fits.bin_average(fits.large_speed_form, lower, upper, 0.0, beta, q)
    weight = shape * 0.5 * (upper**2 - lower**2)
    counts = rng.poisson(collisions * weight / weight.sum())
    density = counts / (0.5 * (upper**2 - lower**2))
    with np.errstate(divide="ignore", invalid="ignore"):
        errors = np.where(counts > 0, density / np.sqrt(counts), np.nan)
    return pd.DataFrame(
        {
            "v_lo": lower,
            "v_hi": upper,
            "v": np.sqrt(lower * upper),
            "p0v": density,
            "p0v_err": errors,
            "count": counts,
        }
    ), pd.DataFrame({"v": np.sqrt(lower * upper), "p0v": shape})


def test_the_relative_error_window_follows_the_speeds_of_r():
    """At r = 0.99 the window 0.01 <= v <= 5 sat in the far low-speed tail (speeds scale like
    1/q, q = 0.0151) and the row read inf from its empty bins.  1.2e7 collisions (the default
    run at r = 0.99) fill every bin of 0.01 <= q v <= 5 = 0.66 <= v <= 330, where the largest
    relative error is that of the rarest bin, about 1/sqrt(its count)."""
    restitution = Fraction(99, 100)
    low, high = quality_speeds(restitution)
    assert (low, high) == pytest.approx((0.01 / 0.015149984850015164, 5 / 0.015149984850015164))
    p0v, curve = _collision_counted_bins(restitution, 1.2e7, np.random.default_rng(17))
    row = _by_check(outgoing_speed_checks(p0v, restitution, 8, solver_curve=curve)).loc[
        "p0v_largest_relative_error"
    ]
    inside = p0v[(p0v.v >= low) & (p0v.v <= high)]
    assert row.bins == len(inside) > 0
    rarest = 1.0 / np.sqrt(inside["count"].min())
    assert np.isfinite(row.value) and row.value == pytest.approx(rarest, rel=1e-12)
    assert "0.66 <= v <= 330 (0.01 <= q v <= 5, q = 0.01515" in row.detail
    markdown = validation_markdown(
        validation_table([{**row.to_dict(), "r_label": "0.99", "r": 0.99, "check": row.name}])
    )
    assert "largest relative error, 0.01 <= q v <= 5 (0.66 <= v <= 330)" in markdown
    # a run with no bin in the window: NaN, and the row says why
    below = p0v[p0v.v_hi < 0.5]
    row = _by_check(outgoing_speed_checks(below, restitution, 8, solver_curve=curve)).loc[
        "p0v_largest_relative_error"
    ]
    assert np.isnan(row.value) and "no bin with its centre in 0.66 <= v <= 330" in row.detail
    assert "the bins span 0.0001 <= v <= 0.398" in row.detail
    # a short run (6e4 collisions, 8 shards of 2e6): an infinite error says it is empty bins
    short, _ = _collision_counted_bins(restitution, 6e4, np.random.default_rng(18))
    row = _by_check(outgoing_speed_checks(short, restitution, 8, solver_curve=curve)).loc[
        "p0v_largest_relative_error"
    ]
    if not np.isfinite(row.value):
        assert "without a collision or an error" in row.detail


def test_validation_at_an_r_without_exact_solution_uses_the_solver_and_skips_p_x():
    """At r = 0.6 the reference of P(0, v) is the solver's curve (here a curve 1% high, which
    the residuals must show); there is no P(x) row."""
    rng = np.random.default_rng(14)
    restitution = Fraction(1, 2)
    p0v, _ = _simulated_bins(restitution, 0.01, rng, lo=1e-4, hi=100.0)
    speeds = np.geomspace(1e-4, 50.0, 401)
    curve = pd.DataFrame(
        {"v": speeds, "p0v": 1.01 * exact.outgoing_speed_density(speeds, restitution)}
    )
    rows = _by_check(
        validation_rows("0.6", Fraction(3, 5), p0v, None, _fits_table(), 4, solver_curve=curve)
    )
    assert not any(check.startswith(("px", "v2")) for check in rows.index)
    speeds_row = rows.loc["p0v_chi2_per_bin"]
    assert speeds_row.reference == "solver"
    assert speeds_row.value > 1.5  # a 1-sigma shift doubles chi^2/n
    with pytest.raises(ValueError, match="no exact"):
        outgoing_speed_checks(p0v, Fraction(3, 5), 4)


def test_validation_fit_rows_and_markdown():
    rows = _by_check(fit_checks(_fits_table(joint_p=0.37, chi2=1.25), shards=16))
    assert list(rows.index) == [
        "small_speed_fit_joint_p_value",
        "small_speed_fit_chi2_per_dof",
        "large_speed_fit_joint_p_value",
        "large_speed_fit_chi2_per_dof",
    ]
    assert rows.loc["large_speed_fit_joint_p_value", "value"] == 0.37
    assert rows.loc["large_speed_fit_chi2_per_dof", "value"] == 1.25
    assert rows.loc["large_speed_fit_chi2_per_dof", "bins"] == 13  # 10 dof + 3 parameters
    assert "m = 1.020 ± 0.030 (theory 1)" in rows.loc["large_speed_fit_joint_p_value", "detail"]
    rng = np.random.default_rng(15)
    p0v, _ = _simulated_bins(Fraction(1, 2), 0.01, rng)
    table = validation_table(
        validation_rows(
            "0.5", Fraction(1, 2), p0v, _position_bins(Fraction(1, 2), 0.01, rng), _fits_table(), 3
        )
    )
    assert table.p_sign_flip.isna().all()
    markdown = validation_markdown(table)
    assert markdown.count("\n") == len(table) + 2
    assert "P(0,v): largest relative error, 0.01 <= q v <= 5 (0.01 <= v <= 5)" in markdown
    assert "| 1%" in markdown
    # one column separator per column and edge on every line: no '|' inside a cell
    assert {line.count("|") for line in markdown.splitlines()} == {9}


def test_validation_fit_rows_say_why_a_joint_p_value_is_missing():
    fits = _fits_table()
    fits.loc[fits.window == "large_speed", "joint_p_value"] = np.nan  # 2 shards, 2 exponents
    fits.loc[fits.window == "small_speed", ["joint_p_value", "chi2_per_dof", "dof"]] = np.nan
    fits.loc[fits.window == "small_speed", ["v_min", "v_max"]] = np.nan  # no usable window
    rows = _by_check(fit_checks(fits, shards=2))
    assert "too few shards" in rows.loc["large_speed_fit_joint_p_value", "detail"]
    assert rows.loc["small_speed_fit_joint_p_value", "detail"].startswith("no usable window")
    fits.loc[fits.window == "small_speed", ["value", "error"]] = np.nan
    detail = _by_check(fit_checks(fits, shards=2)).loc["small_speed_fit_joint_p_value", "detail"]
    assert detail == "no usable window (the fit's log says why); theory beta = 1"
    assert rows.loc["small_speed_fit_chi2_per_dof", "bins"] == 0
    assert np.isnan(rows.loc["small_speed_fit_chi2_per_dof", "value"])


def _fits_at_099(time):
    """The fits of 16 synthetic shards of P(0, v) = A v^-m e^(-q v) at r = 0.99 (the theory's
    m = 2e-4, q = 0.0151, A from I = 0.00377) over 1.26 <= v <= 39.8, as a run near r = 1 has
    them: no small speeds, both auto windows from the lowest bin, and a curve whose e^(-q v)
    passes, fitted with a free beta, for a power law."""
    from fit_support import _bins, synthetic_shards

    from bouncing_ball import fits
    from bouncing_ball.estimators import jackknife, outgoing_speed_density

    m, q = fits.theory_exponents(fits.LARGE_SPEED, 0.99)
    truth = (np.log(0.00377 * q**2), m, q)
    edges = np.geomspace(10**0.1, 10**1.6, 16)
    lower, upper = _bins(edges)
    counts, times = synthetic_shards(np.random.default_rng(5), fits.LARGE_SPEED, truth, edges, time)
    _, errors = jackknife(lambda c, t: outgoing_speed_density(c, t, lower, upper), counts, times)
    reference = fits.bin_average(fits.large_speed_form, lower, upper, *truth)
    windows = dict.fromkeys((fits.SMALL_SPEED, fits.LARGE_SPEED), "auto")
    table, problems = fits.asymptotic_fits(
        lower, upper, counts, times, errors, reference, 0.99, windows
    )
    assert problems == []
    return table, len(times)


def test_fits_that_test_nothing_are_not_counted_as_checks():
    """At r = 0.99 the table reported "small-v fit: joint p 0.903" for a window inside the
    large-v one, where beta = 0.011 cannot be told from 0, and a large-v p for q = 0.013 +-
    0.013.  Such rows are "not checked: <why>", their values NaN, what the fit gave kept in
    the detail; an exponent without power beside one with it is named, not counted."""
    table, shards = _fits_at_099(2.0e5)
    rows = _by_check(fit_checks(table, shards))
    small, large = (
        rows.loc["small_speed_fit_joint_p_value"],
        rows.loc["large_speed_fit_joint_p_value"],
    )
    assert np.isnan(small.value) and np.isnan(large.value)
    assert (
        rows.loc[["small_speed_fit_chi2_per_dof", "large_speed_fit_chi2_per_dof"]]
        .value.isna()
        .all()
    )
    assert small.detail.startswith(
        "not checked: its window [1.26, 10] is not below the large-v window [1.26, 39.8]"
    )
    assert "could not reject beta = 0" in small.detail and "joint p 0.541" in small.detail
    assert large.detail.startswith("not checked: no power: ")
    assert "could not reject m = 0" in large.detail and "could not reject q = 0" in large.detail
    markdown = validation_markdown(
        validation_table(
            [{**row, "r_label": "0.99", "r": 0.99} for row in fit_checks(table, shards)]
        )
    )
    assert markdown.count("| not checked |") == 4
    # ten times the time resolves q: the large-v row is a check of q, m named as not tested
    table, shards = _fits_at_099(2.0e6)
    large = _by_check(fit_checks(table, shards)).loc["large_speed_fit_joint_p_value"]
    assert 0.0 < large.value <= 1.0
    assert "not tested: the theory's m = 0.000202" in large.detail
    assert "reject q = 0" not in large.detail


def test_a_window_where_the_form_does_not_hold_on_the_solvers_curve_is_not_checked():
    """A window given by hand (fits.large_speed_window) where the solver's own curve, fitted
    with free exponents, gives m off the theory's by more than max_bias of the data's error."""
    fits = _fits_table()
    drifted = (fits.source == "solver") & (fits.window == "large_speed") & (fits.parameter == "m")
    fits.loc[drifted & (fits.fit == "free_exponents"), "value"] = 1.02  # 0.02 > 0.5 x 0.03
    rows = _by_check(fit_checks(fits, shards=16, max_bias=0.5))
    row = rows.loc["large_speed_fit_joint_p_value"]
    assert np.isnan(row.value)
    assert row.detail.startswith(
        "not checked: the form does not hold over this window: on the solver's curve the free "
        "fit gives m = 1.02 against the theory's 1, more than 0.5 of the data's error 0.03"
    )
    assert rows.loc["small_speed_fit_joint_p_value", "value"] == 0.4  # untouched
    assert (
        _by_check(fit_checks(fits, shards=16, max_bias=1.0)).loc[
            "large_speed_fit_joint_p_value", "value"
        ]
        == 0.4
    )


def _correlated_deviations(rng, shards=16, bins=30, correlation=0.8):
    """Shards x bins of N(0, 1) deviations with correlation ``correlation`` between any two bins
    (a component shared by every bin of a shard, like the shard's normalisation)."""
    shared = rng.standard_normal((shards, 1))
    own = rng.standard_normal((shards, bins))
    return np.sqrt(correlation) * shared + np.sqrt(1.0 - correlation) * own


def test_sign_flip_p_value_is_uniform_under_the_null_on_correlated_bins():
    """400 replicates of 16 shards x 30 bins with a correlation of 0.8 between bins: the
    p-values of chi^2/n fill 10 equal bins of [0, 1] within 4 binomial standard deviations
    each, and pass a KS test of uniformity, while the p-value that treats n chi^2/n as
    chi^2 with n degrees of freedom (independent bins) rejects far more than its level."""
    rng = np.random.default_rng(21)
    replicates = 400
    flipped, independent = [], []
    for _ in range(replicates):
        deviations = _correlated_deviations(rng)
        chi2, p_chi2, p_worst = sign_flip_test(deviations, flips=2000)
        assert 0.0 < p_chi2 <= 1.0 and 0.0 < p_worst <= 1.0
        flipped.append(p_chi2)
        independent.append(stats.chi2.sf(30 * chi2, 30))
    counts, _ = np.histogram(flipped, bins=10, range=(0.0, 1.0))
    share = 0.1
    spread = np.sqrt(replicates * share * (1.0 - share))
    assert np.all(np.abs(counts - replicates * share) < 4.0 * spread), counts
    assert stats.kstest(flipped, "uniform").pvalue > 1e-3
    # the naive p-value: below 0.05 in far more than 5% of the replicates
    assert np.mean(np.array(independent) < 0.05) > 0.05 + 4.0 * np.sqrt(0.05 * 0.95 / replicates)


def test_sign_flip_p_value_is_small_for_a_bias():
    """The same correlated data with a bias of 6 standard errors in every bin: p of chi^2
    below 1e-3 (without the bias, above)."""
    rng = np.random.default_rng(22)
    shards, bins = 16, 30
    deviations = _correlated_deviations(rng, shards, bins)
    _, p_null, _ = sign_flip_test(deviations)
    assert p_null > 1e-3
    standard_error = 1.0 / np.sqrt(shards)  # of a bin's mean over the shards
    _, p_biased, _ = sign_flip_test(deviations + 6.0 * standard_error)
    assert p_biased < 1e-3


@pytest.mark.parametrize("zero_shards", [0, 1])
def test_sign_flip_test_counts_every_pattern_that_ties_with_the_observed_statistic(zero_shards):
    """A shift of 100 standard deviations in every bin of 8 shards: a flipped pattern ties
    with the observed statistic exactly when it gives every shifted shard the same sign (all
    + or all -: z^2 does not see the overall sign; a shard of zero deviations, whatever its
    sign), and every other pattern is far below.  p = (1 + the ties drawn) / (1 + flips),
    on any BLAS."""
    rng = np.random.default_rng(23)
    deviations = _correlated_deviations(rng, 8, 12) + 100.0
    deviations[8 - zero_shards :] = 0.0
    assert sign_flip_test(deviations) == sign_flip_test(deviations)
    # the patterns sign_flip_test draws: one block of 500 from its seed
    signs = np.random.default_rng(SIGN_FLIP_SEED).choice([-1.0, 1.0], size=(500, 8))
    shifted = signs[:, : 8 - zero_shards]
    ties = int(np.sum(np.all(shifted == shifted[:, :1], axis=1)))
    assert ties >= 2  # the draws hold such patterns: the count below is tested
    _, p_chi2, p_worst = sign_flip_test(deviations, flips=500)
    assert p_chi2 == p_worst == (1 + ties) / 501


def test_sign_flip_test_is_the_same_however_the_blas_blocks_the_sums(monkeypatch):
    """The flips in blocks of 1000, 7 and 1 (a matrix product or a vector product, other
    BLAS kernels and roundings): the same statistic and p-values to the last bit."""
    from bouncing_ball.validation import sign_flip

    rng = np.random.default_rng(27)
    deviations = _correlated_deviations(rng, 8, 12) + 100.0
    results = set()
    for block in (1000, 7, 1):
        monkeypatch.setattr(sign_flip, "_FLIPS_PER_BLOCK", block)
        results.add(sign_flip_test(deviations, flips=300))
    assert len(results) == 1


def test_sign_flip_sums_over_shards_are_exact():
    """The deviations as ``_integer_deviations`` rounds them: integers whose sum under any
    signs (here every one of the 2^10 patterns) is the exact integer sum, in any order."""
    from itertools import product

    from bouncing_ball.validation.sign_flip import _integer_deviations

    rng = np.random.default_rng(28)
    deviations = rng.standard_normal((10, 5)) * np.array([1e-300, 1e-8, 1.0, 1e8, 1e300])
    integers = _integer_deviations(deviations)
    # each bin scaled by a power of 2 to a largest |integer| of 52 - ceil(log2(10)) bits and
    # rounded: the integers' ratios are the deviations' to 2^-47
    top = np.max(np.abs(integers), axis=0)
    assert np.all(integers == np.rint(integers)) and np.all((top >= 2.0**47) & (top <= 2.0**48))
    np.testing.assert_array_less(
        np.abs(integers / top - deviations / np.max(np.abs(deviations), axis=0)), 2.0**-47
    )
    signs = np.array(list(product([-1, 1], repeat=10)))
    exact = [
        [sum(int(s) * int(q) for s, q in zip(row, column)) for column in integers.T]
        for row in signs
    ]
    assert np.array_equal(signs.astype(float) @ integers, np.array(exact, dtype=float))
    assert np.array_equal(
        signs[:, ::-1].astype(float) @ integers[::-1], np.array(exact, dtype=float)
    )


@pytest.mark.parametrize(
    "deviations, flips, message",
    [
        (np.ones((1, 3)), 10, "shards >= 2"),
        (np.ones(4), 10, "shards >= 2"),
        (np.array([[1.0, np.nan], [0.0, 1.0]]), 10, "finite"),
        (np.array([[1.0, 2.0], [0.0, 2.0], [3.0, 2.0]]), 10, r"bin\(s\) \[1\]"),
        (np.array([[1.0, 0.0], [0.0, 0.0]]), 10, r"bin\(s\) \[1\]"),
        (np.array([[1.0], [-1.0]]), 0, "flips"),
        (np.array([[1.0], [-1.0]]), 2.5, "flips"),
    ],
)
def test_sign_flip_test_refuses_what_it_cannot_test(deviations, flips, message):
    """No shards to flip, non-finite deviations, a bin without scatter between the shards
    (z is 0/0 or infinite), no flips."""
    with pytest.raises(ValueError, match=message):
        sign_flip_test(deviations, flips=flips)


def test_ratio_deviations_add_up_to_the_merged_estimate_minus_the_reference():
    rng = np.random.default_rng(24)
    numerators, denominators = rng.uniform(1.0, 2.0, (6, 4)), rng.uniform(1.0, 3.0, (6, 4))
    reference = np.array([0.5, 0.6, 0.7, 0.8])
    shares = ratio_deviations(numerators, denominators, reference)
    np.testing.assert_allclose(
        shares.sum(axis=0), numerators.sum(axis=0) / denominators.sum(axis=0) - reference
    )


def _synthetic_shards(restitution, shards, rng, relative_noise=0.04, bias=0.0):
    """Shards (the attributes the merge reads) at the exact P(0, v), P(x) and <v^2>_x of r,
    each bin of each shard off by Gaussian noise of relative size ``relative_noise``; P(0, v)
    scaled by 1 + ``bias``."""
    speed_bins, position_bins = LogBins(1e-3, 10.0, 5), LogBins(1e-3, 1e2, 5)
    v_lo, v_hi = speed_bins.lower[1:-1], speed_bins.upper[1:-1]
    x_lo, x_hi = position_bins.lower[1:-1], position_bins.upper[1:-1]
    p0v = (1.0 + bias) * exact.outgoing_speed_bin_average(v_lo, v_hi, restitution)
    px = exact.position_bin_average(x_lo, x_hi, restitution)
    v2 = exact.speed_squared_given_position_bin_average(x_lo, x_hi, restitution)
    time = 1.0e3

    def noisy(values):
        return values * (1.0 + relative_noise * rng.standard_normal(len(values)))

    def padded(values):  # the under- and overflow bins, as the tallies hold them
        return np.r_[1.0, values, 1.0]

    made = []
    for _ in range(shards):
        in_bin = noisy(time * px * (x_hi - x_lo))
        made.append(
            SimpleNamespace(
                speed_bins=speed_bins,
                position_bins=position_bins,
                time=time,
                speed_counts=padded(noisy(time * p0v * 0.5 * (v_hi**2 - v_lo**2))),
                position_time=padded(in_bin),
                position_v2_time=padded(noisy(in_bin * v2)),
                **dict.fromkeys(RATE_CONTROLS, 0.0),  # control sums that explain nothing
            )
        )
    return made


@pytest.mark.parametrize("restitution", exact.EXACT_RESTITUTIONS)
def test_validation_chi2_rows_get_a_sign_flip_p_value_from_the_shards(restitution):
    """Shards at the exact solution: every chi^2/n row of a plain estimate has a p_sign_flip
    in (0, 1], not below 1e-3, and the sign flips' chi^2/n of the shards' shares is the table's to first
    order; the other rows have none.  P(0, v) 5% high (5 standard errors a bin): its p drops
    below 1e-3."""
    rng = np.random.default_rng(25)
    shards = _synthetic_shards(restitution, 16, rng)
    rows = _by_check(
        validation_rows(
            "label",
            restitution,
            outgoing_speed_histogram(shards),
            position_histogram(shards),
            _fits_table(),
            len(shards),
            per_shard=shard_ratios(shards),
        )
    )
    chi2_rows = [
        check
        for check in rows.index
        if check.endswith("chi2_per_bin")
        and not check.startswith(("p0v_controlled", "p0v_martingale"))
    ]
    assert chi2_rows == ["p0v_chi2_per_bin", "px_chi2_per_bin", "v2_given_x_chi2_per_bin"]
    # the controlled P(0, v)s have no per-shard shares to flip: their rows have no p
    assert {"p0v_controlled_chi2_per_bin", "p0v_martingale_chi2_per_bin"} <= set(rows.index)
    for check in chi2_rows:
        assert 1e-3 < rows.loc[check, "p_sign_flip"] <= 1.0, check
        assert "sign flips of the 16 shards" in rows.loc[check, "detail"]
    assert rows.drop(index=chi2_rows).p_sign_flip.isna().all()
    table = outgoing_speed_histogram(shards)
    usable = np.flatnonzero(
        np.isfinite(table.p0v_err)
        & (table.v_lo > 0)
        & np.isfinite(table.v_hi)
        & (table["count"] >= MINIMUM_BIN_COUNT)
    )
    numerators, denominators = shard_ratios(shards)["p0v"]
    reference = exact.outgoing_speed_bin_average(
        table.v_lo.to_numpy()[usable], table.v_hi.to_numpy()[usable], restitution
    )
    chi2, _, _ = sign_flip_test(
        ratio_deviations(numerators[:, usable], denominators[:, usable], reference)
    )
    assert chi2 == pytest.approx(rows.loc["p0v_chi2_per_bin", "value"], rel=0.1)
    biased = _synthetic_shards(restitution, 16, np.random.default_rng(25), bias=0.05)
    p0v_rows = _by_check(
        outgoing_speed_checks(
            outgoing_speed_histogram(biased),
            restitution,
            len(biased),
            per_shard=shard_ratios(biased),
        )
    )
    assert p0v_rows.loc["p0v_chi2_per_bin", "p_sign_flip"] < 1e-3


def test_validation_refuses_tallies_of_another_number_of_shards():
    rng = np.random.default_rng(26)
    shards = _synthetic_shards(Fraction(1, 2), 4, rng)
    with pytest.raises(ValueError, match="tallies of 4 shards for a table of 5 shards"):
        outgoing_speed_checks(
            outgoing_speed_histogram(shards), Fraction(1, 2), 5, per_shard=shard_ratios(shards)
        )


def _validation_inputs(permutation_seed=None):
    """The arguments of ``validation_rows`` for 16 synthetic shards at r = 1/2, the bins of
    the merged tables and of the shards' tallies shuffled alike by ``permutation_seed``
    (None: in order)."""
    restitution = Fraction(1, 2)
    shards = _synthetic_shards(restitution, 16, np.random.default_rng(29))
    p0v, position = outgoing_speed_histogram(shards), position_histogram(shards)
    per_shard = shard_ratios(shards)
    if permutation_seed is not None:
        order = np.random.default_rng(permutation_seed)
        speeds, heights = order.permutation(len(p0v)), order.permutation(len(position))
        p0v = p0v.iloc[speeds].reset_index(drop=True)
        position = position.iloc[heights].reset_index(drop=True)
        columns = {"p0v": speeds, "px": heights, "v2_given_x": heights}
        per_shard = {
            key: tuple(part[:, columns[key]] for part in parts) for key, parts in per_shard.items()
        }
    return ("0.5", restitution, p0v, position, _fits_table(), len(shards), None, per_shard)


def _numbers(rows):
    """The validation rows' value, bin_centre and p_sign_flip, to the last bit (float.hex)."""
    return {
        row["check"]: [float(row[key]).hex() for key in ("value", "bin_centre", "p_sign_flip")]
        for row in rows
    }


def test_validation_numbers_do_not_depend_on_the_order_of_the_bins_nor_the_blas_threads(
    tmp_path,
):
    """The table's chi^2/n, worst z and its bin, p_sign_flip, ... to the last bit: with the
    bins in order, shuffled twice, and computed in a process with another number of BLAS
    threads (2 where this one has 1, else 1)."""
    import os
    import pickle
    import subprocess
    import sys

    arguments = tmp_path / "arguments.pickle"
    arguments.write_bytes(pickle.dumps(_validation_inputs()))
    threads = "2" if os.environ.get("OPENBLAS_NUM_THREADS") == "1" else "1"
    other = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import pickle, sys\n"
            "from bouncing_ball.validation import validation_rows\n"
            f"arguments = pickle.loads(open({str(arguments)!r}, 'rb').read())\n"
            "sys.stdout.buffer.write(pickle.dumps(validation_rows(*arguments)))\n",
        ],
        env=dict(
            os.environ,
            OPENBLAS_NUM_THREADS=threads,
            OMP_NUM_THREADS=threads,
            MKL_NUM_THREADS=threads,
        ),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    in_order = _numbers(validation_rows(*_validation_inputs()))
    flipped = [p for _, _, p in in_order.values() if p != float("nan").hex()]
    assert len(flipped) == 3  # P(0, v), P(x), <v^2>_x
    for seed in (30, 31):
        assert _numbers(validation_rows(*_validation_inputs(seed))) == in_order, seed
    out, err = other.communicate(timeout=120)
    assert other.returncode == 0, err.decode()
    assert _numbers(pickle.loads(out)) == in_order
