"""The edges of a workflow job: its log file, with the traceback when it fails, and its end;
and the end of the run.

Every script under ``scripts/`` runs its work inside
``job_log(snakemake.log[0], exit_when_done=True)``, so a failing job leaves its exception,
with the traceback, in its rule's log (the file Snakemake points to), not only on the console;
a job collects garbage seldom, and a job that succeeds ends its process at once.  The
Snakefile's ``onsuccess`` and ``onerror`` handlers call ``end_pending_timers``, so the run ends
when its last job does.
"""

import gc
import logging
import os
import sys
import threading
from contextlib import contextmanager

#: gc thresholds in a job (``job_log(..., exit_when_done=True)``): Python's are 700, 10, 10.
JOB_GC_THRESHOLDS = (100_000, 50, 100)


@contextmanager
def job_log(path, exit_when_done=False):
    """Log at INFO to ``path`` for the block; an exception is logged with its traceback, then raised.

    Parameters
    ----------
    path : str or pathlib.Path
        The log file.
    exit_when_done : bool, optional
        For a process that is a job and nothing else (a script under ``scripts/``), never
        for one that goes on (a test, a notebook).  The block collects garbage seldom: the
        objects its imports made are frozen out of every collection (``gc.freeze``) and a
        collection waits for ``JOB_GC_THRESHOLDS`` allocations, where a numba compile or a
        matplotlib draw would otherwise run thousands of them (a tenth of a second or more
        of CPU per job, a second in the shard loop's compile, for a few percent more
        memory).  And the process ends as soon as the block succeeds: the log and the
        standard streams are flushed, then ``os._exit(0)``.  That skips the interpreter's
        teardown of its modules, a quarter of a second or more of CPU in a process that has
        loaded numpy, pandas, scipy and matplotlib.  A failing block ends the process as
        Python does.
    """
    if exit_when_done:
        gc.freeze()
        gc.set_threshold(*JOB_GC_THRESHOLDS)
    logging.basicConfig(filename=str(path), level=logging.INFO, format="%(message)s", force=True)
    try:
        yield
    except BaseException:
        logging.exception("the job failed:")
        raise
    finally:
        logging.shutdown()
    if exit_when_done:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)


def end_pending_timers() -> int:
    """Cancel every ``threading.Timer`` still waiting in this process; return how many.

    For Snakemake's own process, from the workflow's ``onsuccess`` and ``onerror`` handlers,
    when every job has ended.  Snakemake's job-rate limiter (``--max-jobs-per-timespan``, at
    least one second) starts a timer at each round of scheduling to wake the scheduler again,
    and the interpreter waits for the last one before it exits: without this, a run ends up to
    a second after its last job.  Nothing is left for a timer to wake by then.

    Returns
    -------
    int
        The timers cancelled.
    """
    pending = [
        thread
        for thread in threading.enumerate()
        if isinstance(thread, threading.Timer) and thread.is_alive()
    ]
    for timer in pending:
        timer.cancel()
    return len(pending)
