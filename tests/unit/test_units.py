"""Physical units: Equilibrium, ExactEquilibrium and simulate with gravity g and noise Lambda.

Every quantity in units (g, Lambda) is its paper-unit value times L^a T^b (L = Lambda^2 / g^3,
T = Lambda / g^2, eq. (eqmo) rescaled), its arguments divided by theirs; the physics checks
hold in metres and seconds on their own (normalisation, <x> from P(x), the exact r = 1/2).
"""

import copy
import pickle
import re

import numpy as np
import pytest
from scipy import integrate

import bouncing_ball as bb
from bouncing_ball.bins import LogBins
from bouncing_ball.units import DIMENSIONS, PhysicalUnits
from bouncing_ball.workflow import solver_tables

GRAVITY, NOISE = 9.81, 0.05
UNITS = PhysicalUnits(GRAVITY, NOISE)
# a converted argument x L / L is x to a relative 2^-52 or so, and each value moves by that
# times its logarithmic derivative (below 10 at the points used: P(0, v) ~ v^-beta, e^(-q v)
# at v <= 5, P(x) at x <= 10, nu(T) at T <= 10); the values themselves are products, exact to
# 2^-52; so 1e-12 is far above the rounding and far below any dimensional mistake.
ROUNDING = 1e-12


@pytest.fixture(scope="module", params=["exact", "solver"])
def pair(request):
    """(in the paper's units, in UNITS) at r = 1/2."""
    if request.param == "exact":
        return bb.ExactEquilibrium("1/2"), bb.ExactEquilibrium("1/2", gravity=GRAVITY, noise=NOISE)
    return bb.Equilibrium("1/2"), bb.Equilibrium("1/2", gravity=GRAVITY, noise=NOISE)


def _length(x):
    return np.asarray(x, dtype=float) * UNITS.length


def _speed(v):
    return np.asarray(v, dtype=float) * UNITS.speed


def _time(t):
    return np.asarray(t, dtype=float) * UNITS.time


