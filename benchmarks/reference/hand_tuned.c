/*
 * hand_tuned.c -- a hand-tuned C99 loop of the paper's Sec. IV simulation: the speed anchor
 * of the benchmark ("a hand-tuned C loop of the same physics", python -m benchmarks).
 *
 * Physics (the same as bouncing_ball.simulation._run; g = Lambda = 1):
 *   - start at x = 1, v = 0;
 *   - step dt = D(x, v) + delta, D = s*^2 the largest step allowed by eq. (criterion), s* the
 *     positive root of f(s) = x + v s^2 - c s^3 - s^4 / 2;
 *   - the exact free-flight update of eqs. (xstep), (vstep), two standard normals per step;
 *   - a step ending at x < 0 is cut where the cubic Hermite mean path m(t) of the bridge
 *     (ends (x, v), (x1, v1) over dt) first reaches 0; the impact speed is |m'(tau)|,
 *     v_out = r v_in, delta = (v_out / divisor)^2 / 2 (the paper's 1/500 rule), and the
 *     clock advances by tau; the last step of a phase is shortened to end at its stop time.
 * Tallies after the equilibration time: collisions, time, steps, int x dt and int x^2 dt in
 * expectation given both ends of each step (mean path plus bridge variance, as
 * free_flight.mean_path_integrals), and the outgoing speeds on the log bins passed in.
 * Not tallied (unlike the project's loop): P(x), <v^2>_x, P(x, v), flights.
 *
 * Where it is fast, and how it stays honest (its ns per step: python -m
 * benchmarks.hand_tuned_loop):
 *   - The loop is latency-bound: each step's size needs the root of the state the previous
 *     step produced.  The root: Householder's third-order iteration (quartic convergence) on
 *     f, one division an iteration, stopped after a step <= ROOT_TOLERANCE s (the error left
 *     is ~e^4 of a last step e: <= 3e-11 relative on simulated states, where ~1e-10 was
 *     asked).  It starts from a first-order prediction off the previous step's root (see
 *     run_phase), about 2.0 iterations a step; the previous root alone gives 2.3-2.4, and the
 *     project's cold start (cube root and rational fit) 1.2-1.6 iterations but costs more than
 *     it saves (glibc's cbrt alone ~25 ns).  After a collision (x = 0) the root has a closed
 *     form.  A start left of the maximum of f (f' >= 0, which the iteration cannot leave)
 *     falls back to the project's cold start (free_flight.largest_safe_step); such restarts
 *     are counted (none in the runs measured).
 *   - A step that does not collide needs no cubic: the mean-path integrals of x and x^2 over
 *     the whole step are written through the cubic Hermite mass matrix of its two ends (equal
 *     to free_flight.mean_path_integrals to rounding); the collision path uses the project's
 *     crossing search (free_flight.first_crossing_time, cubic_level_time).
 *   - Normals: a 256-layer ziggurat (Marsaglia & Tsang's layers, numpy's layout: 8 bits of
 *     layer, 1 sign bit and 52 bits of abscissa from one 64-bit draw, 98.5 % accepted at once;
 *     the sign applied without a branch) on xoshiro256+ (Blackman & Vigna) seeded by
 *     splitmix64; the lowest 3 bits of xoshiro256+, its weak ones, are never used.  About
 *     1.5 ns a normal, mostly hidden behind the root's latency.
 *   - Built with gcc -O3 -march=native -ffp-contract=fast -fno-math-errno -std=c99: fused
 *     multiply-adds are contracted wherever gcc likes (the line-by-line reference
 *     shard_loop.c switches contraction off and calls fma() exactly where the numba loop
 *     does, to match it bit for bit), and sqrt needs no errno branch.
 *
 * Entry points (ctypes, benchmarks/hand_tuned_loop.py):
 *   hand_tuned_run      one shard; CPU time measured inside (CLOCK_PROCESS_CPUTIME_ID)
 *   hand_tuned_normals  n normals of the generator (to check it)
 *   hand_tuned_root     the criterion root from a given start (to check it)
 */

#define _POSIX_C_SOURCE 199309L

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <time.h>

