"""The pipeline's plumbing: what the Snakemake workflow's rules and scripts need, and a notebook
user never does.

- ``config``: the config's checks that a schema cannot express, and the settings of each job;
- ``stages``: the library modules behind each stage (their digest re-runs what an edit touches);
- ``batches`` and ``shards``: a job's shards stored in one file, and read back;
- ``io``: tables with their provenance, written atomically; ``audit``: results on disk held to
  the config; ``jobs``: a job's log;
- ``plotting``: the figures; ``studies``: the accuracy studies' reports;
- ``solver_tables``: rule solve's tables and checks, from an equilibrium object.

The physics is the package's top level (``bouncing_ball``); nothing there imports from here.
"""
