"""A shard's work is bounded by its step budget; its tallies add up."""

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from bouncing_ball.bins import LogBins
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

REPOSITORY = Path(__file__).resolve().parents[1]


def _run(recorded_time, equilibration_time, max_steps, r=0.5):
    return simulate_shard(
        restitution=r,
        seed_sequence=shard_seed_sequence(2, str(r), 0),
        recorded_time=recorded_time,
        equilibration_time=equilibration_time,
        criterion_c=5.0,
        min_step_divisor=500.0,
        max_steps=max_steps,
        speed_bins=LogBins(1e-4, 1e2, 10),
        position_bins=LogBins(1e-3, 1e3, 5),
    )


def test_budget_stops_a_shard_and_says_so():
    full = _run(2000.0, 10.0, 10**9)
    assert full.budget_exhausted == 0 and full.time == pytest.approx(2000.0)
    cut = _run(2000.0, 10.0, full.steps // 2)
    assert cut.budget_exhausted == 1
    assert 0.0 < cut.time < 2000.0
    assert cut.steps < full.steps // 2  # the budget counts equilibration steps too


def test_position_tallies_cover_the_recorded_time():
    shard = _run(5000.0, 10.0, 10**9, r=0.75)
    assert shard.position_time.sum() == pytest.approx(shard.time, rel=1e-12)
    assert shard.position_time.min() >= 0.0 and shard.position_v2_time.min() >= 0.0
    assert shard.speed_counts.sum() == shard.collisions


def test_merge_refuses_a_shard_that_recorded_nothing(tmp_path):
    config = yaml.safe_load((REPOSITORY / "config" / "config.yaml").read_text())
    config["simulation"].update(max_steps=100, equilibration_time=100.0)
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(config))
    shard = tmp_path / "shard0.parquet"
    made = subprocess.run(
        [
            sys.executable,
            "scripts/simulate_shard.py",
            "--restitution",
            "0.5",
            "--shard",
            "0",
            "--config",
            str(tmp_path / "config.yaml"),
            "--shard-time",
            "10",
            str(shard),
        ],
        cwd=REPOSITORY,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert made.returncode == 0 and "STEP BUDGET EXHAUSTED" in made.stderr
    merged = subprocess.run(
        [
            sys.executable,
            "scripts/merge_shards.py",
            "--restitution",
            "0.5",
            *[f"--{name}={tmp_path / name}.parquet" for name in ("p0v", "position", "summary")],
            str(shard),
        ],
        cwd=REPOSITORY,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert merged.returncode != 0
    assert "shard0.parquet: recorded no time" in merged.stderr
    assert not list(tmp_path.glob("p0v*"))  # nothing half-written
