"""A failing job says why in its rule's log, with its traceback, and leaves no half output."""

import copy
import re

from workflow_support import SMALL, copy_repository, snakemake


def test_a_shard_that_recorded_nothing_is_refused_by_the_merge_with_the_reason_in_its_log(
    tmp_path,
):
    """r = 0.5 with a step budget that ends inside equilibration, and r = 0.05 (below r_c)
    with the paper's delta rule alone, whose speed collapses: both merges fail, and each
    merge log names the shard, the reason and the way out, with the traceback."""
    config = copy.deepcopy(SMALL)
    config["restitution"] = [0.5, 0.05]
    config["simulation"].update(shards=2, shard_time=200.0, equilibration_time=50.0)
    config["simulation"]["per_restitution"] = {
        "0.5": {"max_steps": 100},
        "0.05": {"max_steps": 200000},
    }
    directory = copy_repository(tmp_path, config)
    targets = [f"results/simulation/r{label}/summary.parquet" for label in ("0.5", "0.05")]
    result = snakemake(directory, "--keep-going", *targets)
    assert result.returncode != 0
    # one job of shards 0-1 per r (simulation.shards_per_job: 2)
    assert "STEP BUDGET EXHAUSTED" in (directory / "logs/simulation/r0.5/shards0-1.log").read_text()
    budget = (directory / "logs/simulation/r0.5/merge.log").read_text()
    assert re.search(r"shards0-1\.parquet: shard \d recorded no time", budget)
    assert "Raise the budget" in budget
    collapse = (directory / "logs/simulation/r0.05/merge.log").read_text()
    assert "below r_c" in collapse and "simulation.min_step_floor" in collapse
    for log in (budget, collapse):
        assert "Traceback (most recent call last)" in log
    for label in ("0.5", "0.05"):
        folder = directory / "results/simulation" / f"r{label}"
        assert sorted(path.name for path in folder.iterdir()) == ["shards0-1.parquet"]