#define SQRT3 1.7320508075688772
#define SQRT1_12 0.28867513459481287
#define COLLAPSED_STEP 1.0e-80
#define ROOT_TOLERANCE 2.0e-3 /* a last step below this (relative) leaves ~tol^4 */
#define ROOT_MAX_ITERATIONS 60

#define LIKELY(x) __builtin_expect(!!(x), 1)
#define UNLIKELY(x) __builtin_expect(!!(x), 0)
#define ALWAYS_INLINE inline __attribute__((always_inline))

/* ---------------------------------------------------------------- generator */

typedef struct {
    uint64_t s[4];
} rng_t;

static inline uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

/* xoshiro256+ 1.0 (Blackman & Vigna) on a state held in four scalars, so that the compiler keeps
   it in registers (a state in memory gets its stores vectorised, which triples a normal's cost) */
#define RNG_NEXT(s0, s1, s2, s3, out)                                                              \
    do {                                                                                           \
        (out) = (s0) + (s3);                                                                       \
        uint64_t t_ = (s1) << 17;                                                                  \
        (s2) ^= (s0);                                                                              \
        (s3) ^= (s1);                                                                              \
        (s1) ^= (s2);                                                                              \
        (s0) ^= (s3);                                                                              \
        (s2) ^= t_;                                                                                \
        (s3) = rotl((s3), 45);                                                                     \
    } while (0)

static inline uint64_t rng_next(rng_t *g)
{
    uint64_t out;
    RNG_NEXT(g->s[0], g->s[1], g->s[2], g->s[3], out);
    return out;
}

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static void rng_seed(rng_t *g, uint64_t seed)
{
    uint64_t state = seed;
    for (int i = 0; i < 4; i++)
        g->s[i] = splitmix64(&state);
}

/* uniform on [0, 1) from the top 53 bits */
static inline double rng_uniform(rng_t *g) { return (double)(rng_next(g) >> 11) * 0x1.0p-53; }

/* ---------------------------------------------------------------- ziggurat */

#define ZIG_R 3.6541528853610088 /* right edge of the base layer */
#define ZIG_V 4.92867323399e-3   /* area of each layer */
#define ZIG_MASK52 0x000fffffffffffffULL

typedef struct {
    uint64_t k[256]; /* accept at once if the 52-bit abscissa is below k */
    double w[256];   /* layer width / 2^52 */
    double f[257];   /* exp(-x^2 / 2) at the layers' edges, f[256] = 1 */
} zig_t;

/* Layer i >= 1 spans [0, X_i] x [f(X_i), f(X_{i+1})], X_1 = R, X_256 = 0; the base layer 0 is
   [0, R] x [0, f(R)] plus the tail beyond R, drawn as a rectangle of width X_0 = V / f(R). */
static void zig_init(zig_t *z)
{
    double x[257];
    x[0] = ZIG_V / exp(-0.5 * ZIG_R * ZIG_R);
    x[1] = ZIG_R;
    for (int i = 1; i < 255; i++)
        x[i + 1] = sqrt(-2.0 * log(ZIG_V / x[i] + exp(-0.5 * x[i] * x[i])));
    x[256] = 0.0;
    for (int i = 0; i < 256; i++) {
        double inner = i == 0 ? ZIG_R : x[i + 1];
        z->k[i] = (uint64_t)(0x1.0p52 * (inner / x[i]));
        z->w[i] = x[i] * 0x1.0p-52;
        z->f[i] = exp(-0.5 * x[i] * x[i]);
    }
    z->f[256] = 1.0;
}

static double zig_slow(rng_t *g, const zig_t *z, uint64_t u, unsigned idx, double x)
{
    for (;;) {
        if (idx == 0) { /* the tail beyond R (Marsaglia 1964) */
            for (;;) {
                double xx = -log1p(-rng_uniform(g)) * (1.0 / ZIG_R);
                double yy = -log1p(-rng_uniform(g));
                if (yy + yy > xx * xx)
                    return (u >> 55) & 1 ? -(ZIG_R + xx) : ZIG_R + xx;
            }
        }
        if (z->f[idx] + rng_uniform(g) * (z->f[idx + 1] - z->f[idx]) < exp(-0.5 * x * x))
            return x;
        /* rejected: a fresh draw */
        u = rng_next(g);
        idx = (unsigned)(u >> 56);
        uint64_t rabs = (u >> 3) & ZIG_MASK52;
        x = (double)(int64_t)rabs * z->w[idx];
        if (u & (1ULL << 55))
            x = -x;
        if (rabs < z->k[idx])
            return x;
    }
}

