"""Interrupted runs, corrupt files and reruns: the workflow recovers and the numbers do not change."""

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
import yaml
from workflow_support import SMALL, copy_repository, planned_jobs, snakemake, two_at_a_time

from bouncing_ball.workflow.config import shard_settings
from bouncing_ball.workflow.io import read_table

# three shards of r = 1/2, each long enough that a job can be killed mid-run
# (two jobs: shards 0-1 and 2-2, simulation.shards_per_job 2)
LONG = yaml.safe_load(yaml.safe_dump(SMALL)) | {"restitution": [0.5]}
LONG["simulation"]["per_restitution"] = {"0.5": {"shards": 3, "shard_time": 2.5e6}}
TABLES = [f"results/simulation/r0.5/{name}.parquet" for name in ("p0v", "position", "summary")]


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    directory = copy_repository(tmp_path_factory.mktemp("uninterrupted"), LONG)
    result = snakemake(directory, *TABLES)
    assert result.returncode == 0, result.stderr[-3000:]
    return directory


def _shard_processes(directory):
    """Pids of the simulate_shards scripts running in ``directory``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            command = (entry / "cmdline").read_bytes()
            folder = os.readlink(entry / "cwd")
        except OSError:
            continue
        if (
            b"simulate_shards" in command
            and b"snakemake" not in command.split(b"\0")[0]
            and folder == str(directory)
        ):
            found.append(int(entry.name))
    return found


def _start(directory):
    return subprocess.Popen(
        [sys.executable, "-m", "snakemake", "--cores", "2", *TABLES],
        cwd=directory,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
        # as in a terminal: a background job of a non-interactive shell (a CI script, nohup
        # ... &) inherits SIGINT ignored, and Python then never raises KeyboardInterrupt
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )


def _wait_for_a_computing_shard(directory, running_for=1.2, timeout=120):
    """A shard job that has run ``running_for`` seconds (past start-up, inside the loop)."""
    deadline = time.monotonic() + timeout
    seen = {}
    while time.monotonic() < deadline:
        now = time.monotonic()
        for pid in _shard_processes(directory):
            seen.setdefault(pid, now)
            if now - seen[pid] >= running_for:
                return pid
        time.sleep(0.05)
    raise AssertionError("no simulate_shards job was seen running")


def _press_ctrl_c(run, presses=5, patience=1.0):
    """SIGINT to the whole process group, as Ctrl-C in a terminal sends, again after
    ``patience`` seconds while Snakemake still runs, as a user would press it again.
    Snakemake 9.27 swallows a KeyboardInterrupt that arrives while its log handler writes
    a line (logging.py: ``except (KeyboardInterrupt, SystemExit): pass``), so a first
    press can be lost."""
    for _ in range(presses):
        os.killpg(run.pid, signal.SIGINT)
        try:
            run.wait(timeout=patience)
            return
        except subprocess.TimeoutExpired:
            continue


def _assert_same_tables(directory, reference):
    for table in TABLES:
        got, _ = read_table(directory / table)
        expected, _ = read_table(reference / table)
        pd.testing.assert_frame_equal(got, expected, check_exact=True)


def _assert_no_half_files(directory):
    folder = directory / "results/simulation/r0.5"
    for path in folder.glob("*.parquet"):
        read_table(path)  # every file there is whole
    assert not list(folder.glob(".*")), "temporary files left behind"


@pytest.mark.parametrize(
    "how", ["kill the shard job", "kill snakemake and its jobs", "interrupt (Ctrl-C)"]
)
def test_an_interrupted_run_completes_on_rerun_with_the_same_numbers(uninterrupted, tmp_path, how):
    directory = copy_repository(tmp_path, LONG)
    run = _start(directory)
    victim = _wait_for_a_computing_shard(directory)
    if how == "kill the shard job":
        os.kill(victim, signal.SIGKILL)
    elif how == "kill snakemake and its jobs":
        os.killpg(run.pid, signal.SIGKILL)
    else:
        _press_ctrl_c(run)
    output, _ = run.communicate(timeout=300)
    assert run.returncode != 0, output[-2000:]
    assert not (directory / TABLES[2]).exists()
    _assert_no_half_files(directory)
    # what the README tells a user to type: the same command again (after a hard kill of
    # Snakemake itself, its lock stays: snakemake --unlock first, as the message says)
    if how == "kill snakemake and its jobs":
        locked = snakemake(directory, *TABLES)
        assert locked.returncode != 0 and "--unlock" in locked.stdout + locked.stderr
        assert snakemake(directory, "--unlock").returncode == 0
    result = snakemake(directory, *TABLES)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-3000:]
    _assert_same_tables(directory, uninterrupted)
    _assert_no_half_files(directory)


def test_a_truncated_batch_of_shards_is_named_and_forcing_its_rule_recovers(
    uninterrupted, tmp_path
):
    directory = tmp_path / "copy"
    shutil.copytree(uninterrupted, directory)
    batch = directory / "results/simulation/r0.5/shards2-2.parquet"
    content = batch.read_bytes()
    batch.write_bytes(content[: len(content) // 2])
    result = snakemake(directory, *TABLES)
    assert result.returncode != 0
    message = result.stdout + result.stderr
    assert "results/simulation/r0.5/shards2-2.parquet: not a readable Parquet file" in message
    assert "--forcerun results/simulation/r0.5/shards2-2.parquet" in message  # the way out
    assert "pyarrow" not in message.split("shards2-2.parquet: not a readable")[0][-300:]
    # the targets first: --forcerun takes every file after it (with none left, rule all ran)
    result = snakemake(
        directory, *TABLES, "--forcerun", "results/simulation/r0.5/shards2-2.parquet"
    )
    assert result.returncode == 0, result.stderr[-3000:]
    _assert_same_tables(directory, uninterrupted)  # a re-run batch is bit-identical


def test_a_corrupt_merged_table_is_named_by_the_rule_that_reads_it(finished_run, tmp_path):
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    table = directory / "results/simulation/r0.5/p0v.parquet"
    table.write_bytes(b"not parquet at all")
    result = snakemake(
        directory, "results/figures/fig5.pdf"
    )  # newer than fig5: fig5 re-runs, reads it
    assert result.returncode != 0
    assert (
        "results/simulation/r0.5/p0v.parquet: not a readable Parquet file"
        in result.stdout + result.stderr
    )


def test_extreme_r_runs_end_to_end_within_its_budget(tmp_path):
    """r = 0.05 (below r_c, with a floor on delta) and r = 0.85 (slow relaxation): every stage
    finishes; the solver's tables pass their checks; I is infinite below r_c."""
    config = yaml.safe_load(yaml.safe_dump(SMALL)) | {"restitution": [0.05, 0.85]}
    config["simulation"]["per_restitution"] = {
        "0.05": {"min_step_floor": 1.0e-12},
        # the shortest shards the config check accepts there, in relaxation times of r
        "0.85": {"shard_time": {"relaxation_times": 8}},
    }
    directory = copy_repository(tmp_path, config)
    targets = [
        f"results/{kind}/r{label}/summary.parquet"
        for kind in ("simulation", "solver")
        for label in ("0.05", "0.85")
    ]
    result = snakemake(
        directory,
        *targets,
        "results/fits/r0.05.parquet",
        "results/fits/r0.85.parquet",
        "results/tables/moments.csv",
    )
    assert result.returncode == 0, result.stderr[-3000:]
    for label in ("0.05", "0.85"):
        simulated, _ = read_table(directory / f"results/simulation/r{label}/summary.parquet")
        assert simulated.shards_out_of_budget.iloc[0] == 0
        shard_time = shard_settings(config, label).shard_time  # 2e3; 8 relaxation times at 0.85
        assert simulated.total_time.iloc[0] == pytest.approx(3 * shard_time)
        solved, _ = read_table(directory / f"results/solver/r{label}/summary.parquet")
        assert solved.accuracy_estimate.iloc[0] < 1e-8
        # int P dx, within the interpolation error of w(F) at the test config's few nodes
        tolerance = max(1e-8, solved.weight_interpolation_error.iloc[0])
        assert abs(solved.position_normalization.iloc[0] - 1.0) <= tolerance
    below, _ = read_table(directory / "results/solver/r0.05/summary.parquet")
    assert below.collision_rate.iloc[0] == float("inf")
    table = pd.read_csv(directory / "results/tables/moments.csv")
    assert np.isnan(table[(table.r_label == 0.05) & (table.quantity == "collision_rate")].z.iloc[0])


