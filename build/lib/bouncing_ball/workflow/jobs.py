"""The edges of a workflow job: its log file, with the traceback when it fails.

Every script under ``scripts/`` runs its work inside ``job_log(snakemake.log[0])``,
so a failing job leaves its exception, with the traceback, in its rule's log
(the file Snakemake points to), not only on the console.
"""

import logging
from contextlib import contextmanager


@contextmanager
def job_log(path):
    """Log at INFO to ``path`` for the block; an exception is logged with its traceback, then raised."""
    logging.basicConfig(filename=str(path), level=logging.INFO, format="%(message)s", force=True)
    try:
        yield
    except BaseException:
        logging.exception("the job failed:")
        raise
    finally:
        logging.shutdown()
