"""The comparison of simulation, solver and exact results: z-scores, residuals, the paper's numbers."""

from fractions import Fraction

import numpy as np
import pandas as pd
import pytest

from bouncing_ball import exact
from bouncing_ball.comparison import (
    PAPER_VALUES,
    VALIDATION_CHECKS,
    fit_checks,
    moment_rows,
    moments_markdown,
    moments_table,
    outgoing_speed_checks,
    outgoing_speed_residuals,
    validation_markdown,
    validation_rows,
    validation_table,
    value_with_error,
)


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
        }
    )
    frame.loc[5, ["p0v", "p0v_err", "count"]] = [0.0, np.nan, 0]
    edge_rows = pd.DataFrame(
        {
            "v_lo": [0.0, hi],
            "v_hi": [lo, np.inf],
            "v": [lo / 2, np.inf],
            "p0v": [1.0, np.nan],
            "p0v_err": [0.1, np.nan],
            "count": [10, 0],
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
            "count": 10,
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
                            "value": 1.02,
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
    rows = _by_check(validation_rows("label", restitution, p0v, position, _fits_table(), shards=16))
    assert list(rows.index) == list(VALIDATION_CHECKS)
    assert (rows.r_label == "label").all() and (rows.r == float(restitution)).all()
    speeds = rows.loc["p0v_chi2_per_bin"]
    assert speeds.reference == "exact" and speeds.bins == len(p0v) - 3
    assert speeds.expected == pytest.approx(15.0 / 13.0)
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
    assert speeds_row.reference == "solver" and speeds_row.expected == pytest.approx(3.0)
    assert speeds_row.value > 1.5  # a 1-sigma shift doubles chi^2/n
    with pytest.raises(ValueError, match="no exact"):
        outgoing_speed_checks(p0v, Fraction(3, 5), 4)


def test_validation_fit_rows_and_markdown():
    rows = _by_check(fit_checks(_fits_table(joint_p=0.37, chi2=1.25)))
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
    assert np.isnan(table.set_index("check").loc["p0v_chi2_per_bin", "expected"])
    markdown = validation_markdown(table)
    assert markdown.count("\n") == len(table) + 2
    assert "P(0,v): largest relative error, 0.01 <= v <= 5" in markdown and "| 1%" in markdown
    # one column separator per column and edge on every line: no '|' inside a cell
    assert {line.count("|") for line in markdown.splitlines()} == {9}


def test_validation_fit_rows_say_why_a_joint_p_value_is_missing():
    fits = _fits_table()
    fits.loc[fits.window == "large_speed", "joint_p_value"] = np.nan  # 2 shards, 2 exponents
    fits.loc[fits.window == "small_speed", ["joint_p_value", "chi2_per_dof", "dof"]] = np.nan
    fits.loc[fits.window == "small_speed", ["v_min", "v_max"]] = np.nan  # no usable window
    rows = _by_check(fit_checks(fits))
    assert "too few shards" in rows.loc["large_speed_fit_joint_p_value", "detail"]
    assert rows.loc["small_speed_fit_joint_p_value", "detail"].startswith("no usable window")
    assert rows.loc["small_speed_fit_chi2_per_dof", "bins"] == 0
    assert np.isnan(rows.loc["small_speed_fit_chi2_per_dof", "value"])
