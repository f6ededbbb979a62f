# bouncing-ball: Burkhardt & Kotsev, "Equilibrium statistics of an inelastically
# bouncing ball, subject to gravity and a random force", reproduced for any r.
from snakemake.utils import min_version, validate

min_version("9.0")


configfile: "config/config.yaml"


validate(config, "workflow/schemas/config.schema.yaml")


include: "workflow/rules/common.smk"
include: "workflow/rules/simulation.smk"


rule all:
    input:
        simulation_targets(),
    default_target: True


rule simulation:
    input:
        simulation_targets(),
