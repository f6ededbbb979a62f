"""What the workflow tests share: a small config, a tiny studies file, a copy of the repository,
running Snakemake."""

import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import yaml

REPOSITORY = Path(__file__).resolve().parents[1]
# the small config shared by the workflow tests, CI and the SLURM stage
TEST_CONFIG = REPOSITORY / ".test" / "config" / "config.yaml"
SMALL = yaml.safe_load(TEST_CONFIG.read_text())
FIGURES = [f"results/figures/fig{n}.{ext}" for n in range(1, 14) for ext in ("pdf", "png")]


# the studies file of the studies' tests (test_study_rules.py): 2-4 shards per run of 1e3-2e3
# time units; batches and groups of 2 shards so that every column of the r075 report has a
# number for run c3 and the pooled runs; coverage: 2 runs of 4 shards per r, too few shards for
# the control variates
TINY = {
    "criterion_bias": {
        "restitution": ["1/2", "1/3"],
        "criterion_c": [3.0, 5.0],
        "seed": 7,
        "shards": 2,
        "shard_time": {"1/2": 2.0e3, "1/3": 1.0e3},
        "minimum_count": 5,
    },
    "r075": {
        "restitution": 0.75,
        "shard_time": 2.0e3,
        "batch_size": 2,
        "group_size": 2,
        "runs": {
            "c3": {"criterion_c": 3.0, "seed": 1, "shards": 4},
            "c5": {"criterion_c": 5.0, "seed": 2, "shards": 2},
        },
    },
    "coverage": {
        "restitution": ["1/2", "1/3"],
        "seed": 3,
        "runs": 2,
        "shards": 4,
        "shard_time": {"1/2": 1.0e3, "1/3": 1.0e3},
    },
}


def copy_with_studies(directory, studies):
    """A copy of the repository (``copy_repository``) with ``studies`` as config/studies.yaml."""
    copy_repository(directory, SMALL)
    (directory / "config" / "studies.yaml").write_text(yaml.safe_dump(studies))
    return directory


def copy_repository(tmp_path, config):
    for name in ("Snakefile", "workflow", "scripts", "config", "profiles"):
        source = REPOSITORY / name
        if source.is_dir():
            shutil.copytree(source, tmp_path / name)
        else:
            shutil.copy(source, tmp_path / name)
    (tmp_path / "config" / "config.yaml").write_text(yaml.safe_dump(config))
    return tmp_path


def snakemake(directory, *arguments):
    return subprocess.run(
        [sys.executable, "-m", "snakemake", "--cores", "2", *arguments],
        cwd=directory,
        capture_output=True,
        text=True,
        timeout=600,
    )


def two_at_a_time(function, calls):
    """[function(*arguments) for arguments in calls], two calls at a time: for independent
    Snakemake starts (``snakemake``, ``planned_jobs``), each of which parses the Snakefile in
    a process of its own while this one waits, on CI's two cores."""
    with ThreadPoolExecutor(2) as pool:
        return list(pool.map(lambda arguments: function(*arguments), calls))


def planned_jobs(directory, env=None, *targets):
    """{rule: count} of the jobs a dry run would execute (empty if nothing to do)."""
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            "--cores",
            "2",
            "--dry-run",
            *targets,
            "--quiet",
            "rules",
        ],
        cwd=directory,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    jobs = {}
    lines = (result.stdout + result.stderr).splitlines()
    if "Job stats:" in lines:
        for line in lines[lines.index("Job stats:") + 3 :]:
            parts = line.split()
            if len(parts) != 2 or parts[0] == "total":
                break
            jobs[parts[0]] = int(parts[1])
    return jobs
