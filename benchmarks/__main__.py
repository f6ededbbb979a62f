"""python -m benchmarks [--json] [--markdown FILE] [--scaling]: see benchmarks/benchmark.py."""

from .benchmark import run_single_threaded

run_single_threaded("benchmarks")