# each public member: (its value in UNITS given arguments in UNITS, its value in the paper's
# units given the same arguments in the paper's, its dimension)
MEMBERS = {
    "r": (lambda eq: eq.r, "dimensionless"),
    "restitution": (lambda eq: float(eq.restitution), "dimensionless"),
    "beta": (lambda eq: eq.beta, "dimensionless"),
    "m": (lambda eq: eq.m, "dimensionless"),
    "q": (lambda eq: eq.q, "per_speed"),
    "collision_rate": (lambda eq: eq.collision_rate, "rate"),
    "mean_x": (lambda eq: eq.mean_x, "length"),
    "delta_x": (lambda eq: eq.delta_x, "length"),
    "mean_flight_time": (lambda eq: eq.mean_flight_time, "time"),
    "flight_time_second_moment": (lambda eq: eq.flight_time_second_moment, "time_squared"),
    "accuracy": (lambda eq: eq.accuracy, "dimensionless"),
    "position_accuracy": (lambda eq: eq.position_accuracy, "dimensionless"),
    "distribution_available": (lambda eq: float(eq.distribution_available), "dimensionless"),
    "smallest_speed": (lambda eq: eq.smallest_speed, "speed"),
    "smallest_force": (lambda eq: eq.smallest_force, "per_length"),
    "p0v": (lambda eq, s: eq.p0v(s(_speed)([0.1, 1.0, 5.0])), "phase_space_density"),
    "px": (lambda eq, s: eq.px(s(_length)([0.0, 0.1, 1.0, 10.0])), "per_length"),
    "v2_given_x": (lambda eq, s: eq.v2_given_x(s(_length)([0.1, 1.0, 10.0])), "speed_squared"),
    "pxv": (
        lambda eq, s: eq.pxv(s(_length)(1.0), s(_speed)([-1.0, 0.0, 1.0])),
        "phase_space_density",
    ),
    "weight": (
        lambda eq, s: eq.weight(1.0 / s(_length)([10.0, 1.0, 0.1])),
        "per_root_length",
    ),
    "flight_rate_density": (
        lambda eq, s: eq.flight_rate_density(s(_time)([0.1, 1.0, 10.0])),
        "rate_per_time",
    ),
    "flight_time_density": (
        lambda eq, s: eq.flight_time_density(s(_time)([0.1, 1.0, 10.0])),
        "rate",
    ),
    "return_speed_density": (
        lambda eq, s: eq.return_speed_density(s(_speed)([0.5, 1.0]), s(_speed)(1.0)),
        "per_speed",
    ),
    "p0v_bin_average": (
        lambda eq, s: eq.p0v_bin_average(s(_speed)([0.01, 0.5]), s(_speed)([0.02, 10.0])),
        "phase_space_density",
    ),
    "px_bin_average": (
        lambda eq, s: eq.px_bin_average(s(_length)([0.0, 1.0]), s(_length)([1e-3, 3.0])),
        "per_length",
    ),
    "v2_given_x_bin_average": (
        lambda eq, s: eq.v2_given_x_bin_average(s(_length)([0.0, 1.0]), s(_length)([0.1, 3.0])),
        "speed_squared",
    ),
    "pxv_cell_average": (
        lambda eq, s: eq.pxv_cell_average(
            s(_length)(1.0), s(_length)(1.5), s(_speed)([-1.0, 0.5]), s(_speed)([-0.5, 1.0])
        ),
        "phase_space_density",
    ),
    "relaxation_eigenvalue": (lambda eq: eq.relaxation_eigenvalue, "dimensionless"),
    "correlation_bounces": (lambda eq: eq.correlation_bounces, "dimensionless"),
    "relaxation_time": (lambda eq: eq.relaxation_time, "time"),
    "relaxation_rate": (lambda eq: eq.relaxation_rate, "rate"),
    "bounce_chain_time": (lambda eq: eq.bounce_chain_time, "time"),
    "relaxation_rate_accuracy": (lambda eq: eq.relaxation_rate_accuracy, "dimensionless"),
    "relaxation_accuracy": (lambda eq: eq.relaxation_accuracy, "dimensionless"),
}
# the observables() dict, by key
OBSERVABLE_DIMENSIONS = {
    "r": "dimensionless",
    "beta": "dimensionless",
    "m": "dimensionless",
    "q": "per_speed",
    "collision_rate": "rate",
    "mean_x": "length",
    "delta_x": "length",
    "mean_flight_time": "time",
    "flight_time_second_moment": "time_squared",
    "accuracy": "dimensionless",
}
# the solver's own objects, in the paper's units whatever the units, and the units themselves
PAPER_ONLY = {"solution", "weight_function", "units", "observables"}


def _public(cls):
    return {name for name in dir(cls) if not name.startswith("_")}


def _value(member, eq, physical):
    call, _ = MEMBERS[member]
    if call.__code__.co_argcount == 1:
        return call(eq)
    # the arguments in the object's units: converted for the physical one
    return call(eq, (lambda convert: convert) if physical else (lambda _: np.asarray))


def test_every_member_is_its_paper_value_times_its_unit(pair):
    """Dimensional consistency: each public member of EquilibriumBase, its arguments in
    metres and seconds, is the paper-unit value times L^a T^b of its dimension."""
    assert set(MEMBERS) | PAPER_ONLY == _public(bb.EquilibriumBase)
    paper, physical = pair
    for name in MEMBERS:
        factor = UNITS.factor(MEMBERS[name][1])
        expected = np.asarray(_value(name, paper, False), dtype=float) * factor
        got = np.asarray(_value(name, physical, True), dtype=float)
        np.testing.assert_allclose(got, expected, rtol=ROUNDING, atol=0.0, err_msg=name)
    observables = physical.observables()
    assert set(observables) == set(OBSERVABLE_DIMENSIONS)
    for key, value in paper.observables().items():
        factor = UNITS.factor(OBSERVABLE_DIMENSIONS[key])
        assert observables[key] == pytest.approx(value * factor, rel=ROUNDING, abs=0.0), key
    assert physical.units == UNITS and paper.units == PhysicalUnits()
    assert physical.solution is paper.solution or type(paper) is bb.ExactEquilibrium


