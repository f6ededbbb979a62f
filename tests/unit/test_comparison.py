"""The comparison of simulation, solver and exact results: z-scores, residuals, the paper's numbers."""

from fractions import Fraction

import numpy as np
import pandas as pd
import pytest

from bouncing_ball import exact
from bouncing_ball.comparison import (
    PAPER_VALUES,
    moment_rows,
    moments_markdown,
    moments_table,
    outgoing_speed_residuals,
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
