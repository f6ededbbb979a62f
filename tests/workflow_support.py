"""What the workflow tests share: a small config, a copy of the repository, running Snakemake."""

import shutil
import subprocess
import sys
from pathlib import Path

import yaml

REPOSITORY = Path(__file__).resolve().parents[1]
# the small config shared by the workflow tests, CI and the SLURM stage
TEST_CONFIG = REPOSITORY / ".test" / "config" / "config.yaml"
SMALL = yaml.safe_load(TEST_CONFIG.read_text())
FIGURES = [f"results/figures/fig{n}.{ext}" for n in range(1, 14) for ext in ("pdf", "png")]


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