static ALWAYS_INLINE double zig_normal(uint64_t *s0, uint64_t *s1, uint64_t *s2, uint64_t *s3,
                                       const zig_t *z)
{
    uint64_t u;
    RNG_NEXT(*s0, *s1, *s2, *s3, u);
    unsigned idx = (unsigned)(u >> 56);     /* bits 56-63: layer */
    uint64_t rabs = (u >> 3) & ZIG_MASK52;   /* bits 3-54: abscissa */
    uint64_t negative = 0 - ((u >> 55) & 1); /* bit 55: sign, as a mask (a branch would miss half
                                                the time) */
    double x = (double)(int64_t)((rabs ^ negative) - negative) * z->w[idx];
    if (LIKELY(rabs < z->k[idx]))
        return x;
    rng_t g = {{*s0, *s1, *s2, *s3}}; /* the rare path, on a copy: the state never escapes */
    x = zig_slow(&g, z, u, idx, x);
    *s0 = g.s[0];
    *s1 = g.s[1];
    *s2 = g.s[2];
    *s3 = g.s[3];
    return x;
}

/* ---------------------------------------------------------------- step-size root */

/* D at x = 0: the root of s^2 (v - c s - s^2 / 2) */
static inline double floor_root(double v, double c)
{
    return v > 0.0 ? 2.0 * v / (c + sqrt(c * c + 2.0 * v)) : 0.0;
}

/* the project's starting point (free_flight.largest_safe_step): the root of the cubic without
   the s^4 / 2 term, from rational fits in units of (x / c)^(1/3); x > 0 */
static double cold_start(double x, double v, double c)
{
    double a3 = x / c;
    double a = cbrt(a3);
    double b = v / c;
    double a2 = a * a;
    if (b >= 0.0)
        return b + a * ((a3 + 0.44356066 * a2 * b)
                        / (a3 + b * (a2 * (0.44356066 + 2.0 / 3.0) + b * (0.56163652 * a + 0.44356066 * b))));
    return sqrt(a3 / (-b + a2 * (a - 0.06071102 * b) / (a2 - b * (0.40104058 * a - 0.00211799 * b))));
}

/*
 * The positive root s* of f(s) = x + v s^2 - c s^3 - s^4 / 2 (x > 0) from the start s, and in
 * *fp the slope f' near it (at the last iterate but one: close enough for the next predictor).
 * f has one positive root, f' < 0 and f'' < 0 on [s*, inf), and f' > 0 only left of the
 * maximum of f.  Householder's order-3 step
 *     s -= f (6 f'^2 - 3 f f'') / (6 f'^3 - 6 f f' f'' + f^2 f''')
 * converges quartically: after a step of relative size e the error left is about e^4, so it
 * stops after a step <= ROOT_TOLERANCE s (measured on simulated states: <= 3e-11 relative).
 * A Newton step stands in where its denominator is not negative (far from s*); a start left
 * of the maximum of f, where no iteration of this kind can go, restarts from the project's
 * cold start; so does an iteration that has not converged in ROOT_MAX_ITERATIONS.
 */
