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
    "simulation.loop",
    "simulation.step_tallies",
    "tallies",
)
# reading a job's batch files back and merging their shards (workflow.shards checks each file's
# provenance against the config with workflow.audit); the return-law and flight-law controls of
# the estimators read the return-speed law and the flight times (flight_time, kernel) and the
# solver's P(0, v) (solver, asymptotics, jit)
READ_SHARDS = (
    "asymptotics",
    "bins",
    "estimators",
    "flight_time",
    "jit",
    "kernel",
    "solver",
    "restitution",
    "settings",
    "tallies",
    "workflow.audit",
    "workflow.batches",
    "parquet",
    "workflow.io",
    "workflow.shards",
)
MERGE = (*READ_SHARDS, "simulation.equilibration")
SOLVER = (
    "airy",
    "asymptotics",
    "bins",
    "distribution",
    "equilibrium",
    "flight_time",
    "jit",
    "kernel",
    "relaxation",
    "restitution",
    "solver",
    "time_relaxation",
    "workflow.solver_tables",
)
EXACT = ("airy", "bins", "exact")
THEORY = ("asymptotics", "bins")
FITS = (*READ_SHARDS, "asymptotics", "fits")
PLOTTING = ("parquet", "workflow.io", "workflow.plotting", "restitution")
COMPARISON = ("validation", "fits", "parquet", "workflow.io", "restitution")
# the studies' reports (workflow/rules/studies.smk); their shards are SIMULATION's; the
# exact moments of the coverage report are ExactEquilibrium's (equilibrium)
STUDIES = (
    *READ_SHARDS,
    "airy",
    "equilibrium",
    "exact",
    "fits",
    "validation",
    "workflow.studies",
)
# results/tables/validation: the comparison, the exact bin averages, the solver curve's bin
# averages, and the shards read back for the sign-flip p-values
VALIDATION = (*READ_SHARDS, "airy", "exact", "fits", "validation")