def test_r_outside_the_solver_range_is_refused_before_any_job(tmp_path):
    """Above the range of the whole distribution (0.9995, 0.9999) and below the solver's
    (0.015): refused before any job, naming the target and the range (all-NaN P(x) in a job
    that succeeds, or a crashed solve job, otherwise)."""
    labels = ("0.9995", "0.9999", "0.015")
    # a copy for each, the starts two at a time
    for label in labels:
        (tmp_path / label).mkdir()
    directories = [copy_repository(tmp_path / label, SMALL) for label in labels]
    targets = [f"results/solver/r{label}/summary.parquet" for label in labels]
    results = two_at_a_time(snakemake, zip(directories, targets))
    for directory, result in zip(directories, results):
        assert result.returncode != 0
        assert (
            "outside the range of r where P(x, v) is verified, 0.02 <= r <= 0.999"
            in result.stdout + result.stderr
        )
        assert not (directory / "results/solver").exists()


def test_every_reader_refuses_a_table_of_the_wrong_kind_or_r(finished_run, tmp_path):
    """A table of the wrong kind, or the r = 1/3 solver's tables under the r = 1/2 label (a
    copy, a symlink): each reader names the file instead of drawing a wrong comparison."""
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    results = directory / "results"
    shutil.copy(results / "solver/r0.5/p0v.parquet", results / "theory/exponents.parquet")
    shutil.copy(results / "solver/r0.333333/p0v.parquet", results / "solver/r0.5/p0v.parquet")
    shutil.copy(results / "solver/r0.5/summary.parquet", results / "exact/r0.5/summary.parquet")
    (results / "solver/r0.5/summary.parquet").unlink()
    (results / "solver/r0.5/summary.parquet").symlink_to("../r0.333333/summary.parquet")
    before = {path: path.read_bytes() for path in results.rglob("*.p*")}
    result = snakemake(directory, "--keep-going")
    assert result.returncode != 0
    wrong_kind = "results/theory/exponents.parquet: not a exponents table: written by rule solve"
    wrong_r = "not the same r: results/simulation/r0.5/p0v.parquet (r = 1/2), results/solver/r0.5/p0v.parquet (r = 1/3)"
    expected = {
        "figures/fig1": wrong_kind,
        "figures/fig2": wrong_kind,
        "figures/fig7": wrong_r,
        "fits/r0.5": "results/solver/r0.5/p0v.parquet: solved for r = 0.333333, not r = 0.5",
        "figures/fig6": "results/exact/r0.5/summary.parquet: not a exact summary table",
        "tables/moments": "results/exact/r0.5/summary.parquet: not a exact summary table",
        "tables/position_asymptotics": (
            "results/solver/r0.5/summary.parquet: made for r = 0.333333, not r = 0.5"
        ),
    }
    for log, message in expected.items():
        text = (directory / "logs" / f"{log}.log").read_text()
        assert message in text and "UnreadableFileError" in text, (log, text[-1500:])
    # Fig. 4 and the validation table wait for the fit of r = 1/2, which failed
    # the failed jobs' outputs are gone (Snakemake removes them), nothing else changed
    after = {path: path.read_bytes() for path in results.rglob("*.p*")}
    assert {path: data for path, data in before.items() if path in after} == after


