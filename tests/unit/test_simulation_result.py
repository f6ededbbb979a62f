"""simulate and SimulationResult as a scipy or emcee user expects them: a required shard_time,
a SeedSequence root seed, a progress bar, observables() with errors, save and load, and table
names that no Equilibrium function shares."""

import inspect
import io

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import bouncing_ball as bb
from bouncing_ball.parquet import UnreadableFileError, write_table
from bouncing_ball.simulation import SCALARS, SimulationResult, run, seeds, shard_seed_sequence

# short shards: what is tested is the API, not the physics of the estimates
pytestmark = pytest.mark.filterwarnings(
    "ignore::bouncing_ball.simulation.equilibration.EquilibrationWarning"
)

RUN = {"shard_time": 100.0, "settings": {"equilibration_time": 10.0}, "progress": False}


@pytest.fixture(scope="module")
def result():
    """16 shards: enough for the control variates (tallies.SHARDS_PER_CONTROL per control)."""
    return bb.simulate("1/2", shards=16, seed=3, **RUN)


@pytest.fixture(scope="module")
def pair():
    """Two shards seeded by the int 1."""
    return bb.simulate("1/2", shards=2, seed=1, **RUN)


# --- shard_time and the seed


def test_shard_time_is_required_in_the_signature():
    parameter = inspect.signature(bb.simulate).parameters["shard_time"]
    assert parameter.default is inspect.Parameter.empty
    assert parameter.kind is inspect.Parameter.KEYWORD_ONLY


def test_a_shard_settings_must_hold_the_shard_time(pair):
    with pytest.raises(ValueError, match="settings.shard_time = 100.0 differ"):
        bb.simulate("1/2", shards=2, shard_time=50.0, seed=1, settings=pair.settings)


def test_a_seed_sequence_root_extends_the_int_seeds_streams():
    """The int seed n is the root SeedSequence(n); a root's spawn key and pool size lead the
    shard's, followed by (the label's integer, shard)."""
    r_key = int.from_bytes(b"0.5", "big")
    for shard in (0, 5):
        by_int = shard_seed_sequence(7, "0.5", shard)
        assert by_int.entropy == 7 and by_int.spawn_key == (r_key, shard)
        by_root = shard_seed_sequence(np.random.SeedSequence(7), "0.5", shard)
        assert np.array_equal(by_int.generate_state(8), by_root.generate_state(8))
    child = np.random.SeedSequence(7).spawn(2)[1]
    stream = shard_seed_sequence(child, "0.5", 5)
    assert stream.entropy == 7 and stream.spawn_key == (1, r_key, 5)
    assert not np.array_equal(stream.generate_state(8), by_int.generate_state(8))


def test_a_seed_sequence_seed_reproduces_and_is_recorded(pair):
    same = bb.simulate("1/2", shards=2, seed=np.random.SeedSequence(1), **RUN)
    assert same.batch_frame().equals(pair.batch_frame())
    root = np.random.SeedSequence(1).spawn(1)[0]
    spawned = bb.simulate("1/2", shards=2, seed=root, **RUN)
    assert spawned.seed is root and "spawn_key=(0,)" in repr(spawned)
    assert not spawned.batch_frame().equals(pair.batch_frame())


@pytest.mark.parametrize(
    ("seed", "error"),
    [(1.5, TypeError), (True, TypeError), (np.random.default_rng(1), TypeError), (-1, ValueError)],
)
def test_a_seed_that_is_no_root_seed_is_refused(seed, error):
    with pytest.raises(error, match="seed"):
        bb.simulate("1/2", shards=2, seed=seed, **RUN)


# --- the progress bar


class _Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize(
    ("stderr", "notebook", "progress", "shown"),
    [
        (_Terminal, False, True, True),
        (io.StringIO, True, True, True),
        (io.StringIO, False, True, False),
        (_Terminal, False, False, False),
        (io.StringIO, True, False, False),
    ],
)
def test_the_progress_bar_shows_on_a_terminal_and_in_a_notebook_only(
    monkeypatch, stderr, notebook, progress, shown
):
    """Outside a kernel tqdm.auto is tqdm's text bar, so the notebook case is seen on stderr."""
    stream = stderr()
    monkeypatch.setattr("sys.stderr", stream)
    monkeypatch.setattr(run, "_in_notebook", lambda: notebook)
    bar = run._Progress("0.5", 3, progress)
    for done in range(4):
        bar.show(done)
    bar.close()
    assert ("simulate r=0.5" in stream.getvalue() and "3/3" in stream.getvalue()) is shown
    assert bool(stream.getvalue()) is shown


def test_simulate_shows_its_shards_on_a_terminal(monkeypatch):
    monkeypatch.setattr("sys.stderr", _Terminal())
    bb.simulate("1/2", shards=2, seed=1, **{**RUN, "progress": True})
    assert "2/2" in __import__("sys").stderr.getvalue()


# --- observables()


def test_observables_are_every_scalar_with_its_error(result):
    table = result.observables()
    assert table.columns.tolist() == [
        "observable",
        "symbol",
        "estimator",
        "value",
        "error",
        "shards",
        "dof",
    ]
    rows = table.set_index(["observable", "estimator"])
    controls = int(result.summary_table.control_variates.iloc[0])
    assert controls > 0
    for name, (symbol, _) in SCALARS.items():
        plain, controlled = rows.loc[(name, "plain")], rows.loc[(name, "controlled")]
        assert (plain.value, plain.error) == (
            getattr(result, name),
            getattr(result, f"{name}_err"),
        )
        assert (controlled.value, controlled.error) == (
            getattr(result, f"{name}_controlled"),
            getattr(result, f"{name}_controlled_err"),
        )
        assert plain.symbol == symbol and plain.dof == 15 and controlled.dof == 15 - controls
    eigenvalue = rows.loc[("relaxation_eigenvalue", "bounce-chain fit")]
    assert (eigenvalue.value, eigenvalue.error) == (
        result.relaxation_eigenvalue,
        result.relaxation_eigenvalue_err,
    )
    assert (table.shards == 16).all() and (table.error > 0).all()
    assert np.isfinite(table[["value", "error"]].to_numpy()).all()


