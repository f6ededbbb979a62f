"""A job's log: its messages, and the traceback when it fails; how a job ends; what a job
imports; how the run ends."""

import logging
import subprocess
import sys
import threading
import time
from pathlib import Path

import pandas as pd
import pytest

from bouncing_ball.workflow.io import (
    UnreadableFileError,
    read_tables_of_one_restitution,
    write_table,
)
from bouncing_ball.workflow.jobs import end_pending_timers, job_log

REPOSITORY = Path(__file__).resolve().parents[2]


def test_a_failing_job_leaves_its_traceback_in_its_log(tmp_path):
    log = tmp_path / "logs" / "job.log"
    log.parent.mkdir()
    with pytest.raises(ZeroDivisionError), job_log(log):
        logging.info("started")
        1 / 0  # noqa: B018
    text = log.read_text()
    assert "started" in text and "Traceback (most recent call last)" in text
    assert "ZeroDivisionError" in text


def _run_job(log, body):
    """A process that runs ``body`` as a job (``job_log(log, exit_when_done=True)``), with an
    exit handler that prints "teardown"."""
    code = f"""
import atexit, logging
from bouncing_ball.workflow.jobs import end_pending_timers, job_log
atexit.register(lambda: print("teardown", flush=True))
with job_log({str(log)!r}, exit_when_done=True):
    logging.info("started")
    print("output", end="")
    {body}
"""
    return subprocess.run(
        [sys.executable, "-c", code], cwd=REPOSITORY, capture_output=True, text=True
    )


def test_a_job_that_succeeds_ends_its_process_at_once_with_its_output_flushed(tmp_path):
    done = _run_job(tmp_path / "job.log", "pass")
    assert done.returncode == 0, done.stderr
    assert done.stdout == "output"  # flushed, and no interpreter teardown (no exit handler)
    assert (tmp_path / "job.log").read_text() == "started\n"


def test_a_job_that_fails_ends_as_python_does_with_its_traceback_logged(tmp_path):
    failed = _run_job(tmp_path / "job.log", "1 / 0")
    assert failed.returncode == 1
    assert failed.stdout == "outputteardown\n" and "ZeroDivisionError" in failed.stderr
    assert "Traceback (most recent call last)" in (tmp_path / "job.log").read_text()


def test_a_job_collects_garbage_seldom_and_a_process_that_goes_on_keeps_pythons_setting(tmp_path):
    code = f"""
import gc
from bouncing_ball.workflow.jobs import JOB_GC_THRESHOLDS, job_log
default = gc.get_threshold()
with job_log({str(tmp_path / "a.log")!r}):
    kept = gc.get_threshold() == default
with job_log({str(tmp_path / "b.log")!r}, exit_when_done=True):
    print(kept, gc.get_threshold() == JOB_GC_THRESHOLDS, gc.get_freeze_count() > 0, end="")
"""
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=REPOSITORY, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == "True True True"


def test_tables_of_two_r_are_refused_together(tmp_path):
    frame = pd.DataFrame({"v": [1.0]})
    write_table(frame, tmp_path / "a.parquet", {"r": "1/2"})
    write_table(frame, tmp_path / "b.parquet", {"r": "1/2"})
    write_table(frame, tmp_path / "c.parquet", {"r": "1/4"})
    both = read_tables_of_one_restitution(tmp_path / "a.parquet", tmp_path / "b.parquet")
    assert [provenance["r"] for _, provenance in both] == ["1/2", "1/2"]
    with pytest.raises(UnreadableFileError, match="c.parquet"):
        read_tables_of_one_restitution(tmp_path / "a.parquet", tmp_path / "c.parquet")


def _modules_after(code: str) -> set[str]:
    """The modules a fresh interpreter holds after running ``code`` in the repository."""
    script = f"import sys\n{code}\nprint(' '.join(sys.modules))"
    result = subprocess.run(
        [sys.executable, "-c", script],
        cwd=REPOSITORY,
        capture_output=True,
        text=True,
        check=True,
    )
    return set(result.stdout.split())


def test_a_simulation_job_writes_its_batch_without_importing_pandas(tmp_path):
    # what scripts/simulate_shards.py imports and does after its loop, on one empty shard
    code = f"""
from bouncing_ball.bins import LogBins
from bouncing_ball.restitution import parse_restitution, restitution_label
from bouncing_ball.settings import ShardSettings
from bouncing_ball.tallies import ShardTallies
from bouncing_ball.workflow.batches import batch_to_table
from bouncing_ball.workflow.io import write_table
from bouncing_ball.workflow.jobs import end_pending_timers, job_log
settings = ShardSettings(
    shard_time=1.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
    max_steps=100, speed_bins=LogBins(0.1, 10.0, 1),
)
shard = ShardTallies.from_loop(settings, ShardTallies.loop_arrays(settings))
write_table(batch_to_table({{0: shard}}), {str(tmp_path / "batch.parquet")!r}, {{"r": "1/2"}})
"""
    assert "pandas" not in _modules_after(code)


def test_a_merge_job_does_not_import_scipy_stats():
    # the modules scripts/merge_shards.py imports
    code = (
        "import bouncing_ball.simulation.equilibration, bouncing_ball.estimators, "
        "bouncing_ball.workflow.shards, bouncing_ball.workflow.io"
    )
    modules = _modules_after(code)
    assert "scipy.special" in modules and "scipy.stats" not in modules


def test_the_run_ends_without_waiting_for_a_pending_timer():
    # Snakemake's job-rate limiter leaves such a timer behind at every round of scheduling
    fired = threading.Event()
    timer = threading.Timer(60.0, fired.set)
    timer.start()
    other = threading.Thread(target=time.sleep, args=(0.2,))
    other.start()
    started = time.perf_counter()
    assert end_pending_timers() == 1
    timer.join(5.0)
    assert not timer.is_alive() and time.perf_counter() - started < 5.0
    assert not fired.is_set()
    other.join()  # a thread that is not a timer runs to its end
    assert end_pending_timers() == 0
