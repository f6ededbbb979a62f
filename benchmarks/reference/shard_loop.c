/*
 * shard_loop.c -- a plain C99 reference implementation of one simulation shard.
 *
 * What it is: a line-by-line translation of the numba-compiled shard loop
 * ``bouncing_ball.simulation._run`` and of every numba function it calls:
 *
 *   bouncing_ball/free_flight.py: free_flight_step, _floor_root, _fitted_root,
 *       criterion_root, hermite_cubic, cubic_value, cubic_slope,
 *       mean_path_integrals, whole_step_integrals, speed_squared_coefficients,
 *       quintic_antiderivative_value, piece_inverse, level_time_estimate,
 *       level_time_one_step, level_time, cubic_level_time, slope_zeros,
 *       monotone_piece_end, first_crossing_time, bridge_sample,
 *       bridge_speed_squared_given_position
 *   bouncing_ball/simulation/step_tallies.py: _bin_index, _log_bin_index, _linear_bin_index,
 *       _walked_bin_index, _tally_position, _tally_step, _bridge_correction, floor_stratum_end,
 *       _tally_second_bridge_point
 *   bouncing_ball/simulation/loop.py: _run
 *
 * (translated from the committed versions of those files).  Every floating-point
 * operation is the same as in the Python source and in the same order (same
 * parenthesisation, same constants, ``np.cbrt`` -> cbrt, ``math.log`` -> log,
 * Python's min/max -> py_min/py_max, which keep Python's choice between equal
 * arguments, ``jit.fma`` -> fma, the correctly rounded fused multiply-add both
 * give), so with the compiler's own contraction switched off (numba fuses a
 * multiply-add only where the source calls ``fma``) it gives bit-identical
 * tallies.  Where Python returns a tuple
 * the C returns a struct (piece_inverse) or the first value with the second
 * through a pointer (tally_position and tally_step, whose (k, k_s, k_s2) are the
 * bin of the step's end and the bins its mean-path assignment gives the bridge
 * points' times s, s2; criterion_root, whose (s*, f'(s*)) the loop carries from
 * step to step as root, slope_at_root, with the predictor k0, k1, k2 of the next
 * step's start computed before the step, as in ``_run``; free_flight.root_predictor
 * and predicted_start are written out inline in the loop).  ``_run``'s last
 * argument ``parts`` (a bitmask of the tallies, for the benchmark's breakdown)
 * has no counterpart: this loop always records everything, i.e. it is
 * ``_run`` with parts = EVERY_TALLY, which is what ``simulate_shard`` passes
 * by default; in particular the bridge point is drawn before the P(x) tally,
 * which uses it for its bridge correction, and P(x, v) takes its x cell from
 * that correction's walk (``_walked_bin_index``), not from ``_bin_index``.
 * The normals come from numpy's own C generator,
 * ``random_standard_normal`` of libnpyrandom.a, called on the bit generator that
 * Python passes in (``np.random.PCG64(seed).ctypes.bit_generator``), i.e. the
 * same ziggurat that ``pcg64.standard_normal`` ports, on the same stream
 * (which the numba loop advances inline, ``pcg64.next_uint64``).  The bridge
 * point's draws (a uniform and two normals per recorded step) come likewise from
 * a second bit generator, ``tallies.tally_seed_sequence``'s, with numpy's
 * ``random_standard_uniform`` (= ``pcg64.next_double``).
 *
 * What it is for: the yardstick of the performance target "the numba simulation
 * runs at >= 90 % of the speed of a plain C implementation of the same loop
 * (gcc -O3, a fast generator)", and a cross-check of the compiled loop.  It is
 * not used by the workflow.
 *
 * How it is built and run: ``benchmarks.reference_loop.build()`` compiles it with
 *
 *   gcc -O3 -march=native -ffp-contract=off -fPIC -shared -std=c99
 *       -I<numpy.get_include()> -I<Python include> shard_loop.c
 *       <numpy>/random/lib/libnpyrandom.a -lm -o shard_loop.so
 *
 * into a cache folder keyed on this file's hash and the flags, and
 * ``reference_loop.reference_shard`` (the arguments of ``simulation.simulate_shard``
 * but ``parts``, and the library) calls ``bouncing_ball_shard_loop`` via ctypes.
 * No allocation happens inside the loop (the two bin-bound arrays are
 * allocated once before it, as np.empty is in ``_run``).
 */

#include "numpy/random/distributions.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

/* free_flight.py constants */
#define SQRT3 0x1.bb67ae8584caap+0    /* math.sqrt(3.0) */
#define SQRT1_12 0x1.279a74590331cp-2 /* math.sqrt(1.0 / 12.0) */
#define SQRT2_3 0x1.a20bd700c2c3ep-1  /* math.sqrt(2.0 / 3.0) */
#define SQRT3_2 0x1.3988e1409212ep+0  /* math.sqrt(1.5) */
#define SQRT1_2 0x1.6a09e667f3bcdp-1  /* math.sqrt(0.5) */
#define FIT_P 0.44356066
#define FIT_Q 0.56163652
#define FIT_N1 0.40104058
#define FIT_N2 0.00211799
#define FIT_N3 0.06071102
#define SMALLEST_NORMAL DBL_MIN /* np.finfo(np.float64).tiny */
#define ROOT_TOLERANCE 2.0e-3

/* simulation/loop.py, simulation/step_tallies.py */
#define COLLAPSED_STEP 1.0e-80
#define FLOOR_STRATUM_HEIGHT 0.1
/* the layout of the scalars (bouncing_ball.tallies.SCALARS, its one definition):
   benchmarks/reference_loop.py defines SCALAR_<NAME> as the index of each when it compiles
   this file (-DSCALAR_TIME=0 ...), and EARLY_FRACTION as tallies.EARLY_FRACTION */
#if !defined(SCALAR_TIME) || !defined(EARLY_FRACTION)
#error "compile with benchmarks.reference_loop.build(), which passes the scalars' layout"
#endif

