# bouncing-ball: Burkhardt & Kotsev, "Equilibrium statistics of an inelastically
# bouncing ball, subject to gravity and a random force", reproduced for any r.
from snakemake.utils import min_version, validate

min_version("9.0")


configfile: "config/config.yaml"


validate(config, "workflow/schemas/config.schema.yaml")


wildcard_constraints:
    r=r"[0-9][0-9.e-]*",
    shard=r"[0-9]+",


localrules:
    all,
    simulation,


include: "workflow/rules/common.smk"
include: "workflow/rules/simulation.smk"


rule all:
    default_target: True
    input:
        simulation_targets(),


# stage target: every simulated r, merged
rule simulation:
    input:
        simulation_targets(),
