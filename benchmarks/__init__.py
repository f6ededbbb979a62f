"""Development tools outside the physics library: the benchmark command and the C
reference of the shard loop.  Run from the repository root: ``python -m benchmarks``."""