/* Python's min(a, b) and max(a, b) on floats, as numba compiles them */
static inline double py_min(double a, double b) { return b < a ? b : a; }
static inline double py_max(double a, double b) { return b > a ? b : a; }

/* ---------------------------------------------------------------- free_flight.py */

static inline void free_flight_step(double x, double v, double dt, double normal_r, double normal_s,
                                    double *x_new, double *v_new)
{
    double root_2dt = sqrt(2.0 * dt);
    double position_noise = SQRT1_12 * fma(SQRT3, normal_r, normal_s);
    *x_new = fma(dt, fma(root_2dt, position_noise, fma(-0.5, dt, v)), x);
    *v_new = fma(root_2dt, normal_r, v - dt);
}

/* _floor_root: s* at x = 0, the root of s^2 (v - c s - s^2/2), 0 for v <= 0 */
static inline double floor_root(double v, double c)
{
    if (v <= 0.0)
        return 0.0;
    return 2.0 * v / (c + sqrt(c * c + 2.0 * v));
}

/* _fitted_root: the root of the cubic x + v s^2 - c s^3 from the rational fits; x > 0 */
static inline double fitted_root(double x, double v, double c)
{
    double a3 = x / c;
    double a = cbrt(a3);
    double b = v / c;
    double a2 = a * a;
    if (b >= 0.0) {
        return b + a * ((a3 + FIT_P * a2 * b)
                        / (a3 + b * (a2 * (FIT_P + 2.0 / 3.0) + b * (FIT_Q * a + FIT_P * b))));
    }
    return sqrt(a3 / (-b + a2 * (a - FIT_N3 * b) / (a2 - b * (FIT_N1 * a - FIT_N2 * b))));
}

/* criterion_root: returns the positive root s* of f(s) = x + v s^2 - c s^3 - s^4/2 and
   sets *slope_out to f'(s*) (Python returns the pair) */
static inline double criterion_root(double x, double v, double c, double start, double *slope_out)
{
    if (x < SMALLEST_NORMAL) {
        double s = floor_root(v, c);
        *slope_out = s * (2.0 * v - s * (3.0 * c + 2.0 * s));
        return s;
    }
    int fitted = !(start > 0.0);
    double s = fitted ? fitted_root(x, v, c) : start;
    int i = 0;
    for (;;) {
        double s2 = s * s;
        double f = fma(s2, fma(-s, fma(0.5, s, c), v), x);
        double f1 = s * fma(-s, fma(2.0, s, 3.0 * c), 2.0 * v);
        if (!(f1 < 0.0) || i == 60) {
            if (fitted) { /* from the fitted start: only on underflow */
                *slope_out = f1;
                return s;
            }
            s = fitted_root(x, v, c);
            fitted = 1;
            i = 0;
            continue;
        }
        double f2 = fma(-s, fma(6.0, s, 6.0 * c), 2.0 * v);
        double f3 = fma(-12.0, s, -6.0 * c);
        double f_f2 = f * f2;
        double six_f1_squared = 6.0 * (f1 * f1);
        double denominator = fma(f1, fma(-6.0, f_f2, six_f1_squared), f * f * f3);
        /* Householder where its denominator is negative, else Newton */
        double step = denominator < 0.0 ? f * fma(-3.0, f_f2, six_f1_squared) / denominator : f / f1;
        i += 1;
        if (!(s - step > 0.0)) { /* overshot past 0: halve instead (f(0) = x > 0) */
            s *= 0.5;
            continue;
        }
        s -= step;
        if (fabs(step) <= ROOT_TOLERANCE * s) {
            *slope_out = f1;
            return s;
        }
    }
}

static inline void hermite_cubic(double x0, double v0, double x1, double v1, double dt,
                                 double *a0, double *a1, double *a2, double *a3)
{
    double inv_dt = 1.0 / dt;
    double slope = (x1 - x0) * inv_dt;
    *a0 = x0;
    *a1 = v0;
    *a2 = (3.0 * slope - 2.0 * v0 - v1) * inv_dt;
    *a3 = (v0 + v1 - 2.0 * slope) * (inv_dt * inv_dt);
}

static inline double cubic_value(double a0, double a1, double a2, double a3, double t)
{
    return fma(t, fma(t, fma(t, a3, a2), a1), a0);
}

static inline double cubic_slope(double a1, double a2, double a3, double t)
{
    return fma(t, fma(3.0 * t, a3, 2.0 * a2), a1);
}

static inline void mean_path_integrals(double a0, double a1, double a2, double a3, double dt,
                                       double tau, double *int_x_out, double *int_x2_out)
{
    double int_x = tau * (a0 + tau * (0.5 * a1 + tau * ((1.0 / 3.0) * a2 + tau * 0.25 * a3)));
    double c0 = a0 * a0;
    double c1 = 2.0 * a0 * a1;
    double c2 = a1 * a1 + 2.0 * a0 * a2;
    double c3 = 2.0 * (a0 * a3 + a1 * a2);
    double c4 = a2 * a2 + 2.0 * a1 * a3;
    double c5 = 2.0 * a2 * a3;
    double c6 = a3 * a3;
    double int_m2 = tau * (
        c0
        + tau
        * (
            0.5 * c1
            + tau
            * (
                (1.0 / 3.0) * c2
                + tau
                * (
                    0.25 * c3
                    + tau * ((1.0 / 5.0) * c4 + tau * ((1.0 / 6.0) * c5 + tau * (1.0 / 7.0) * c6))
                )
            )
        )
    );
    /* int_0^tau 2 t^3 (dt - t)^3 / (3 dt^3) dt */
    double u = tau / dt;
    double tau2 = tau * tau;
    double int_var = (2.0 / 3.0) * tau2 * tau2 * (0.25 - u * (3.0 / 5.0 - u * (0.5 - u * (1.0 / 7.0))));
    *int_x_out = int_x;
    *int_x2_out = int_m2 + int_var;
}