def test_the_solve_is_shared_whatever_the_units():
    assert (
        bb.Equilibrium("1/2", gravity=GRAVITY, noise=NOISE).solution
        is bb.Equilibrium("1/2").solution
    )


def test_the_paper_units_are_the_default_and_bit_identical():
    default, ones = bb.Equilibrium("1/2"), bb.Equilibrium("1/2", gravity=1, noise=1.0)
    assert default.units.is_paper and ones.units.is_paper
    x = np.array([0.1, 1.0, 10.0])
    assert np.array_equal(default.px(x), ones.px(x)) and default.mean_x == ones.mean_x


@pytest.mark.parametrize("cls", [bb.Equilibrium, bb.ExactEquilibrium])
def test_pickle_and_copy_carry_the_units(cls):
    eq = cls("1/2", gravity=GRAVITY, noise=NOISE)
    for twin in (pickle.loads(pickle.dumps(eq)), copy.copy(eq), copy.deepcopy(eq)):
        assert twin.units == UNITS and twin.mean_x == eq.mean_x


def test_the_physics_holds_in_metres_and_seconds():
    """int P dx = 1 and <x> from P(x) over x in metres; rho(T) integrates to 1 over T in
    seconds; the exact r = 1/2 <x> = 6 L and I = 1 / (3 T) (eq. (P(x)2)), so <x> and Delta x
    go as g^-3 Lambda^2 and I as g^2 Lambda^-1, the paper's closing paragraph."""
    eq = bb.ExactEquilibrium("1/2", gravity=GRAVITY, noise=NOISE)
    length, time = NOISE**2 / GRAVITY**3, NOISE / GRAVITY**2
    assert eq.mean_x == pytest.approx(6.0 * length, rel=1e-10)
    assert eq.collision_rate == pytest.approx(1.0 / (3.0 * time), rel=1e-10)
    # quadrature tolerances 1e-10 relative; P(x) ~ x^((1 - beta)/3) = x^0 at x -> 0 (beta = 1)
    options = {"epsabs": 0.0, "epsrel": 1e-10, "limit": 200}
    # over x in metres, on pieces that follow P(x)'s scale (quad's map of (0, inf) does not)
    edges = (0.0, length, 10.0 * length, 100.0 * length, np.inf)
    norm, mean = (
        sum(
            integrate.quad(lambda x, k=k: x**k * float(eq.px(x)), lo, hi, **options)[0]
            for lo, hi in zip(edges[:-1], edges[1:], strict=True)
        )
        for k in (0, 1)
    )
    assert norm == pytest.approx(1.0, rel=1e-8)
    assert mean == pytest.approx(eq.mean_x, rel=1e-8)
    solver = bb.Equilibrium(0.6, gravity=GRAVITY, noise=NOISE)
    # rho(T) dT = T rho(T) d ln T by Gauss-Legendre on panels of half a decade in ln T, from
    # 1e-14 T to 1e4 T: rho ~ T^(-beta/2) below (eq. (short)), so the part left out there is
    # of order (1e-14)^(1 - beta/2) = 1e-9 at beta = 0.73; above, rho has fallen to nothing
    nodes, weights = np.polynomial.legendre.leggauss(20)
    edges = np.linspace(np.log(1e-14 * time), np.log(1e4 * time), 37)
    lo, hi = edges[:-1, None], edges[1:, None]
    times = np.exp(0.5 * (lo + hi) + 0.5 * (hi - lo) * nodes)
    mass = 0.5 * (hi - lo) * weights * times * solver.flight_time_density(times)
    assert np.sum(mass) == pytest.approx(1.0, rel=1e-7)
    assert np.sum(mass * times) == pytest.approx(solver.mean_flight_time, rel=1e-7)


@pytest.fixture(scope="module")
def runs():
    """The same run (seed, shards, shard time) in the paper's units and in UNITS."""
    shard_time, equilibration = 300.0, 1000.0
    paper = bb.simulate(
        0.6,
        shards=16,
        shard_time=shard_time,
        seed=11,
        settings={"equilibration_time": equilibration},
        progress=False,
    )
    physical = bb.simulate(
        0.6,
        shards=16,
        shard_time=shard_time * UNITS.time,
        seed=11,
        settings={"equilibration_time": equilibration * UNITS.time},
        progress=False,
        gravity=GRAVITY,
        noise=NOISE,
    )
    return paper, physical


