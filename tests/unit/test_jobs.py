"""A job's log: its messages, and the traceback when it fails."""

import logging

import pandas as pd
import pytest

from bouncing_ball.workflow.io import (
    UnreadableFileError,
    read_tables_of_one_restitution,
    write_table,
)
from bouncing_ball.workflow.jobs import job_log


def test_a_failing_job_leaves_its_traceback_in_its_log(tmp_path):
    log = tmp_path / "logs" / "job.log"
    log.parent.mkdir()
    with pytest.raises(ZeroDivisionError), job_log(log):
        logging.info("started")
        1 / 0  # noqa: B018
    text = log.read_text()
    assert "started" in text and "Traceback (most recent call last)" in text
    assert "ZeroDivisionError" in text


def test_tables_of_two_r_are_refused_together(tmp_path):
    frame = pd.DataFrame({"v": [1.0]})
    write_table(frame, tmp_path / "a.parquet", {"r": "1/2"})
    write_table(frame, tmp_path / "b.parquet", {"r": "1/2"})
    write_table(frame, tmp_path / "c.parquet", {"r": "1/4"})
    both = read_tables_of_one_restitution(tmp_path / "a.parquet", tmp_path / "b.parquet")
    assert [provenance["r"] for _, provenance in both] == ["1/2", "1/2"]
    with pytest.raises(UnreadableFileError, match="c.parquet"):
        read_tables_of_one_restitution(tmp_path / "a.parquet", tmp_path / "c.parquet")