static ALWAYS_INLINE double criterion_root(double x, double v, double c, double s, double *fp_out,
                                           int64_t *iterations, int64_t *restarts)
{
    if (UNLIKELY(!(x >= DBL_MIN))) { /* x = 0, as far as doubles go */
        s = floor_root(v, c);
        *fp_out = s * (2.0 * v - s * (3.0 * c + 2.0 * s));
        return s;
    }
    int cold = 0;
    if (UNLIKELY(!(s > 0.0))) {
        s = cold_start(x, v, c);
        cold = 1;
    }
    const double c3 = 3.0 * c, c6 = 6.0 * c, v2 = 2.0 * v;
    for (int i = 0;; i++) {
        double s2 = s * s;
        double f = x + s2 * (v - s * (c + 0.5 * s));
        double fp = s * (v2 - s * (c3 + 2.0 * s));
        double fpp = v2 - s * (c6 + 6.0 * s);
        double fppp = -c6 - 12.0 * s;
        *iterations += 1;
        if (UNLIKELY(!(fp < 0.0) || i == ROOT_MAX_ITERATIONS)) {
            if (cold) /* from the cold start: only on underflow */
                return s;
            s = cold_start(x, v, c);
            cold = 1;
            i = 0;
            *restarts += 1;
            continue;
        }
        *fp_out = fp;
        double ffpp = f * fpp;
        double fp2 = fp * fp;
        double num = f * (6.0 * fp2 - 3.0 * ffpp);
        double den = fp * (6.0 * fp2 - 6.0 * ffpp) + f * f * fppp;
        double step = LIKELY(den < 0.0) ? num / den : f / fp;
        double s_new = s - step;
        if (UNLIKELY(!(s_new > 0.0))) { /* overshot past 0: halve instead (f(0) = x > 0) */
            s *= 0.5;
            continue;
        }
        s = s_new;
        if (fabs(step) <= ROOT_TOLERANCE * s)
            return s;
    }
}

/* ---------------------------------------------------------------- the bridge's mean path */

static inline double cubic_value(double a0, double a1, double a2, double a3, double t)
{
    return a0 + t * (a1 + t * (a2 + t * a3));
}

static inline double cubic_slope(double a1, double a2, double a3, double t)
{
    return a1 + t * (2.0 * a2 + t * 3.0 * a3);
}

/* free_flight.cubic_level_time: the t in [t_lo, t_hi] where m(t) = level, m monotone there and
   bracketing (f_lo, f_hi: m - level at the ends); safeguarded Halley */
static double cubic_level_time(double a0, double a1, double a2, double a3, double level,
                               double t_lo, double t_hi, double f_lo, double f_hi)
{
    if (f_lo == 0.0)
        return t_lo;
    int rising = f_lo < 0.0;
    double width = t_hi - t_lo;
    double lo = t_lo, hi = t_hi;
    double t = t_lo + width * f_lo / (f_lo - f_hi);
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
        int is_short = fabs(t_new - t) <= 1e-5 * width;
        if (!(lo < t_new && t_new < hi) || (is_short && fabs(d1) * width < 0.1 * fabs(f_hi - f_lo))) {
            t_new = 0.5 * (lo + hi);
            if (hi - lo <= 1e-10 * width)
                return t_new;
        } else if (is_short) {
            return t_new;
        }
        t = t_new;
    }
    return t;
}

/* free_flight.slope_zeros: the zeros t1 < t2 of m' strictly inside (0, t_end); returns count */
static int slope_zeros(double a1, double a2, double a3, double t_end, double *t1, double *t2)
{
    double a = 3.0 * a3, b = 2.0 * a2, c = a1;
    int n = 0;
    *t1 = t_end;
    *t2 = t_end;
    if (a == 0.0) {
        if (b != 0.0) {
            double r = -c / b;
            if (0.0 < r && r < t_end) {
                *t1 = r;
                n = 1;
            }
        }
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
        *t1 = r1;
        n = 1;
    }
    if (0.0 < r2 && r2 < t_end && r2 > r1) {
        if (n == 0)
            *t1 = r2;
        else
            *t2 = r2;
        n += 1;
    }
    return n;
}

/* free_flight.first_crossing_time: the first t in (0, t_end] where m reaches 0, given
   m(0) = a0 >= 0 > m(t_end) = x_end; a path that falls all the way (the Bernstein control
   points of m' all negative) needs no split at the zeros of m' */
