"""Fixtures shared by the test modules."""

import pytest
from workflow_support import SMALL, copy_repository, snakemake


@pytest.fixture(scope="session")
def finished_run(tmp_path_factory):
    """A complete run of the workflow on the small config, in a temporary copy (do not modify)."""
    directory = copy_repository(tmp_path_factory.mktemp("workflow"), SMALL)
    result = snakemake(directory)
    assert result.returncode == 0, result.stderr[-3000:]
    return directory
