"""What the workflow tests share: a small config, a copy of the repository, running Snakemake."""

import shutil
import subprocess
import sys
from pathlib import Path

import yaml

REPOSITORY = Path(__file__).resolve().parents[1]
SMALL = {
    "restitution": [0.5, "1/3"],
    "seed": 5,
    "simulation": {
        "shards": 3,
        "shard_time": 2.0e3,
        "equilibration_time": 50.0,
        "criterion_c": 3.0,
        "min_step_divisor": 500,
        "max_steps": 1.0e9,
        "speed_bins": {"lo": 1.0e-4, "hi": 1.0e2, "per_decade": 10},
        "position_bins": {"lo": 1.0e-3, "hi": 1.0e3, "per_decade": 5},
        "per_restitution": {"1/3": {"shards": 2}},
    },
    "solver": {
        "quadrature_step": 0.25,
        "output_speeds": {"min": 1.0e-4, "max": 50, "points": 41},
        "restitution_grid": {"min": 0.1, "max": 0.9, "points": 5},
    },
    "exact": {
        "positions": [0, 0.1],
        "speeds": {"min": -2, "max": 3, "points": 6},
        "position_grid": {"min": 1.0e-3, "max": 100, "points": 6},
    },
    "theory": {"restitution_grid": {"min": 0.1, "max": 0.9, "points": 9}},
    "fits": {
        "minimum_count": 5,
        "max_bias": 0.5,
        "small_speed_window": "auto",
        "large_speed_window": "auto",
    },
    "figures": {"fig4": [0.5], "fig5": ["1/3", "1/2"], "png_dpi": 60},
}
FIGURES = [f"results/figures/fig{n}.{ext}" for n in range(1, 8) for ext in ("pdf", "png")]


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