static double first_crossing_time(double a0, double a1, double a2, double a3, double t_end,
                                  double x_end, double v_end)
{
    if (a1 < 0.0 && a1 + a2 * t_end < 0.0 && v_end < 0.0)
        return cubic_level_time(a0, a1, a2, a3, 0.0, 0.0, t_end, a0, x_end);
    double t1, t2;
    int n = slope_zeros(a1, a2, a3, t_end, &t1, &t2);
    double start = 0.0, m_start = a0;
    for (int k = 0; k <= n; k++) {
        double stop = k == 0 && n >= 1 ? t1 : (k == 1 && n == 2 ? t2 : t_end);
        double m_stop = stop == t_end ? x_end : cubic_value(a0, a1, a2, a3, stop);
        if (m_stop <= 0.0)
            return cubic_level_time(a0, a1, a2, a3, 0.0, start, stop, m_start, m_stop);
        start = stop;
        m_start = m_stop;
    }
    return t_end;
}

/* free_flight.mean_path_integrals: E[int_0^tau x] and E[int_0^tau x^2] given the ends of a step
   of length dt (mean path a0 + a1 t + a2 t^2 + a3 t^3, plus the bridge variance of x) */
static void mean_path_integrals(double a0, double a1, double a2, double a3, double dt, double tau,
                                double *int_x, double *int_x2)
{
    *int_x = tau * (a0 + tau * (0.5 * a1 + tau * ((1.0 / 3.0) * a2 + tau * 0.25 * a3)));
    double c0 = a0 * a0;
    double c1 = 2.0 * a0 * a1;
    double c2 = a1 * a1 + 2.0 * a0 * a2;
    double c3 = 2.0 * (a0 * a3 + a1 * a2);
    double c4 = a2 * a2 + 2.0 * a1 * a3;
    double c5 = 2.0 * a2 * a3;
    double c6 = a3 * a3;
    double int_m2 = tau * (c0 + tau * (0.5 * c1 + tau * ((1.0 / 3.0) * c2 + tau * (0.25 * c3 + tau * ((1.0 / 5.0) * c4 + tau * ((1.0 / 6.0) * c5 + tau * (1.0 / 7.0) * c6))))));
    double u = tau / dt;
    double tau2 = tau * tau;
    double int_var = (2.0 / 3.0) * tau2 * tau2 * (0.25 - u * (3.0 / 5.0 - u * (0.5 - u * (1.0 / 7.0))));
    *int_x2 = int_m2 + int_var;
}