def test_simulate_in_units_is_the_paper_run_times_its_units(runs):
    paper, physical = runs
    # the shards ran on the same streams for the same times (to a rounding of the times)
    assert physical.settings.shard_time == pytest.approx(paper.settings.shard_time, rel=1e-15)
    assert physical.units == UNITS and paper.units.is_paper
    for name, dimension in (("mean_x", "length"), ("collision_rate", "rate")):
        for suffix in ("", "_err"):
            assert getattr(physical, name + suffix) == pytest.approx(
                getattr(paper, name + suffix) * UNITS.factor(dimension), rel=ROUNDING
            )
    assert physical.total_time == pytest.approx(paper.total_time * UNITS.time, rel=ROUNDING)
    for table, columns in (
        ("px_histogram", {"x_lo": "length", "x": "length", "px": "per_length"}),
        ("p0v_histogram", {"v_hi": "speed", "p0v": "phase_space_density", "count": None}),
        ("flight_time_histogram", {"t_lo": "time", "density": "rate"}),
        ("pxv_histogram", {"v_lo": "speed", "pxv_err": "phase_space_density"}),
    ):
        ours, theirs = getattr(physical, table), getattr(paper, table)
        for column, dimension in columns.items():
            factor = 1.0 if dimension is None else UNITS.factor(dimension)
            np.testing.assert_allclose(
                ours[column], theirs[column] * factor, rtol=ROUNDING, err_msg=f"{table}.{column}"
            )
    table = physical.observables().set_index(["observable", "estimator"])
    reference = paper.observables().set_index(["observable", "estimator"])
    assert list(table.index) == list(reference.index)
    dimensions = {
        "collision_rate": "rate",
        "mean_x": "length",
        "delta_x": "length",
        "mean_flight_time": "time",
        "flight_time_second_moment": "time_squared",
        "relaxation_eigenvalue": "dimensionless",
    }
    for (observable, estimator), row in table.iterrows():  # every estimator, martingale too
        factor = UNITS.factor(dimensions[observable])
        for column in ("value", "error"):
            assert row[column] == pytest.approx(
                reference.loc[(observable, estimator), column] * factor, rel=ROUNDING
            ), (observable, estimator, column)


def test_simulate_in_units_agrees_with_equilibrium_in_units(runs):
    """<x> simulated in metres against Equilibrium's: z = (sim - eq) / err, Student t with
    15 dof; |z| > 5 has probability 2e-3 under the null."""
    _, physical = runs
    eq = bb.Equilibrium(0.6, gravity=GRAVITY, noise=NOISE)
    z = (physical.mean_x - eq.mean_x) / physical.mean_x_err
    assert abs(z) < 5.0
    compared = bb.compare(eq, physical).set_index(["quantity", "estimator"])
    assert compared.loc[("mean_x", "plain"), "z"] == pytest.approx(z, rel=1e-12)
    with pytest.raises(ValueError, match="same gravity and noise"):
        bb.compare(bb.Equilibrium(0.6), physical)


def test_save_and_load_carry_the_units(runs, tmp_path):
    _, physical = runs
    path = tmp_path / "units.parquet"
    physical.save(path)
    loaded = bb.load(path)
    assert loaded.units == UNITS and loaded.mean_x == physical.mean_x


