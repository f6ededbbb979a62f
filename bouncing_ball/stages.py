"""The library modules behind each stage of the workflow.

A digest of their source is a parameter of the stage's rules, so an edit of
that code re-runs the stage and nothing else (``bouncing_ball.source_digest``).
Kept apart from the modules so that the workflow can plan a run without
importing numba, scipy or matplotlib.
"""

SIMULATION = ("bins", "free_flight", "simulation", "tallies")
MERGE = ("bins", "histograms", "shards", "tallies")
SOLVER = ("asymptotics", "kernel", "solver")
EXACT = ("exact",)
THEORY = ("asymptotics",)
FITS = ("asymptotics", "bins", "fits", "histograms", "io", "shards", "tallies")
PLOTTING = ("plotting",)
COMPARISON = ("comparison", "fits")
