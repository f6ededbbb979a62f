"""Checks of the SLURM stage (.ci/slurm.sh): the jobs went through SLURM, the results equal a local run's.

python .ci/slurm_check.py LOCAL_RUN_DIR SLURM_RUN_DIR SLURM_RUN_LOG
"""

import re
import subprocess
import sys
from pathlib import Path

import pandas as pd

from bouncing_ball.workflow.io import read_table

# what the small test config (.test/config/config.yaml: r = 1/2 with 3 shards, 1/3 with 2,
# at most 2 per job: batches 0-1 and 2-2 of r = 1/2, 0-1 of r = 1/3) submits
SUBMITTED = {
    "rule_simulate_shards": 3,
    "rule_merge_shards": 2,
    "rule_fit": 2,
    "rule_exact_solution": 2,
}
# what each may ask SLURM for: the resources of workflow/rules/*.smk (CPUs, minutes, MB); a
# batch asks for 20 minutes per shard
REQUESTED = {
    "rule_simulate_shards": {(1, 2 * 20, 500), (1, 20, 500)},
    "rule_merge_shards": {(1, 10, 1000)},
    "rule_fit": {(1, 10, 1000)},
    "rule_exact_solution": {(1, 10, 500)},
}
LOCAL = ("theory", "solve", "solve_grid", "moments_table")
SUBMISSION = re.compile(r"Job (\S+) has been submitted with SLURM jobid (\d+) \(log: (.+?)\)\.?$")


def fail(message):
    print(f"SLURM stage FAILED: {message}")
    sys.exit(1)


def check_jobs(run_dir, log_text):
    submissions = [SUBMISSION.search(line) for line in log_text.splitlines()]
    submissions = [match for match in submissions if match]
    kinds = {}
    for match in submissions:
        _, slurm_id, log_file = match.groups()
        log_path = Path(log_file)
        kind = log_path.relative_to(run_dir / ".snakemake" / "slurm_logs").parts[0]
        kinds[kind] = kinds.get(kind, 0) + 1
        if not log_path.is_file():
            fail(f"SLURM job {slurm_id}: no log file {log_path}")
        state = subprocess.run(
            ["scontrol", "show", "job", slurm_id], capture_output=True, text=True
        )
        fields = dict(re.findall(r"(\w+)=(\S*)", state.stdout))
        if fields.get("JobState") != "COMPLETED":
            fail(
                f"SLURM job {slurm_id} is not COMPLETED for slurmctld:\n{state.stdout}{state.stderr}"
            )
        hours, minutes, _ = map(int, fields["TimeLimit"].split(":"))
        requested = (
            int(fields["NumCPUs"]),
            60 * hours + minutes,
            int(fields["MinMemoryNode"].rstrip("M")),
        )
        if requested not in REQUESTED.get(kind, ()):
            fail(
                f"SLURM job {slurm_id} ({kind}) asked for (CPUs, minutes, MB) {requested}, "
                f"expected {REQUESTED.get(kind)}"
            )
    if kinds != SUBMITTED:
        fail(f"submitted to SLURM {kinds}, expected {SUBMITTED}")
    if "Falling back to 'sacct'" in log_text:
        fail("the plugin fell back to sacct for job states (MinJobAge too low?)")
    for rule in LOCAL:
        if f"localrule {rule}:" not in log_text:
            fail(f"rule {rule} did not run locally")
    ids = sorted(int(match.group(2)) for match in submissions)
    print(
        f"{len(ids)} SLURM jobs, all COMPLETED for slurmctld, each with its log under "
        f".snakemake/slurm_logs: job ids {ids}; by kind {kinds}; local rules {', '.join(LOCAL)}"
    )


def check_results(local_dir, slurm_dir):
    local = sorted(
        p.relative_to(local_dir) for p in (local_dir / "results").rglob("*") if p.is_file()
    )
    cluster = sorted(
        p.relative_to(slurm_dir) for p in (slurm_dir / "results").rglob("*") if p.is_file()
    )
    if local != cluster:
        fail(
            f"different files: local only {sorted(set(local) - set(cluster))}, "
            f"SLURM only {sorted(set(cluster) - set(local))}"
        )
    tables = 0
    for name in local:
        if name.suffix == ".parquet":
            frame, provenance = read_table(local_dir / name)
            other, other_provenance = read_table(slurm_dir / name)
            try:
                pd.testing.assert_frame_equal(frame, other, check_exact=True)
            except AssertionError as error:
                fail(f"{name} differs between the local and the SLURM run: {error}")
            if provenance != other_provenance:
                fail(f"{name}: provenance differs: {provenance} != {other_provenance}")
            tables += 1
        elif (local_dir / name).read_bytes() != (slurm_dir / name).read_bytes():
            fail(f"{name} differs between the local and the SLURM run")
    print(
        f"{len(local)} result files ({tables} tables, exactly, with provenance) equal a local run's"
    )


def main():
    local_dir, slurm_dir, log = map(Path, sys.argv[1:4])
    check_jobs(slurm_dir, log.read_text())
    check_results(local_dir, slurm_dir)


if __name__ == "__main__":
    main()