static inline void whole_step_integrals(double x0, double v0, double x1, double v1, double dt,
                                        double *int_x_out, double *int_x2_out)
{
    *int_x_out = dt * fma(dt * (1.0 / 12.0), v0 - v1, 0.5 * (x0 + x1));
    double m0 = fma(13.0 / 35.0, fma(x0, x0, x1 * x1), (9.0 / 35.0) * (x0 * x1));
    double m1 = fma(11.0 / 105.0, fma(x0, v0, -(x1 * v1)), (13.0 / 210.0) * fma(x1, v0, -(x0 * v1)));
    double m2 = fma(1.0 / 105.0, fma(v0, v0, v1 * v1), -(1.0 / 70.0) * (v0 * v1));
    *int_x2_out = dt * fma(dt, fma(dt, fma(dt, 1.0 / 210.0, m2), m1), m0);
}

typedef struct {
    double s1, s2, s3, s4, s5;
} quintic;

static inline quintic speed_squared_coefficients(double a1, double a2, double a3, double dt)
{
    double inv_dt = 1.0 / dt;
    quintic q;
    q.s1 = a1 * a1;
    q.s2 = 2.0 * a1 * a2 + 1.0;
    q.s3 = (4.0 / 3.0) * a2 * a2 + 2.0 * a1 * a3 - (8.0 / 3.0) * inv_dt;
    q.s4 = 3.0 * a2 * a3 + 3.0 * inv_dt * inv_dt;
    q.s5 = (9.0 / 5.0) * a3 * a3 - (6.0 / 5.0) * inv_dt * inv_dt * inv_dt;
    return q;
}

static inline double quintic_antiderivative_value(double s1, double s2, double s3, double s4,
                                                  double s5, double t)
{
    return t * fma(t, fma(t, fma(t, fma(t, s5, s4), s3), s2), s1);
}

/* piece_inverse: what level_time needs of a monotone piece (Python returns the 7-tuple
   (t_lo, width, x_lo, rise, inv_rise, m0, m1)) */
typedef struct {
    double t_lo, width, x_lo, rise, inv_rise, m0, m1;
} piece_inverse_t;

static inline piece_inverse_t piece_inverse(double t_lo, double t_hi, double x_lo, double x_hi,
                                            double d_lo, double d_hi)
{
    double width = t_hi - t_lo;
    double rise = x_hi - x_lo;
    double inv_rise = 1.0 / rise;
    double m0, m1;
    m0 = m1 = 0.0;
    if (d_lo * rise * width > 0.1 * rise * rise && d_hi * rise * width > 0.1 * rise * rise) {
        double inv = rise / (d_lo * d_hi * width);
        m0 = d_hi * inv; /* (rise / width) / m'(t_lo) */
        m1 = d_lo * inv;
    }
    piece_inverse_t inverse = {t_lo, width, x_lo, rise, inv_rise, m0, m1};
    return inverse;
}

/* level_time_estimate: the inverse cubic Hermite start of level_time (the linear one next to a
   zero of m'), no iteration */
static inline double level_time_estimate(double level, piece_inverse_t inverse)
{
    double t_lo = inverse.t_lo, width = inverse.width, x_lo = inverse.x_lo;
    double inv_rise = inverse.inv_rise, m0 = inverse.m0, m1 = inverse.m1;
    double u = (level - x_lo) * inv_rise;
    if (m0 == 0.0)
        return t_lo + width * u;
    return t_lo + width * (u * u * (3.0 - 2.0 * u) + u * (1.0 - u) * ((1.0 - u) * m0 - u * m1));
}

/* level_time_one_step: the estimate and one unconditional Halley step from it (no test: it may
   leave the piece or be NaN; the caller, tally_position, clips it) */
static inline double level_time_one_step(double a0, double a1, double a2, double a3, double level,
                                         piece_inverse_t inverse)
{
    double t = level_time_estimate(level, inverse);
    double f = cubic_value(a0, a1, a2, a3, t) - level;
    double d1 = cubic_slope(a1, a2, a3, t);
    double d2 = 2.0 * a2 + 6.0 * a3 * t;
    return t - 2.0 * f * d1 / (2.0 * d1 * d1 - f * d2);
}

static inline double level_time(double a0, double a1, double a2, double a3, double level,
                                piece_inverse_t inverse)
{
    double t_lo = inverse.t_lo, width = inverse.width, x_lo = inverse.x_lo, rise = inverse.rise;
    double inv_rise = inverse.inv_rise;
    if ((level - x_lo) * inv_rise <= 0.0)
        return t_lo;
    int rising = rise > 0.0;
    double lo = t_lo, hi = t_lo + width;
    double t = level_time_estimate(level, inverse);
    for (int i = 0; i < 200; i++) {
        double f = cubic_value(a0, a1, a2, a3, t) - level;
        if (f == 0.0)
            return t;
        if ((f < 0.0) == rising)
            lo = t;
        else
            hi = t;
        double d1 = cubic_slope(a1, a2, a3, t);
        double d2 = 2.0 * a2 + 6.0 * a3 * t;
        double t_new = t - 2.0 * f * d1 / (2.0 * d1 * d1 - f * d2);
        int is_short = fabs(t_new - t) <= 1e-3 * width;
        /* !(lo < t_new < hi): outside the bracket, or a zero or NaN denominator */
        if (!(lo < t_new && t_new < hi) || (is_short && fabs(d1) * width < 0.1 * fabs(rise))) {
            t_new = 0.5 * (lo + hi); /* bisect (also where a step is short only because m' is small) */
            if (hi - lo <= 1e-10 * width)
                return t_new;
        } else if (is_short) {
            return t_new;
        }
        t = t_new;
    }
    return t;
}

static inline double cubic_level_time(double a0, double a1, double a2, double a3, double level,
                                      double t_lo, double t_hi, double x_lo, double x_hi,
                                      double d_lo, double d_hi)
{
    return level_time(a0, a1, a2, a3, level, piece_inverse(t_lo, t_hi, x_lo, x_hi, d_lo, d_hi));
}

