# Helpers for every stage: r labels and exact values, per-r settings, shard lists, targets.
from bouncing_ball.config import check_config, simulation_settings
from bouncing_ball.restitution import exact_string, parse_restitution

try:
    RESTITUTION = check_config(config)  # {label: exact r}, refused before any job runs
except ValueError as error:
    raise ValueError(f"invalid config: {error}") from None


def restitution_value(wildcards):
    """Exact r of a label: from the config, or the label itself read as a number."""
    if wildcards.r in RESTITUTION:
        return exact_string(RESTITUTION[wildcards.r])
    return exact_string(parse_restitution(wildcards.r, f"r label '{wildcards.r}'"))


def settings(wildcards):
    return simulation_settings(config, wildcards.r)


def shard_files(wildcards):
    return expand(
        "results/simulation/r{r}/shard{shard}.parquet",
        r=wildcards.r,
        shard=range(settings(wildcards)["shards"]),
    )


def simulation_targets():
    return expand(
        "results/simulation/r{r}/{table}.parquet",
        r=RESTITUTION,
        table=("p0v", "position", "summary"),
    )