def test_observables_leave_out_what_two_shards_cannot_estimate(pair):
    """Two shards fit no control variate: only the plain estimates (and lambda, if two lags
    are resolved), each with 1 degree of freedom."""
    table = pair.observables()
    assert set(table.estimator) <= {"plain", "bounce-chain fit"}
    assert set(SCALARS) <= set(table.observable) and (table.dof == 1).all()


def test_every_scalar_property_is_documented():
    for name in SCALARS:
        for column in (name, f"{name}_err", f"{name}_controlled", f"{name}_controlled_err"):
            assert getattr(SimulationResult, column).__doc__, column


# --- table names


def test_no_name_is_a_function_on_equilibrium_and_a_table_on_the_result(pair):
    shared = {
        name
        for name in set(dir(bb.Equilibrium)) & set(dir(SimulationResult))
        if not name.startswith("_")
    }
    for name in shared:
        assert callable(getattr(bb.Equilibrium, name)) == callable(
            getattr(SimulationResult, name)
        ), name
    for name in ("p0v", "px", "pxv", "v2_given_x", "flight_time_density", "summary"):
        assert name not in dir(SimulationResult)
        with pytest.raises(AttributeError, match=f"no attribute '{name}': the table is"):
            getattr(pair, name)


# --- save and load


def _same(one, other):
    assert other.restitution == one.restitution and other.settings == one.settings
    assert (other.shard_indices, other.requested_shards) == (
        one.shard_indices,
        one.requested_shards,
    )
    assert seeds._seed_record(other.seed) == seeds._seed_record(one.seed)
    assert other.batch_frame().equals(one.batch_frame())
    assert other.summary_table.equals(one.summary_table)
    assert other.observables().equals(one.observables())
    for table in ("p0v_histogram", "position_histogram", "pxv_histogram", "flight_time_histogram"):
        assert getattr(other, table).equals(getattr(one, table)), table


def test_a_saved_result_loads_equal(result, tmp_path):
    path = tmp_path / "deep" / "half.parquet"
    result.save(path)
    _same(result, bb.load(path))
    assert pq.read_schema(path).metadata[b"bouncing_ball"]


def test_a_partial_result_with_a_seed_sequence_loads_equal(result, tmp_path):
    partial = SimulationResult(
        restitution=result.restitution,
        seed=np.random.SeedSequence([2**70, 5], spawn_key=(3,), pool_size=8),
        settings=result.settings,
        tallies=(result.tallies[4], result.tallies[1]),
        shard_indices=(4, 1),
        requested_shards=16,
    )
    path = tmp_path / "partial.parquet"
    partial.save(path)
    loaded = bb.load(path)
    _same(partial, loaded)
    assert loaded.partial and loaded.seed.pool_size == 8 and loaded.seed.spawn_key == (3,)


def test_load_refuses_what_save_did_not_write(pair, tmp_path):
    saved = tmp_path / "pair.parquet"
    pair.save(saved)
    cut = tmp_path / "cut.parquet"
    cut.write_bytes(saved.read_bytes()[: saved.stat().st_size // 2])
    workflow_table = tmp_path / "p0v.parquet"
    write_table(pd.DataFrame({"v": [1.0], "p0v": [0.5]}), workflow_table, {"rule": "solve"})
    bare = tmp_path / "bare.parquet"
    pq.write_table(pa.table({"x": [1.0]}), bare)
    for path, match in (
        (cut, "cut.parquet: not a readable Parquet file"),
        (workflow_table, "p0v.parquet: not a saved SimulationResult .written by solve"),
        (bare, "bare.parquet: no 'bouncing_ball' provenance"),
        (tmp_path / "none.parquet", "none.parquet: file not found"),
    ):
        with pytest.raises(UnreadableFileError, match=match):
            bb.load(path)


def test_load_refuses_shards_that_are_not_its_provenances(pair, tmp_path):
    path = tmp_path / "pair.parquet"
    pair.save(path)
    table = pq.read_table(path)
    provenance = pair.provenance()
    write_table(table, path, {**provenance, "shard_indices": [0, 1, 2]})
    with pytest.raises(UnreadableFileError, match="pair.parquet: not a readable SimulationResult"):
        bb.load(path)


def test_load_of_a_folder_of_two_results_names_them(pair, tmp_path):
    """It said the shards were not on the configured bins (pyarrow read both files as one)."""
    pair.save(tmp_path / "run1.parquet")
    pair.save(tmp_path / "run1.seed2.parquet")
    with pytest.raises(UnreadableFileError) as refused:
        bb.load(tmp_path)
    message = str(refused.value)
    assert (
        "a folder, not a file; it holds 2 saved results (run1.parquet, run1.seed2.parquet)"
        in message
    )
    assert "bins" not in message
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(UnreadableFileError, match="empty: a folder, not a file; it holds no saved"):
        bb.load(empty)


def test_save_and_load_expand_the_users_home(pair, tmp_path, monkeypatch):
    """save("~/x.parquet") made a folder named '~'."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    pair.save("~/x.parquet")
    assert (tmp_path / "home" / "x.parquet").is_file() and not (tmp_path / "~").exists()
    _same(pair, bb.load("~/x.parquet"))
