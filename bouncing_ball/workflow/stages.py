"""The library modules behind each stage of the workflow.

A digest of their source is a parameter of the stage's rules, so an edit of
that code re-runs the stage and nothing else (``bouncing_ball.source_digest``).
Kept apart from the modules so that the workflow can plan a run without
importing numba, scipy or matplotlib.
"""

# "bins" also builds the config's grids; "restitution" parses r and makes the labels
# that key the random streams; "jit" is how the compiled modules are compiled
# "workflow.batches" is how a job's shards are run and stored (one file per job)
SIMULATION = (
    "workflow.batches",
    "bins",
    "free_flight",
    "jit",
    "pcg64",
    "restitution",
    "settings",
    "simulation",
    "tallies",
)
MERGE = (
    "workflow.audit",
    "workflow.batches",
    "bins",
    "equilibration",
    "histograms",
    "workflow.io",
    "restitution",
    "settings",
    "workflow.shards",
    "tallies",
)
SOLVER = (
    "asymptotics",
    "bins",
    "distribution",
    "equilibrium",
    "flight_time",
    "jit",
    "kernel",
    "restitution",
    "solver",
)
EXACT = ("bins", "exact")
THEORY = ("asymptotics", "bins")
FITS = (
    "asymptotics",
    "workflow.audit",
    "workflow.batches",
    "bins",
    "fits",
    "histograms",
    "workflow.io",
    "restitution",
    "settings",
    "workflow.shards",
    "tallies",
)
PLOTTING = ("workflow.io", "workflow.plotting", "restitution")
COMPARISON = ("comparison", "fits", "workflow.io", "restitution")
# the studies' reports (workflow/rules/studies.smk); their shards are SIMULATION's
STUDIES = (
    "workflow.audit",
    "workflow.batches",
    "bins",
    "comparison",
    "exact",
    "fits",
    "histograms",
    "workflow.io",
    "restitution",
    "settings",
    "workflow.shards",
    "workflow.studies",
    "tallies",
)
# results/tables/validation: the comparison, the exact bin averages, the solver curve's bin
# averages, and the shards read back for the sign-flip p-values
VALIDATION = (
    "workflow.batches",
    "bins",
    "comparison",
    "exact",
    "fits",
    "histograms",
    "workflow.io",
    "restitution",
    "settings",
    "workflow.shards",
    "tallies",
)