/* the zeros of m'(t) strictly inside (0, t_end): returns their count, sets t1 < t2 */
static inline int slope_zeros(double a1, double a2, double a3, double t_end, double *t1_out,
                              double *t2_out)
{
    double a = 3.0 * a3, b = 2.0 * a2, c = a1;
    double t1 = t_end;
    double t2 = t_end;
    int n = 0;
    *t1_out = t1;
    *t2_out = t2;
    if (a == 0.0) {
        if (b != 0.0) {
            double r = -c / b;
            if (0.0 < r && r < t_end) {
                t1 = r;
                n = 1;
            }
        }
        *t1_out = t1;
        *t2_out = t2;
        return n;
    }
    double disc = b * b - 4.0 * a * c;
    if (disc <= 0.0)
        return 0;
    double sq = sqrt(disc);
    double qq = b >= 0.0 ? -0.5 * (b + sq) : -0.5 * (b - sq);
    double r1 = qq / a;
    double r2 = qq != 0.0 ? c / qq : r1;
    if (r1 > r2) {
        double swap = r1;
        r1 = r2;
        r2 = swap;
    }
    if (0.0 < r1 && r1 < t_end) {
        t1 = r1;
        n = 1;
    }
    if (0.0 < r2 && r2 < t_end && r2 > r1) {
        if (n == 0)
            t1 = r2;
        else
            t2 = r2;
        n += 1;
    }
    *t1_out = t1;
    *t2_out = t2;
    return n;
}

static inline double monotone_piece_end(int piece, int n_zero, double t1, double t2, double t_end)
{
    if (piece == 0 && n_zero >= 1)
        return t1;
    if (piece == 1 && n_zero == 2)
        return t2;
    return t_end;
}

static inline double first_crossing_time(double a0, double a1, double a2, double a3, double t_end,
                                         double x_end)
{
    double t1, t2;
    int n = slope_zeros(a1, a2, a3, t_end, &t1, &t2);
    double start = 0.0;
    double m_start = a0;
    for (int k = 0; k < n + 1; k++) {
        double stop = monotone_piece_end(k, n, t1, t2, t_end);
        double m_stop = stop == t_end ? x_end : cubic_value(a0, a1, a2, a3, stop);
        if (m_stop <= 0.0)
            return cubic_level_time(a0, a1, a2, a3, 0.0, start, stop, m_start, m_stop,
                                    cubic_slope(a1, a2, a3, start), cubic_slope(a1, a2, a3, stop));
        start = stop;
        m_start = m_stop;
    }
    return t_end;
}

static inline void bridge_sample(double a0, double a1, double a2, double a3, double dt,
                                 double t, double normal_1, double normal_2, double *x_out,
                                 double *v_out)
{
    double u = t * (1.0 / dt);
    double w = py_max(u * (1.0 - u), 0.0); /* u may exceed 1 by a rounding error at t = dt */
    double root = sqrt(dt * w);
    *x_out = cubic_value(a0, a1, a2, a3, t) + SQRT2_3 * dt * w * root * normal_1;
    *v_out = cubic_slope(a1, a2, a3, t)
             + root * (SQRT3_2 * (1.0 - 2.0 * u) * normal_1 + SQRT1_2 * normal_2);
}

/* bridge_speed_squared_given_position: E[v(t)^2 | x(t), ends] for the x(t) that bridge_sample
   draws with normal_1 */
static inline double bridge_speed_squared_given_position(double a1, double a2, double a3,
                                                         double dt, double t, double normal_1)
{
    double u = t * (1.0 / dt);
    double w = py_max(u * (1.0 - u), 0.0);
    double root = sqrt(dt * w);
    double mean = cubic_slope(a1, a2, a3, t) + root * SQRT3_2 * (1.0 - 2.0 * u) * normal_1;
    return mean * mean + 0.5 * dt * w;
}

/* ------------------------------------------- simulation/step_tallies.py, simulation/loop.py */

static inline int64_t linear_bin_index(double value, double lo, double per_unit, int64_t n,
                                       const double *edges)
{
    if (value < edges[0])
        return 0;
    if (value >= edges[n])
        return n + 1;
    int64_t k = (int64_t)((value - lo) * per_unit);
    if (k < 0)
        k = 0;
    if (k > n - 1)
        k = n - 1;
    while (k > 0 && value < edges[k])
        k -= 1;
    while (k < n - 1 && value >= edges[k + 1])
        k += 1;
    return k + 1;
}

/* _log_bin_index: bin_index given log(value), or an estimate of it (the edges decide) */
static inline int64_t log_bin_index(double value, double log_value, double log_lo, double per_ln,
                                    int64_t n, const double *edges)
{
    if (value < edges[0])
        return 0;
    if (value >= edges[n])
        return n + 1;
    int64_t k = (int64_t)((log_value - log_lo) * per_ln);
    if (k < 0)
        k = 0;
    if (k > n - 1)
        k = n - 1;
    /* correct a last-digit disagreement between log and the stored edges */
    while (k > 0 && value < edges[k])
        k -= 1;
    while (k < n - 1 && value >= edges[k + 1])
        k += 1;
    return k + 1;
}

static inline int64_t bin_index(double value, double log_lo, double per_ln, int64_t n,
                                const double *edges)
{
    if (value < edges[0])
        return 0;
    if (value >= edges[n])
        return n + 1;
    return log_bin_index(value, log(value), log_lo, per_ln, n, edges);
}

/* floor_stratum_end: t_low = FLOOR_STRATUM_HEIGHT / v in a step that starts at the floor with
   v tau > FLOOR_STRATUM_HEIGHT (two bridge points, one in [0, t_low], one in [t_low, tau]);
   else tau (one point) */
static inline double floor_stratum_end(double tau, double x, double v)
{
    if (x == 0.0 && v * tau > FLOOR_STRATUM_HEIGHT)
        return FLOOR_STRATUM_HEIGHT / v;
    return tau;
}

