"""Fixtures shared by the test modules."""

from concurrent.futures import ThreadPoolExecutor

import pytest
from workflow_support import SMALL, TINY, copy_repository, copy_with_studies, snakemake

# the fixtures of the long runs that several tests read, the runs they stand for (a config, a
# folder name and snakemake's arguments); those the session's tests ask for (collected by
# pytest_collection_finish)
LONG_RUNS = {
    "finished_run": (lambda directory: copy_repository(directory, SMALL), "workflow", ()),
    "studies_run": (lambda directory: copy_with_studies(directory, TINY), "studies", ("studies",)),
}
_ASKED_FOR = set()


def pytest_collection_finish(session):
    for item in session.items:
        _ASKED_FOR.update(set(LONG_RUNS) & set(getattr(item, "fixturenames", ())))


@pytest.fixture(scope="session", autouse=True)
def background_runs(tmp_path_factory):
    """{fixture name: (directory, future of snakemake's result)} for each of LONG_RUNS that a
    collected test asks for, each in a temporary copy.  Started at the tier's first test, they
    run while the tests before their first reader do (those start one Snakemake at a time, most
    of them short), so CI's second core has work."""
    with ThreadPoolExecutor(2) as pool:
        started = {}
        for name in sorted(_ASKED_FOR):
            prepare, folder, arguments = LONG_RUNS[name]
            directory = prepare(tmp_path_factory.mktemp(folder))
            started[name] = (directory, pool.submit(snakemake, directory, *arguments))
        yield started


def finished(background_runs, name):
    """The directory of the background run ``name``, once it has finished without error."""
    directory, run = background_runs[name]
    result = run.result()
    assert result.returncode == 0, result.stderr[-3000:]
    return directory


@pytest.fixture(scope="session")
def finished_run(background_runs):
    """A complete run of the workflow on the small config, in a temporary copy (do not modify)."""
    return finished(background_runs, "finished_run")


@pytest.fixture(scope="session")
def studies_run(background_runs):
    """`snakemake studies` with TINY (a tiny config/studies.yaml), in a temporary copy."""
    return finished(background_runs, "studies_run")
