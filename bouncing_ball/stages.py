"""The library modules behind each stage of the workflow.

A digest of their source is a parameter of the stage's rules, so an edit of
that code re-runs the stage and nothing else (``bouncing_ball.source_digest``).
Kept apart from the modules so that the workflow can plan a run without
importing numba, scipy or matplotlib.
"""

# "bins" also builds the config's grids; "restitution" parses r and makes the labels
# that key the random streams; "jit" is how the compiled modules are compiled
# "batches" is how a job's shards are run and stored (one file per job)
SIMULATION = (
    "batches",
    "bins",
    "free_flight",
    "jit",
    "restitution",
    "settings",
    "simulation",
    "tallies",
)
MERGE = (
    "audit",
    "batches",
    "bins",
    "equilibration",
    "histograms",
    "io",
    "restitution",
    "settings",
    "shards",
    "tallies",
)
SOLVER = (
    "asymptotics",
    "bins",
    "distribution",
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
    "audit",
    "batches",
    "bins",
    "fits",
    "histograms",
    "io",
    "restitution",
    "settings",
    "shards",
    "tallies",
)
PLOTTING = ("io", "plotting", "restitution")
COMPARISON = ("comparison", "fits", "io", "restitution")
# the studies' reports (workflow/rules/studies.smk); their shards are SIMULATION's
STUDIES = (
    "audit",
    "batches",
    "bins",
    "comparison",
    "exact",
    "fits",
    "histograms",
    "io",
    "restitution",
    "settings",
    "shards",
    "studies",
    "tallies",
)
# results/tables/validation: the comparison, the exact bin averages, the solver curve's bin
# averages, and the shards read back for the sign-flip p-values
VALIDATION = (
    "batches",
    "bins",
    "comparison",
    "exact",
    "fits",
    "histograms",
    "io",
    "restitution",
    "settings",
    "shards",
    "tallies",
)

# what numba compiles: the modules with compiled functions and what those call into or read
# constants from (the key of numba's cache folder, bouncing_ball.jit); an edit elsewhere does
# not recompile
COMPILED = ("distribution", "free_flight", "jit", "kernel", "simulation", "tallies")