/* _bridge_correction: the point's weight (and weight E[v(s)^2 | x(s), ends]) from bin k_s to k_x */
static inline void bridge_correction(double a1, double a2, double a3, double dt, double weight,
                                     double s, double normal_1, int64_t k_s, int64_t k_x,
                                     double *time_in, double *v2_in)
{
    double v2_s = weight * bridge_speed_squared_given_position(a1, a2, a3, dt, s, normal_1);
    time_in[k_x] += weight;
    time_in[k_s] -= weight;
    v2_in[k_x] += v2_s;
    v2_in[k_s] -= v2_s;
}

/* _walked_bin_index: the bin of value, walking from bin k over the bins' ends (-inf and inf
   those of the under- and overflow bins); a NaN stays in bin k */
static inline int64_t walked_bin_index(double value, int64_t k, const double *bin_lower,
                                       const double *bin_upper)
{
    while (value < bin_lower[k])
        k -= 1;
    while (value >= bin_upper[k])
        k += 1;
    return k;
}

/* edges has n + 1 entries.  Returns the bin of x_b and sets *k_s, *k_s2 to the bins of the
   intervals holding the times s, s2 (unchanged if before the piece); Python returns the triple
   (k, k_s, k_s2) */
static inline int64_t tally_position(double a0, double a1, double a2, double a3, quintic sq,
                                     double t_a, double t_b, double x_a, double x_b, double d_a,
                                     double d_b, int64_t k, double s, int64_t *k_s, double s2,
                                     int64_t *k_s2, int exact_crossings, const double *edges,
                                     int64_t n,
                                     double *time_in, double *v2_in)
{
    double t_prev = t_a;
    double s_prev = quintic_antiderivative_value(sq.s1, sq.s2, sq.s3, sq.s4, sq.s5, t_a);
    piece_inverse_t inverse = piece_inverse(t_a, t_b, x_a, x_b, d_a, d_b);
    for (;;) {
        double level;
        int64_t k_next;
        if (k <= n && x_b >= edges[k]) { /* leaves bin k through its upper edge */
            level = edges[k];
            k_next = k + 1;
        } else if (k >= 1 && x_b < edges[k - 1]) { /* through its lower edge */
            level = edges[k - 1];
            k_next = k - 1;
        } else {
            break;
        }
        double t_e;
        if (exact_crossings)
            t_e = level_time(a0, a1, a2, a3, level, inverse);
        else /* clipped to [t_prev, t_b]; py_max and py_min keep their first argument against a NaN */
            t_e = py_min(t_b, py_max(t_prev, level_time_one_step(a0, a1, a2, a3, level, inverse)));
        double s_e = quintic_antiderivative_value(sq.s1, sq.s2, sq.s3, sq.s4, sq.s5, t_e);
        time_in[k] += t_e - t_prev;
        v2_in[k] += s_e - s_prev;
        *k_s = s >= t_prev ? k : *k_s;
        *k_s2 = s2 >= t_prev ? k : *k_s2;
        t_prev = t_e;
        s_prev = s_e;
        k = k_next;
    }
    double s_b = quintic_antiderivative_value(sq.s1, sq.s2, sq.s3, sq.s4, sq.s5, t_b);
    time_in[k] += t_b - t_prev;
    v2_in[k] += s_b - s_prev;
    *k_s = s >= t_prev ? k : *k_s;
    *k_s2 = s2 >= t_prev ? k : *k_s2;
    return k;
}

/* returns the bin of m(tau) and sets *k_s, *k_s2 to the bins the assignment gives the times s,
   s2 (Python returns the triple (k, k_s, k_s2)) */
static inline int64_t tally_step(double a0, double a1, double a2, double a3, double dt, double tau,
                                 double x_tau, double slope_tau, int64_t k, double s, int64_t *k_s,
                                 double s2, int64_t *k_s2, int exact_crossings, const double *edges, int64_t n,
                                 const double *bin_lower,
                                 const double *bin_upper, double *time_in, double *v2_in)
{
    quintic sq = speed_squared_coefficients(a1, a2, a3, dt);
    double c1 = a0 + a1 * tau * (1.0 / 3.0);
    double c2 = x_tau - slope_tau * tau * (1.0 / 3.0);
    double lowest = py_min(py_min(a0, x_tau), py_min(c1, c2));
    double highest = py_max(py_max(a0, x_tau), py_max(c1, c2));
    if (bin_lower[k] <= lowest && highest < bin_upper[k]) {
        time_in[k] += tau;
        v2_in[k] += quintic_antiderivative_value(sq.s1, sq.s2, sq.s3, sq.s4, sq.s5, tau);
        *k_s = k;
        *k_s2 = k;
        return k;
    }
    /* m' is a quadratic with Bernstein control points m'(0), m'(0) + a2 tau, m'(tau):
       when they share a sign, m is monotone and needs no split */
    double slope_mid = a1 + a2 * tau;
    int n_zero;
    double t1, t2;
    if ((a1 > 0.0 && slope_mid > 0.0 && slope_tau > 0.0)
        || (a1 < 0.0 && slope_mid < 0.0 && slope_tau < 0.0)) {
        n_zero = 0;
        t1 = tau;
        t2 = tau;
    } else {
        n_zero = slope_zeros(a1, a2, a3, tau, &t1, &t2);
    }
    double t_a = 0.0;
    double x_a = a0;
    double d_a = a1;
    *k_s = k;
    *k_s2 = k;
    for (int piece = 0; piece < n_zero + 1; piece++) {
        double t_b = monotone_piece_end(piece, n_zero, t1, t2, tau);
        double x_b, d_b;
        if (t_b == tau) {
            x_b = x_tau;
            d_b = slope_tau;
        } else { /* a zero of m' */
            x_b = cubic_value(a0, a1, a2, a3, t_b);
            d_b = 0.0;
        }
        k = tally_position(a0, a1, a2, a3, sq, t_a, t_b, x_a, x_b, d_a, d_b, k, s, k_s, s2, k_s2,
                           exact_crossings, edges, n, time_in, v2_in);
        t_a = t_b;
        x_a = x_b;
        d_a = d_b;
    }
    return k;
}