@pytest.mark.parametrize(
    ("arguments", "error", "match"),
    [
        ({"gravity": 0.0}, ValueError, "gravity must be positive and finite"),
        ({"gravity": -9.81}, ValueError, "gravity must be positive and finite"),
        ({"noise": np.inf}, ValueError, "noise must be positive and finite"),
        ({"noise": np.nan}, ValueError, "noise must be positive and finite"),
        ({"gravity": "9.81"}, TypeError, "gravity must be a real number"),
        ({"noise": True}, TypeError, "noise must be a real number"),
        ({"gravity": 1e-200}, ValueError, "not a finite, normal double"),
    ],
)
def test_bad_gravity_or_noise_is_refused(arguments, error, match):
    for make in (
        lambda: bb.Equilibrium("1/2", **arguments),
        lambda: bb.ExactEquilibrium("1/2", **arguments),
        lambda: bb.simulate(0.6, shards=2, shard_time=1.0, progress=False, **arguments),
    ):
        with pytest.raises(error, match=match):
            make()


def test_bounds_are_named_in_the_units_given():
    eq = bb.ExactEquilibrium("1/2", gravity=GRAVITY, noise=NOISE)
    largest = 1e12 * UNITS.length
    with pytest.raises(ValueError, match=re.escape(f"x <= {largest:g}")):
        eq.px(2.0 * largest)
    assert set(DIMENSIONS) >= {dimension for _, dimension in MEMBERS.values()}


@pytest.mark.parametrize(
    "table",
    [
        lambda eq: solver_tables.p0v_table(eq, [1.0]),
        lambda eq: solver_tables.position_table(eq, [1.0]),
        lambda eq: solver_tables.distribution_table(eq, [0.5], [1.0]),
        lambda eq: solver_tables.weight_table(eq, [1.0]),
        lambda eq: solver_tables.flight_time_table(eq, [1.0]),
        lambda eq: solver_tables.return_speed_table(eq, LogBins(0.1, 10.0, 1)),
        lambda eq: solver_tables.summary(eq),
        lambda eq: solver_tables.check(eq, {}),
    ],
    ids=[
        "p0v_table",
        "position_table",
        "distribution_table",
        "weight_table",
        "flight_time_table",
        "return_speed_table",
        "summary",
        "check",
    ],
)
def test_rule_solves_tables_refuse_an_equilibrium_in_physical_units(table):
    """The tables of rule solve are in the paper's units: an equilibrium in metres and seconds
    is refused, naming the argument and its units, before anything is computed."""
    equilibrium = bb.Equilibrium("1/2", gravity=GRAVITY, noise=NOISE)
    with pytest.raises(ValueError, match=r"^equilibrium: .*paper's units.*gravity = 9.81"):
        table(equilibrium)


def test_simulate_refuses_a_shard_time_quoting_it_as_given():
    with pytest.raises(ValueError, match=r"shard_time must be positive and finite, got -0.5$"):
        bb.simulate(0.5, shards=2, shard_time=-0.5, gravity=GRAVITY, noise=NOISE)


def test_the_equilibration_warnings_quote_times_in_the_units_given():
    """The same problems as in the paper's units, every time in those given (Lambda / g^2 s)."""
    from bouncing_ball.simulation.equilibration import equilibration_problems

    paper = equilibration_problems(0.95, 2e3, 50.0)
    given = equilibration_problems(0.95, 2e3, 50.0, units=UNITS)
    assert len(given) == len(paper) == 2
    assert f"equilibration_time = {UNITS.to_physical(50.0, 'time'):g} is" in given[0]
    assert f"shard_time = {UNITS.to_physical(2e3, 'time'):g} is" in given[1]
    each = re.compile(r"\(([0-9.e+-]+) each\)")
    for ours, theirs in zip(given, paper):
        ratio = float(each.search(ours)[1]) / float(each.search(theirs)[1])
        assert ratio == pytest.approx(UNITS.to_physical(1.0, "time"), rel=1e-5)  # 6 digits


def test_simulate_warns_in_the_units_given(monkeypatch):
    """simulate hands its units to the equilibration warnings (which quote its times in them)."""
    from bouncing_ball.simulation import equilibration

    class Warned(Exception):
        pass

    def warn(restitution, shard_time, equilibration_time, units=None):
        raise Warned(units)

    monkeypatch.setattr(equilibration, "warn_equilibration_problems", warn)
    with pytest.raises(Warned) as warned:
        bb.simulate(0.5, shards=2, shard_time=1.0, gravity=GRAVITY, noise=NOISE)
    assert warned.value.args[0] == UNITS