/* simulation.step_tallies._bin_index: 0 underflow, n + 1 overflow, edges[0..n] */
static int64_t bin_index(double value, double log_lo, double per_ln, int64_t n, const double *edges)
{
    if (value < edges[0])
        return 0;
    if (value >= edges[n])
        return n + 1;
    int64_t k = (int64_t)((log(value) - log_lo) * per_ln);
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

/* ---------------------------------------------------------------- the loop */

typedef struct {
    double x, v, s, fp, delta, t; /* s: the root at (x, v); fp: f'(s) there */
    int64_t steps, collisions, iterations, restarts;
    double int_x, int_x2;
    int exhausted;
} state_t;

typedef struct {
    double r, c, inv_divisor;
    int64_t max_steps;
    const double *v_edges;
    int64_t nv;
    double v_log_lo, v_per_ln;
    int64_t *speed_counts;
} params_t;

/*
 * Runs until t reaches t_stop; tallies only when `recording` (a constant where inlined).
 *
 * The root of the next step starts from a first-order prediction: with the previous root s0
 * and the slope f'(s0) at the previous state (x0, v0), f at the new state is, to first order,
 * f(s0) = (x1 - x0) + s0^2 (v1 - v0), so s ~ s0 - [(x1 - x0) + s0^2 (v1 - v0)] / f'(s0)
 * = k0 - k1 x1 - k2 v1.  The coefficients come from the previous state, so they are ready
 * (division included) while the step is taken; the prediction adds two fused multiply-adds
 * to the loop's critical path and saves about 0.35 iterations of the root a step.
 */
static ALWAYS_INLINE void run_phase(state_t *state, rng_t *generator, const zig_t *z,
                                    const params_t *p, double t_stop, const int recording)
{
    double x = state->x, v = state->v, s = state->s, fp = state->fp, delta = state->delta;
    double t = state->t;
    int64_t steps = state->steps, collisions = state->collisions;
    int64_t iterations = state->iterations, restarts = state->restarts;
    double int_x = state->int_x, int_x2 = state->int_x2;
    const double r = p->r, c = p->c, inv_divisor = p->inv_divisor;
    const int64_t max_steps = p->max_steps;
    uint64_t s0 = generator->s[0], s1 = generator->s[1], s2 = generator->s[2], s3 = generator->s[3];
    int exhausted = 0;

    while (t < t_stop) {
        if (UNLIKELY(steps >= max_steps)) {
            exhausted = 1;
            break;
        }
        double dt = s * s + delta; /* eq. (criterion) plus delta */
        if (UNLIKELY(!(dt > COLLAPSED_STEP))) {
            exhausted = 1;
            break;
        }
        if (UNLIKELY(t + dt > t_stop))
            dt = t_stop - t;
        /* the predictor's coefficients (off the critical path) */
        double k1 = fp < 0.0 ? 1.0 / fp : 0.0;
        double k2 = k1 * (s * s);
        double k0 = s + k1 * x + k2 * v;
        double normal_r = zig_normal(&s0, &s1, &s2, &s3, z);
        double normal_s = zig_normal(&s0, &s1, &s2, &s3, z);
        double root_2dt = sqrt(2.0 * dt);
        /* eqs. (xstep), (vstep) */
        double x1 = x + dt * (v - 0.5 * dt + root_2dt * (SQRT1_12 * (normal_s + SQRT3 * normal_r)));
        double v1 = v - dt + root_2dt * normal_r;
        steps += 1;
        if (LIKELY(x1 >= 0.0)) {
            if (recording) {
                /* the mean path's integrals through the cubic Hermite mass matrix of the ends,
                   plus int_0^dt Var[x(t) | ends] dt = dt^4 / 210 */
                int_x += dt * (0.5 * (x + x1) + dt * (1.0 / 12.0) * (v - v1));
                double m0 = (13.0 / 35.0) * (x * x + x1 * x1) + (9.0 / 35.0) * (x * x1);
                double m1 = (11.0 / 105.0) * (x * v - x1 * v1) + (13.0 / 210.0) * (x1 * v - x * v1);
                double m2 = (1.0 / 105.0) * (v * v + v1 * v1) - (1.0 / 70.0) * (v * v1);
                int_x2 += dt * (m0 + dt * (m1 + dt * (m2 + dt * (1.0 / 210.0))));
            }
            t += dt;
            x = x1;
            v = v1;
            double predicted = k0 - k1 * x1 - k2 * v1;
            s = criterion_root(x, v, c, predicted > 0.0 ? predicted : s, &fp, &iterations,
                               &restarts);
        } else { /* the step ends where the mean path first reaches 0 */
            double inv_dt = 1.0 / dt;
            double slope = (x1 - x) * inv_dt;
            double a2 = (3.0 * slope - 2.0 * v - v1) * inv_dt;
            double a3 = (v + v1 - 2.0 * slope) * (inv_dt * inv_dt);
            double tau = first_crossing_time(x, v, a2, a3, dt, x1, v1);
            double v_out = r * fabs(cubic_slope(v, a2, a3, tau)); /* eq. (restitution) */
            if (recording) {
                double ix, ix2;
                mean_path_integrals(x, v, a2, a3, dt, tau, &ix, &ix2);
                int_x += ix;
                int_x2 += ix2;
                collisions += 1;
                p->speed_counts[bin_index(v_out, p->v_log_lo, p->v_per_ln, p->nv, p->v_edges)] += 1;
            }
            t += tau;
            x = 0.0;
            v = v_out;
            double root_2delta = v_out * inv_divisor;
            delta = 0.5 * root_2delta * root_2delta;
            s = floor_root(v, c);
            fp = s * (2.0 * v - s * (3.0 * c + 2.0 * s));
        }
    }

    state->x = x;
    state->v = v;
    state->s = s;
    state->fp = fp;
    state->delta = delta;
    state->t = t;
    state->steps = steps;
    state->collisions = collisions;
    state->iterations = iterations;
    state->restarts = restarts;
    state->int_x = int_x;
    state->int_x2 = int_x2;
    state->exhausted = exhausted;
    generator->s[0] = s0;
    generator->s[1] = s1;
    generator->s[2] = s2;
    generator->s[3] = s3;
}

static double cpu_seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

enum {
    OUT_TIME,               /* recorded time */
    OUT_COLLISIONS,         /* recorded collisions */
    OUT_STEPS,              /* recorded steps */
    OUT_INT_X,              /* recorded int x dt */
    OUT_INT_X2,             /* recorded int x^2 dt */
    OUT_ROOT_ITERATIONS,    /* root iterations while recording */
    OUT_ROOT_RESTARTS,      /* cold restarts of the root while recording */
    OUT_CPU_SECONDS,        /* CPU time of the whole call (equilibration included) */
    OUT_RECORDED_CPU,       /* CPU time of the recording alone */
    OUT_EXHAUSTED,          /* 1 if the step budget ran out or the step collapsed */
    OUT_EQUILIBRATION_STEPS /* steps spent equilibrating */
};

/*
 * One shard: equilibrate for `equilibration_time`, then record for `recorded_time`.
 * v_edges has nv + 1 increasing log-spaced edges; speed_counts nv + 2 zeroed entries
 * (0: underflow, nv + 1: overflow); out has 11 entries (the enum above).  Returns 0.
 */
int hand_tuned_run(double r, double c, double divisor, double equilibration_time,
                   double recorded_time, int64_t max_steps, uint64_t seed, const double *v_edges,
                   int64_t nv, int64_t *speed_counts, double *out)
{
    double started = cpu_seconds();
    zig_t z;
    zig_init(&z);
    rng_t g;
    rng_seed(&g, seed);
    params_t p = {r, c, 1.0 / divisor, max_steps, v_edges, nv, log(v_edges[0]), 0.0, speed_counts};
    p.v_per_ln = (double)nv / (log(v_edges[nv]) - p.v_log_lo);
    state_t state = {0};
    state.x = 1.0;
    state.v = 0.0;
    int64_t ignored = 0;
    state.s = criterion_root(1.0, 0.0, c, 0.0, &state.fp, &ignored, &ignored); /* cold */
    state.delta = 0.5 / (divisor * divisor);
    run_phase(&state, &g, &z, &p, equilibration_time, 0);
    int64_t equilibration_steps = state.steps;
    double recording_started = cpu_seconds();
    state.t = 0.0;
    state.steps = 0;
    state.iterations = 0;
    state.restarts = 0;
    if (!state.exhausted)
        run_phase(&state, &g, &z, &p, recorded_time, 1);
    double stopped = cpu_seconds();
    out[OUT_TIME] = state.t;
    out[OUT_COLLISIONS] = (double)state.collisions;
    out[OUT_STEPS] = (double)state.steps;
    out[OUT_INT_X] = state.int_x;
    out[OUT_INT_X2] = state.int_x2;
    out[OUT_ROOT_ITERATIONS] = (double)state.iterations;
    out[OUT_ROOT_RESTARTS] = (double)state.restarts;
    out[OUT_CPU_SECONDS] = stopped - started;
    out[OUT_RECORDED_CPU] = stopped - recording_started;
    out[OUT_EXHAUSTED] = (double)state.exhausted;
    out[OUT_EQUILIBRATION_STEPS] = (double)equilibration_steps;
    return 0;
}

/* n standard normals of the generator seeded with `seed` */
void hand_tuned_normals(uint64_t seed, int64_t n, double *out)
{
    zig_t z;
    zig_init(&z);
    rng_t g;
    rng_seed(&g, seed);
    uint64_t s0 = g.s[0], s1 = g.s[1], s2 = g.s[2], s3 = g.s[3];
    for (int64_t i = 0; i < n; i++)
        out[i] = zig_normal(&s0, &s1, &s2, &s3, &z);
}

/* the criterion root s* at (x, v) from the start s (<= 0: cold); *iterations gets the count */
double hand_tuned_root(double x, double v, double c, double s, int64_t *iterations)
{
    int64_t restarts = 0;
    double fp;
    *iterations = 0;
    return criterion_root(x, v, c, s, &fp, iterations, &restarts);
}
