"""Static checks of the cluster profile (profiles/slurm); .ci/slurm.sh runs it on a real SLURM."""

import re

import yaml
from snakemake.cli import get_argument_parser
from workflow_support import REPOSITORY

PROFILE = REPOSITORY / "profiles" / "slurm" / "config.yaml"


def rule_blocks():
    """{rule name: its text} over the Snakefile and workflow/rules/*.smk."""
    blocks = {}
    for path in [
        REPOSITORY / "Snakefile",
        *sorted((REPOSITORY / "workflow" / "rules").glob("*.smk")),
    ]:
        parts = re.split(r"^rule (\w+):\n", path.read_text(), flags=re.MULTILINE)
        for name, body in zip(parts[1::2], parts[2::2]):
            blocks[name] = re.split(r"^\S", body, maxsplit=1, flags=re.MULTILINE)[0]
    return blocks


def local_rules():
    """The rules marked ``localrule: True``: run by Snakemake itself, never submitted."""
    blocks = rule_blocks()
    return {name for name, body in blocks.items() if re.search(r"^\s+localrule: True$", body, re.M)}


def test_the_profile_names_only_options_snakemake_and_the_slurm_plugin_know():
    profile = yaml.safe_load(PROFILE.read_text())
    known = get_argument_parser()._option_string_actions
    unknown = [key for key in profile if f"--{key}" not in known]
    assert not unknown, f"unknown options in {PROFILE}: {unknown} (is the SLURM plugin installed?)"
    assert profile["executor"] == "slurm"
    assert profile["slurm-status-command"] in ("sacct", "squeue")
    assert isinstance(profile["slurm-init-seconds-before-status-checks"], int)
    assert profile["slurm-init-seconds-before-status-checks"] > 0


def test_shards_come_in_batches_and_a_job_asks_for_one_core():
    """The pipeline's and the studies' shards come in batches, one job each
    (simulation.shards_per_job): no rule is grouped, and every job is single-threaded."""
    profile = yaml.safe_load(PROFILE.read_text())
    assert "group-components" not in profile
    blocks = rule_blocks()
    assert not [name for name, body in blocks.items() if re.search(r"\bgroup:", body)]
    batched = {"simulate_shards", "study_batch"}
    assert all("shards{first}-{last}.parquet" in blocks[name] for name in batched)
    assert profile["cores"] == 1


def test_every_submitted_rule_sets_its_resources_and_local_rules_exist():
    blocks = rule_blocks()
    local = local_rules()
    quick = {
        "all",
        "theory",
        "solve",
        "solve_grid",
        "moments_table",
        "validation_table",
        *(f"fig{n}" for n in range(1, 14)),
        "relaxation",
        "quasi_elastic",
    }
    assert quick <= local, f"not local: {sorted(quick - local)}"
    submitted = set(blocks) - local
    assert {"simulate_shards", "merge_shards", "fit", "exact_solution"} <= submitted
    for name in submitted:
        resources = re.search(r"resources:\n((?:\s+\w+=.+\n)+)", blocks[name])
        assert resources, f"rule {name} sets no resources"
        keys = set(re.findall(r"(\w+)=", resources.group(1)))
        assert {"runtime", "mem_mb", "cpus_per_task"} <= keys, f"rule {name}: {sorted(keys)}"
        threads = re.search(r"threads:\n\s+(\S+)", blocks[name])
        assert threads is None or threads.group(1) == "1", (
            f"rule {name}: threads > 1 meets cores: 1"
        )