/*
 * _run.  v_edges (speeds) has nv + 1 entries, x_edges nx + 1, u_edges (velocities of
 * P(x, v)) nu + 1, f_edges (flight times) nf + 1, w_edges (outgoing speeds, fine) nw + 1;
 * speed_counts, position_time, position_v2_time, flight_time_counts and
 * return_law_speed_counts have nv + 2, nx + 2, nx + 2, nf + 2 and nw + 2 entries,
 * position_velocity_time (nx + 2) x (nu + 2) and return_speed_counts (nv + 2) x (nv + 2),
 * row-major, bounce_lag_sums 9 x lag_size (lags 0 .. lag_size - 1, tallies.BOUNCE_LAG_SUMS),
 * row-major (all zeroed by the caller); scalars has len(tallies.SCALARS).  Returns 0, or -1 if the two small
 * bin-bound arrays cannot be allocated.
 */
int bouncing_ball_shard_loop(bitgen_t *rng, bitgen_t *rng_tally, double restitution, double c,
                             double min_step_divisor, double min_step_floor,
                             double equilibration_time, double recorded_time, int64_t max_steps,
                             const double *v_edges, int64_t nv, const double *x_edges, int64_t nx,
                             const double *u_edges, int64_t nu, const double *f_edges, int64_t nf,
                             const double *w_edges, int64_t nw, int64_t *speed_counts,
                             double *position_time, double *position_v2_time,
                             int64_t *flight_time_counts, double *position_velocity_time,
                             int64_t *return_speed_counts, int64_t *return_law_speed_counts,
                             double *bounce_lag_sums, int64_t lag_size, double *scalars)
{
    double v_log_lo = log(v_edges[0]);
    double v_per_ln = (double)nv / (log(v_edges[nv]) - v_log_lo);
    double x_log_lo = log(x_edges[0]);
    double x_per_ln = (double)nx / (log(x_edges[nx]) - x_log_lo);
    double u_lo = u_edges[0];
    double u_per_unit = (double)nu / (u_edges[nu] - u_lo);
    double f_log_lo = log(f_edges[0]);
    double f_per_ln = (double)nf / (log(f_edges[nf]) - f_log_lo);
    double log_restitution = log(restitution);
    double w_log_lo = log(w_edges[0]);
    double w_per_ln = (double)nw / (log(w_edges[nw]) - w_log_lo);
    /* the two ends of every x bin, the under- and overflow bins unbounded */
    double *x_bin_lower = malloc((size_t)(nx + 2) * sizeof(double));
    double *x_bin_upper = malloc((size_t)(nx + 2) * sizeof(double));
    if (x_bin_lower == NULL || x_bin_upper == NULL) {
        free(x_bin_lower);
        free(x_bin_upper);
        return -1;
    }
    x_bin_lower[0] = -INFINITY;
    for (int64_t j = 0; j < nx + 1; j++) {
        x_bin_lower[j + 1] = x_edges[j];
        x_bin_upper[j] = x_edges[j];
    }
    x_bin_upper[nx + 1] = INFINITY;

    /* start at rest one unit above the floor; equilibration forgets this */
    double x = 1.0;
    double v = 0.0;
    double slope_at_root;
    double root = criterion_root(x, v, c, 0.0, &slope_at_root); /* s* of eq. (criterion), f'(s*) */
    int64_t x_bin = bin_index(x, x_log_lo, x_per_ln, nx, x_edges); /* kept while recording */
    double min_root_2delta = 1.0 / min_step_divisor;
    double delta = py_max(0.5 * min_root_2delta * min_root_2delta, min_step_floor);
    int recording = equilibration_time <= 0.0;
    double t = 0.0;
    double t_stop = recording ? recorded_time : equilibration_time;
    int64_t steps = 0; /* all steps, against the budget */
    int64_t recorded_steps = 0;
    int64_t collisions = 0;
    double int_x = 0.0;
    double int_x2 = 0.0;
    int64_t exhausted = 0;
    int64_t flights = 0;
    double flight_time_sum = 0.0;
    double flight_time_squared_sum = 0.0;
    double since_collision = 0.0; /* time since the last collision (equilibration included) */
    int collided_before = 0;
    int64_t last_out_bin = 0; /* speed bin of the last collision's outgoing speed */
    /* the outgoing speeds of the last collisions and their logarithms (the bounce-lag sums) */
    double ring_log[lag_size];
    double ring_speed[lag_size];
    for (int64_t j = 0; j < lag_size; j++) {
        ring_log[j] = 0.0;
        ring_speed[j] = 0.0;
    }
    int64_t ring_newest = lag_size - 1; /* where the latest collision is */
    int64_t ring_history = 0;           /* collisions in the ring */
    /* the control variates (martingales of mean 0) */
    double noise_sum = 0.0;
    double noise_v_sum = 0.0;
    double noise_scaled_sum = 0.0;
    double normal_sum = 0.0;
    double noise_x_sum = 0.0;
    double noise_xv_sum = 0.0;
    double noise_x2_sum = 0.0;
    double noise_v2_sum = 0.0;
    double noise_v3_sum = 0.0;
    double noise_v4_sum = 0.0;
    double noise_xv2_sum = 0.0;
    double noise_squared_sum = 0.0;
    double noise_squared_v_sum = 0.0;
    double noise_squared_x_sum = 0.0;
    double noise_squared_v2_sum = 0.0;
    double position_noise_sum = 0.0;
    double position_noise_v_sum = 0.0;
    double position_noise_x_sum = 0.0;
    /* the early part of the recording: the running sums when a step first starts past t_early */
    double t_early = recording ? EARLY_FRACTION * recorded_time : INFINITY;
    double early_time = 0.0;
    int64_t early_collisions = 0;
    double early_int_x = 0.0;
    double early_int_x2 = 0.0;

    for (;;) {
        if (t >= t_stop) {
            if (recording)
                break;
            recording = 1;
            x_bin = bin_index(x, x_log_lo, x_per_ln, nx, x_edges);
            t = 0.0;
            t_stop = recorded_time;
            t_early = EARLY_FRACTION * recorded_time;
            continue;
        }
        if (t >= t_early) {
            early_time = t;
            early_collisions = collisions;
            early_int_x = int_x;
            early_int_x2 = int_x2;
            t_early = INFINITY;
        }
        if (steps >= max_steps) {
            exhausted = 1;
            break;
        }
        double dt = fma(root, root, delta); /* eq. (criterion) plus delta */
        if (!(dt > COLLAPSED_STEP)) { /* below r_c without a floor on delta */
            exhausted = 1;
            break;
        }
        if (t + dt > t_stop)
            dt = t_stop - t;
        /* the next root starts from a first-order prediction off this one: f(s; x, v) is linear
           in x and v and f(root; x, v) = 0, so s ~ root - (x1 - x + root^2 (v1 - v)) / f'(root)
           = k0 - k1 x1 - k2 v1, with coefficients ready (division included) before the step */
        double k1 = slope_at_root < 0.0 ? 1.0 / slope_at_root : 0.0;
        double k2 = k1 * root * root;
        double k0 = fma(k2, v, fma(k1, x, root));
        double normal_r = random_standard_normal(rng);
        double normal_s = random_standard_normal(rng);
        double x1, v1;
        free_flight_step(x, v, dt, normal_r, normal_s, &x1, &v1);
        double a0, a1, a2, a3;
        hermite_cubic(x, v, x1, v1, dt, &a0, &a1, &a2, &a3);
        int collided = x1 < 0.0;
        double tau, x_tau, v_tau;
        if (collided) { /* the step ends where the mean path first reaches 0 */
            tau = first_crossing_time(a0, a1, a2, a3, dt, x1);
            x_tau = 0.0;
            v_tau = cubic_slope(a1, a2, a3, tau);
        } else {
            tau = dt;
            x_tau = x1;
            v_tau = v1;
        }
        steps += 1;
        if (recording) {
            recorded_steps += 1;
            /* every part of parts = EVERY_TALLY: CONTROL_VARIATES, MEAN_PATH_INTEGRALS, POSITION, JOINT */
            double xi = sqrt(2.0 * dt) * normal_r; /* the velocity noise of eq. (vstep) */
            noise_sum += xi;
            noise_v_sum += v * xi;
            noise_scaled_sum += v / (x + 0.5 * v * v + 4.0 * dt) * xi;
            normal_sum += normal_r;
            /* the moments' control variates: weights polynomial in the start state times xi,
               q = xi^2 - 2 dt (mean 0 given the past) and eta = dt^(3/2) normal_s */
            double x2 = x * x;
            double v2 = v * v;
            noise_x_sum += x * xi;
            noise_xv_sum += x * v * xi;
            noise_x2_sum += x2 * xi;
            noise_v2_sum += v2 * xi;
            noise_v3_sum += v2 * v * xi;
            noise_v4_sum += v2 * v2 * xi;
            noise_xv2_sum += x * v2 * xi;
            double q = xi * xi - 2.0 * dt;
            noise_squared_sum += q;
            noise_squared_v_sum += v * q;
            noise_squared_x_sum += x * q;
            noise_squared_v2_sum += v2 * q;
            double eta = dt * sqrt(dt) * normal_s;
            position_noise_sum += eta;
            position_noise_v_sum += v * eta;
            position_noise_x_sum += x * eta;
            double ix, ix2;
            if (collided)
                mean_path_integrals(a0, a1, a2, a3, dt, tau, &ix, &ix2);
            else
                whole_step_integrals(x, v, x1, v1, dt, &ix, &ix2);
            int_x += ix;
            int_x2 += ix2;
            /* the step's bridge points, (x(s), v(s)), from the tally stream: P(x, v), and the
               bridge-law correction of P(x), <v^2>_x.  One, s uniform in [0, tau] with weight
               tau; two in a step from the floor, one in each stratum of floor_stratum_end */
            double t_low = floor_stratum_end(tau, x, v);
            int points = t_low < tau ? 2 : 1;
            double u = random_standard_uniform(rng_tally);
            double normal_1 = random_standard_normal(rng_tally);
            double normal_2 = random_standard_normal(rng_tally);
            double s = u * tau;
            double weight = tau;
            double s2 = s;
            if (points == 2) {
                s = t_low + u * (tau - t_low);
                weight = tau - t_low;
                s2 = random_standard_uniform(rng_tally) * t_low;
            }
            int64_t k_s, k_s2;
            x_bin = tally_step(a0, a1, a2, a3, dt, tau, x_tau, v_tau, x_bin, s, &k_s, s2, &k_s2,
                               collided, x_edges, nx, x_bin_lower, x_bin_upper, position_time,
                               position_v2_time);
            for (int point = 0; point < points; point++) {
                if (point == 1) { /* _tally_second_bridge_point: its normals drawn after the first */
                    s = s2;
                    weight = t_low;
                    normal_1 = random_standard_normal(rng_tally);
                    normal_2 = random_standard_normal(rng_tally);
                    k_s = k_s2;
                }
                double x_s, v_s; /* the point itself after the walk, as in numba */
                bridge_sample(a0, a1, a2, a3, dt, s, normal_1, normal_2, &x_s, &v_s);
                /* the assignment gave the time s to bin k_s, the bridge puts x(s) in x_cell: the
                   bridge correction makes the tally exact in expectation (not in a step cut by a
                   collision, which keeps the mean path its collision is placed on) */
                int64_t x_cell = walked_bin_index(x_s, k_s, x_bin_lower, x_bin_upper);
                if (x_cell != k_s && !collided)
                    bridge_correction(a1, a2, a3, dt, weight, s, normal_1, k_s, x_cell,
                                      position_time, position_v2_time);
                /* P(x, v): the point's weight to the cell of (x(s), v(s)); with POSITION on,
                   x_cell is the walk's (parts & POSITION: always, so no bin_index) */
                int64_t cell_v = linear_bin_index(v_s, u_lo, u_per_unit, nu, u_edges);
                position_velocity_time[x_cell * (nu + 2) + cell_v] += weight;
            }
        }
        t += tau;
        since_collision += tau;
        if (collided) {
            double v_in = fabs(v_tau);
            double v_out = restitution * v_in; /* eq. (restitution) */
            double log_v_out = log(v_out); /* the bins of v_out, and of v_in = v_out / r, from it */
            int64_t out_bin = log_bin_index(v_out, log_v_out, v_log_lo, v_per_ln, nv, v_edges);
            ring_newest = ring_newest == lag_size - 1 ? 0 : ring_newest + 1;
            ring_log[ring_newest] = log_v_out;
            ring_speed[ring_newest] = v_out;
            if (ring_history < lag_size)
                ring_history += 1;
            if (recording) {
                /* _tally_bounce_lags: the pairs (u_{n-k}, u_n), k = 0 .. ring_history - 1 */
                for (int64_t k = 0; k < ring_history; k++) {
                    int64_t j = ring_newest - k;
                    if (j < 0)
                        j += lag_size;
                    double lead_log = ring_log[j];
                    double lead_u = ring_speed[j];
                    bounce_lag_sums[0 * lag_size + k] += 1.0;
                    bounce_lag_sums[1 * lag_size + k] += lead_log;
                    bounce_lag_sums[2 * lag_size + k] += lead_u;
                    bounce_lag_sums[3 * lag_size + k] += log_v_out;
                    bounce_lag_sums[4 * lag_size + k] += v_out;
                    bounce_lag_sums[5 * lag_size + k] += lead_log * log_v_out;
                    bounce_lag_sums[6 * lag_size + k] += lead_log * v_out;
                    bounce_lag_sums[7 * lag_size + k] += lead_u * log_v_out;
                    bounce_lag_sums[8 * lag_size + k] += lead_u * v_out;
                }
                collisions += 1;
                speed_counts[out_bin] += 1;
                return_law_speed_counts[log_bin_index(v_out, log_v_out, w_log_lo, w_per_ln, nw,
                                                      w_edges)] += 1;
                if (collided_before) { /* the flight that ends here (parts & FLIGHTS: always) */
                    flights += 1;
                    flight_time_sum += since_collision;
                    flight_time_squared_sum += since_collision * since_collision;
                    flight_time_counts[bin_index(since_collision, f_log_lo, f_per_ln, nf, f_edges)] += 1;
                    return_speed_counts[last_out_bin * (nv + 2)
                                        + log_bin_index(v_in, log_v_out - log_restitution,
                                                        v_log_lo, v_per_ln, nv, v_edges)] += 1;
                }
            }
            collided_before = 1;
            since_collision = 0.0;
            last_out_bin = out_bin;
            x = 0.0;
            x_bin = 0;
            v = v_out;
            double root_2delta = v_out * min_root_2delta;
            delta = py_max(0.5 * root_2delta * root_2delta, min_step_floor); /* below r_c: regularises */
            root = criterion_root(x, v, c, 0.0, &slope_at_root); /* closed form at x = 0 */
        } else {
            x = x1;
            v = v1;
            double predicted = fma(-k2, v1, fma(-k1, x1, k0));
            root = criterion_root(x, v, c, predicted > 0.0 ? predicted : root, &slope_at_root);
        }
    }

    scalars[SCALAR_TIME] = recording ? t : 0.0;
    scalars[SCALAR_COLLISIONS] = (double)collisions;
    scalars[SCALAR_STEPS] = (double)recorded_steps;
    scalars[SCALAR_INT_X] = int_x;
    scalars[SCALAR_INT_X2] = int_x2;
    scalars[SCALAR_BUDGET_EXHAUSTED] = (double)exhausted;
    scalars[SCALAR_FLIGHTS] = (double)flights;
    scalars[SCALAR_FLIGHT_TIME_SUM] = flight_time_sum;
    scalars[SCALAR_FLIGHT_TIME_SQUARED_SUM] = flight_time_squared_sum;
    scalars[SCALAR_NOISE_SUM] = noise_sum;
    scalars[SCALAR_NOISE_V_SUM] = noise_v_sum;
    scalars[SCALAR_NOISE_SCALED_SUM] = noise_scaled_sum;
    scalars[SCALAR_NORMAL_SUM] = normal_sum;
    scalars[SCALAR_EARLY_TIME] = early_time;
    scalars[SCALAR_EARLY_COLLISIONS] = (double)early_collisions;
    scalars[SCALAR_EARLY_INT_X] = early_int_x;
    scalars[SCALAR_EARLY_INT_X2] = early_int_x2;
    scalars[SCALAR_NOISE_X_SUM] = noise_x_sum;
    scalars[SCALAR_NOISE_XV_SUM] = noise_xv_sum;
    scalars[SCALAR_NOISE_X2_SUM] = noise_x2_sum;
    scalars[SCALAR_NOISE_V2_SUM] = noise_v2_sum;
    scalars[SCALAR_NOISE_V3_SUM] = noise_v3_sum;
    scalars[SCALAR_NOISE_V4_SUM] = noise_v4_sum;
    scalars[SCALAR_NOISE_XV2_SUM] = noise_xv2_sum;
    scalars[SCALAR_NOISE_SQUARED_SUM] = noise_squared_sum;
    scalars[SCALAR_NOISE_SQUARED_V_SUM] = noise_squared_v_sum;
    scalars[SCALAR_NOISE_SQUARED_X_SUM] = noise_squared_x_sum;
    scalars[SCALAR_NOISE_SQUARED_V2_SUM] = noise_squared_v2_sum;
    scalars[SCALAR_POSITION_NOISE_SUM] = position_noise_sum;
    scalars[SCALAR_POSITION_NOISE_V_SUM] = position_noise_v_sum;
    scalars[SCALAR_POSITION_NOISE_X_SUM] = position_noise_x_sum;
    free(x_bin_lower);
    free(x_bin_upper);
    return 0;
}
