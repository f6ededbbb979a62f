"""python -m benchmarks [--json] [--scaling]: see benchmarks/benchmark.py."""

from .benchmark import main

main()