def _copy_with_config(finished_run, tmp_path, change):
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    config = yaml.safe_load((directory / "config/config.yaml").read_text())
    change(config)
    (directory / "config/config.yaml").write_text(yaml.safe_dump(config))
    return directory


def _longer_shards(config):
    config["simulation"]["shard_time"] = 3.0e3


def test_tables_of_another_config_without_snakemakes_record_are_named(finished_run, tmp_path):
    """With .snakemake/ gone Snakemake has no record of the parameters that made a table:
    each table's provenance is compared with the config, before any job."""
    directory = _copy_with_config(finished_run, tmp_path, _longer_shards)
    planned = subprocess.run(
        [sys.executable, "-m", "snakemake", "--cores", "2", "--dry-run"],
        cwd=directory,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert planned.returncode == 0 and "simulate_shards" in planned.stdout  # Snakemake knows
    shutil.rmtree(directory / ".snakemake")
    before = {path: path.stat().st_mtime_ns for path in (directory / "results").rglob("*")}
    result = snakemake(directory)
    message = result.stdout + result.stderr
    assert result.returncode != 0
    assert "results made for another config, which Snakemake has no record of" in message
    assert (
        "results/simulation/r0.5/shards2-2.parquet: shard_time = 2000.0 (config: 3000.0)" in message
    )
    assert "results/simulation/r0.333333/summary.parquet: shard_time = 2000.0" in message
    # the rm command lists the stale files sorted: bounce_chain.parquet comes first
    assert "rm results/simulation/r0.333333/bounce_chain.parquet" in message
    assert " results/simulation/r0.333333/distribution.parquet" in message
    assert " results/simulation/r0.333333/p0v.parquet" in message
    assert {path: path.stat().st_mtime_ns for path in (directory / "results").rglob("*")} == before
    for path in (directory / "results/simulation").rglob("*.parquet"):
        path.unlink()  # as the message says
    assert snakemake(directory, "results/simulation/r0.5/summary.parquet").returncode == 0


def test_a_report_of_results_made_with_another_config_is_refused(finished_run, tmp_path):
    """`snakemake --report` without the run's overlay: the figures drawn from other tables
    and the tables made with other settings are named."""

    def other_panels(config):
        config["figures"]["fig4"] = ["1/3"]

    directory = _copy_with_config(finished_run, tmp_path, other_panels)
    result = snakemake(directory, "--report", str(tmp_path / "report.html"))
    message = result.stdout + result.stderr
    assert result.returncode != 0 and not (tmp_path / "report.html").exists()
    assert "the report would caption results that are not this config's" in message
    assert "results/figures/fig4.png: drawn from results/simulation/r0.5/p0v.parquet" in message
    directory = _copy_with_config(finished_run, tmp_path / "b", _longer_shards)
    result = snakemake(directory, "--report", str(tmp_path / "report.html"))
    assert result.returncode != 0
    assert "results/simulation/r0.5/summary.parquet: shard_time = 2000.0" in result.stderr


def test_a_report_of_other_solver_exact_and_figure_settings_is_refused(finished_run, tmp_path):
    """The captions name exact.positions and figures.return_speeds, and the solver's settings
    shape its tables: each is compared with the provenance of the files the report shows."""

    def other_settings(config):
        config["exact"]["positions"] = [0, 0.5]
        config["figures"]["return_speeds"] = [2.0, 5.0]
        config["solver"]["quadrature_step"] = 0.3

    directory = _copy_with_config(finished_run, tmp_path, other_settings)
    result = snakemake(directory, "--report", str(tmp_path / "report.html"))
    message = result.stdout + result.stderr
    assert result.returncode != 0 and not (tmp_path / "report.html").exists()
    assert "the report would caption results that are not this config's" in message
    assert "results/figures/fig11.png: outgoing_speeds = [0.3, 1.0] (config: [2.0, 5.0])" in (
        message
    )
    for table in ("exact/r0.5/distribution", "exact/r0.333333/summary"):
        assert f"results/{table}.parquet: settings.positions = [0, 0.1] (config: [0, 0.5])" in (
            message
        ), table
    for table in ("solver/r0.333333/p0v", "solver/r0.5/position"):
        assert f"results/{table}.parquet: settings.quadrature_step = 0.25 (config: 0.3)" in (
            message
        ), table
    assert "results/solver/time_averages.parquet: quadrature_step = 0.25 (config: 0.3)" in message
    # without Snakemake's record of the parameters, a run names them too (it would keep them)
    shutil.rmtree(directory / ".snakemake")
    result = snakemake(directory, "--dry-run")
    message = result.stdout + result.stderr
    assert result.returncode != 0
    assert "results made for another config, which Snakemake has no record of" in message
    assert "results/solver/r0.5/summary.parquet: settings.quadrature_step = 0.25" in message
    assert "results/figures/fig11.png: outgoing_speeds = " in message


def test_a_report_after_a_run_is_made(finished_run, tmp_path):
    """`--report-after-run` runs what is missing first (here the theory's table, and the
    figures drawn from it), then writes the report."""
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    (directory / "results/theory/exponents.parquet").unlink()
    report = tmp_path / "report.html"
    result = snakemake(directory, "--report", str(report), "--report-after-run")
    assert result.returncode == 0, result.stderr[-3000:]
    assert (directory / "results/theory/exponents.parquet").exists()
    assert "fig11.png" in report.read_text()


def _with_provenance(path, **changes):
    """Rewrite the provenance of a table in place (a copy from another run, as far as the
    workflow can tell)."""
    table = pq.read_table(path)
    metadata = dict(table.schema.metadata)
    provenance = json.loads(metadata[b"bouncing_ball"]) | changes
    metadata[b"bouncing_ball"] = json.dumps(provenance).encode()
    pq.write_table(table.replace_schema_metadata(metadata), path)


def test_a_batch_of_another_seed_is_refused_by_the_merge_and_its_advice_works(
    finished_run, tmp_path
):
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    batch = "results/simulation/r0.5/shards0-1.parquet"
    _with_provenance(directory / batch, seed=6)
    target = "results/simulation/r0.5/summary.parquet"
    result = snakemake(directory, target)
    assert result.returncode != 0
    log = (directory / "logs/simulation/r0.5/merge.log").read_text()
    assert f"{batch}: seed = 6 (config: 5)" in log
    advice = re.search(r"snakemake --cores 2 --forcerun (.*)", log).group(1).split()
    assert advice == [batch]
    result = snakemake(directory, target, "--forcerun", *advice)
    assert result.returncode == 0, result.stderr[-3000:]
    for table in ("shards0-1", "summary", "p0v"):
        got, _ = read_table(directory / f"results/simulation/r0.5/{table}.parquet")
        expected, _ = read_table(finished_run / f"results/simulation/r0.5/{table}.parquet")
        pd.testing.assert_frame_equal(got, expected, check_exact=True)


def test_a_deleted_batch_file_is_made_again(finished_run, tmp_path):
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    batch = "results/simulation/r0.5/shards2-2.parquet"
    (directory / batch).unlink()
    assert planned_jobs(directory)["simulate_shards"] == 1
    result = snakemake(directory, "simulation")
    assert result.returncode == 0, result.stderr[-3000:]
    for table in ("shards2-2", "summary"):
        got, _ = read_table(directory / f"results/simulation/r0.5/{table}.parquet")
        expected, _ = read_table(finished_run / f"results/simulation/r0.5/{table}.parquet")
        pd.testing.assert_frame_equal(got, expected, check_exact=True)
