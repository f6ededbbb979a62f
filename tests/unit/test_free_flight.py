"""Free flight: eqs. (xstep), (vstep), (criterion) and the bridge between step ends,
deterministically (the sampled moments are tests/statistical/test_free_flight_moments.py)."""

import numpy as np
import pytest

from bouncing_ball.free_flight import (
    free_flight_step,
    hermite_cubic,
    largest_safe_step,
    mean_path_integrals,
    whole_step_integrals,
)


def _criterion(x, v, c, step):
    """Left side of eq. (criterion)."""
    return x + v * step - 0.5 * step**2 - c * step**1.5


@pytest.mark.parametrize("c", [3.0, 5.0])
def test_warm_started_root_is_the_cold_root(c):
    """criterion_root from the simulation's warm starts (a previous root, 30 % off either
    way, a start left of the maximum of f, a start of 0) gives the cold start's root to
    the iteration's accuracy, with f'(s*) < 0."""
    from bouncing_ball.free_flight import criterion_root

    rng = np.random.default_rng(2)
    for x, v in zip(10 ** rng.uniform(-8, 3, 300), rng.normal(0, 3, 300)):
        cold, slope = criterion_root(x, v, c, 0.0)
        assert slope < 0.0
        for start in (0.7 * cold, 1.3 * cold, 1e-3 * cold, 30.0 * cold):
            warm, _ = criterion_root(x, v, c, start)
            assert warm == pytest.approx(cold, rel=1e-10)


@pytest.mark.parametrize("c", [3.0, 5.0, 8.0])
def test_largest_safe_step_is_the_root_of_the_criterion(c):
    rng = np.random.default_rng(1)
    for x, v in zip(10 ** rng.uniform(-8, 3, 400), rng.normal(0, 3, 400)):
        step = largest_safe_step(x, v, c)
        assert step > 0
        assert abs(_criterion(x, v, c, step)) <= 1e-10 * max(x, abs(v) * step, step**1.5 * c)
        assert _criterion(x, v, c, 0.999 * step) > 0  # allowed just below
        assert _criterion(x, v, c, 1.001 * step) < 0  # refused just above
    assert largest_safe_step(0.0, -1.0, c) == 0.0
    assert largest_safe_step(1e-320, 2.0, c) == largest_safe_step(0.0, 2.0, c)  # subnormal: 0
    # at x = 0 the root is that of v - c s - s^2/2 = 0
    assert largest_safe_step(0.0, 2.0, c) == pytest.approx(
        (np.sqrt(c * c + 4.0) - c) ** 2, rel=1e-12
    )


def test_level_crossing_time_is_the_root_to_rounding():
    """cubic_level_time against scipy's brentq on monotone pieces of random bridge paths,
    including nearly linear ones (one Halley step), pieces ending at a slope zero, and levels
    within 1e-5 .. 1e-9 of a piece's end value (where m' may be nearly 0): the path at the
    returned time is at the level to 1e-8 of the piece's range (or to rounding of x), and
    where the root is well conditioned the time itself is right to 1e-8 of the piece (the
    iteration stops once a Halley step is below 1e-3 of the piece, leaving ~1e-9)."""
    from scipy.optimize import brentq

    from bouncing_ball.free_flight import (
        cubic_level_time,
        cubic_slope,
        cubic_value,
        monotone_piece_end,
        slope_zeros,
    )

    rng = np.random.default_rng(3)
    near_ends = [1e-5, 1e-7, 1e-9, 1 - 1e-5, 1 - 1e-7, 1 - 1e-9]
    worst_value = worst_time = 0.0
    checked = 0
    for trial in range(3000):
        dt = 10 ** rng.uniform(-6, 0.5)
        x0 = 10 ** rng.uniform(-4, 1)
        v0 = rng.normal(0, 2)
        x1, v1 = free_flight_step(x0, v0, dt, rng.normal(), rng.normal())
        a = hermite_cubic(x0, v0, x1, v1, dt)
        n, t1, t2 = slope_zeros(a[1], a[2], a[3], dt)
        start = 0.0
        for piece in range(n + 1):
            stop = monotone_piece_end(piece, n, t1, t2, dt)
            m_lo, m_hi = cubic_value(*a, start), cubic_value(*a, stop)
            fraction = near_ends[trial % 6] if trial % 2 else rng.uniform(0.01, 0.99)
            level = m_lo + fraction * (m_hi - m_lo)
            if m_hi != m_lo and level not in (m_lo, m_hi):
                slopes = cubic_slope(*a[1:], start), cubic_slope(*a[1:], stop)
                t = cubic_level_time(*a, level, start, stop, m_lo, m_hi, *slopes)
                rounding = 8e-16 * max(abs(m_lo), abs(m_hi))
                residual = abs(cubic_value(*a, t) - level) / (1e-8 * abs(m_hi - m_lo) + rounding)
                worst_value = max(worst_value, residual)
                if 0.01 <= fraction <= 0.99:
                    exact = brentq(
                        lambda s, a=a, level=level: cubic_value(*a, s) - level,
                        start,
                        stop,
                        xtol=1e-300,
                        rtol=1e-15,
                    )
                    # the level is known only to rounding of x: that sets how well t can be known
                    conditioning = 4e-16 * max(abs(m_lo), abs(m_hi)) / abs(m_hi - m_lo)
                    worst_time = max(
                        worst_time, abs(t - exact) / (stop - start) / (1e-8 + conditioning)
                    )
                checked += 1
            start = stop
    assert checked > 3000
    assert worst_value < 1.0
    assert worst_time < 1.0


