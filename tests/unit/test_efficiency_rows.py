"""The benchmark's efficiency table (benchmarks/efficiency.py) from made-up measurements: no
shard is run here."""

import numpy as np
import pytest

from benchmarks.efficiency import ESTIMATORS, OBSERVABLES, efficiency_rows


def fake_measurements():
    """Relative squared errors (value, error) per observable; CPU seconds per estimator."""
    measurements = {}
    for r, scale in ((0.25, 1.0), (0.75, 3.0)):
        for estimator, factor, cpu in (("paper", 8.0, 10.0), ("default", 1.0, 5.0)):
            measurements[(estimator, r)] = {
                "cpu_seconds": cpu,
                "relative_squared_errors": {
                    name: (scale * factor * (k + 1) * 1e-6, 0.25 * scale * factor * (k + 1) * 1e-6)
                    for k, name in enumerate(OBSERVABLES)
                },
            }
    return measurements


def test_one_row_per_observable_and_r_with_the_documented_keys():
    rows = efficiency_rows(fake_measurements())
    assert [(row["observable"], row["r"]) for row in rows] == [
        (name, r) for name in OBSERVABLES for r in (0.25, 0.75)
    ]
    assert all({"observable", "r", *ESTIMATORS, "gain"} <= set(row) for row in rows)


def test_efficiency_is_relative_squared_error_times_cpu_and_gain_is_their_ratio():
    rows = {(row["observable"], row["r"]): row for row in efficiency_rows(fake_measurements())}
    row = rows[("Delta x", 0.75)]  # the third observable: (k + 1) = 3, scale 3
    assert row["paper"] == pytest.approx(3.0 * 8.0 * 3 * 1e-6 * 10.0)
    assert row["default"] == pytest.approx(3.0 * 1.0 * 3 * 1e-6 * 5.0)
    assert row["gain"] == pytest.approx(16.0)  # 8 times the error^2 at twice the CPU
    # each relative uncertainty is 1/4; the gain's adds them in quadrature
    assert row["paper_err"] == pytest.approx(0.25 * row["paper"])
    assert row["gain_err"] == pytest.approx(16.0 * np.hypot(0.25, 0.25))


def test_a_missing_estimator_is_an_error():
    measurements = fake_measurements()
    del measurements[("default", 0.25)]
    with pytest.raises(KeyError):
        efficiency_rows(measurements)