def test_a_grazing_crossing_has_the_right_impact_speed():
    """m(t) = (t - 1)^2 - 1e-7 on [0, 1]: the path grazes the floor; the crossing is at
    1 - sqrt(1e-7), where the slope (the impact speed) is -2 sqrt(1e-7), though m' -> 0 at t = 1."""
    from bouncing_ball.free_flight import cubic_level_time, cubic_slope

    depth = 1e-7
    a = (1.0 - depth, -2.0, 1.0, 0.0)
    t = cubic_level_time(*a, 0.0, 0.0, 1.0, a[0], -depth, -2.0, 0.0)
    assert t == pytest.approx(
        1.0 - np.sqrt(depth), abs=1e-10
    )  # bisection stops at 1e-10 of the piece
    assert cubic_slope(*a[1:], t) == pytest.approx(-2.0 * np.sqrt(depth), rel=1e-6)


def test_whole_step_integrals_are_the_mean_path_integrals_over_the_step():
    """The Hermite mass matrix of the ends gives mean_path_integrals at tau = dt, to rounding,
    over states and steps from the floor to far above it."""
    rng = np.random.default_rng(8)
    for _ in range(2000):
        x0, x1 = rng.uniform(0.0, 5.0, 2) ** 2
        v0, v1 = rng.normal(0.0, 2.0, 2)
        dt = 10.0 ** rng.uniform(-8.0, 0.5)
        expected = mean_path_integrals(*hermite_cubic(x0, v0, x1, v1, dt), dt, dt)
        got = whole_step_integrals(x0, v0, x1, v1, dt)
        # the terms cancel at most by the size of the largest one: rounding of that size
        scale_x = dt * (abs(x0) + abs(x1) + dt * (abs(v0) + abs(v1)))
        scale_x2 = dt * (x0 + x1 + dt * (abs(v0) + abs(v1)) + dt * dt) ** 2
        assert got[0] == pytest.approx(expected[0], rel=0, abs=1e-13 * scale_x)
        assert got[1] == pytest.approx(expected[1], rel=0, abs=1e-13 * scale_x2)


def _same(first, second):
    return np.array_equal(np.asarray(first, dtype=float), np.asarray(second, dtype=float))


def test_the_compiled_step_does_the_written_arithmetic():
    """The compiled update, root and start, and whole-step integrals give the doubles of their
    Python functions (``py_func``, fma rounded from the exact product and sum): the compiler
    fuses, contracts or reorders nothing but the source's own fused multiply-adds, so a step
    is the same on every machine (and in the C reference, which calls fma() at those places)."""
    from bouncing_ball.free_flight import (
        _householder_root,
        criterion_root,
        predicted_start,
        root_predictor,
    )

    rng = np.random.default_rng(5)
    for x, v in zip(10 ** rng.uniform(-6, 2, 200), rng.normal(0.0, 2.0, 200)):
        normal_r, normal_s = rng.normal(size=2)
        root, slope = criterion_root(x, v, 5.0, 0.0)
        # the iteration itself in Python (criterion_root.py_func calls the compiled one)
        for start in (0.7 * root, 1.3 * root):
            iterated = _householder_root(x, v, 5.0, start, 60)
            assert _same(iterated, _householder_root.py_func(x, v, 5.0, start, 60))
        dt = root * root + 1e-6
        step = free_flight_step(x, v, dt, normal_r, normal_s)
        assert _same(step, free_flight_step.py_func(x, v, dt, normal_r, normal_s))
        predictor = root_predictor(root, slope, x, v)
        assert _same(predictor, root_predictor.py_func(root, slope, x, v))
        start = predicted_start(predictor, root, *step)
        assert start == predicted_start.py_func(predictor, root, *step)
        integrals = whole_step_integrals(x, v, *step, dt)
        assert _same(integrals, whole_step_integrals.py_func(x, v, *step, dt))
