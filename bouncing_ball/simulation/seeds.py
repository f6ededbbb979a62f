"""The seed of a simulation: the root of every shard's random streams, as ``simulate`` takes it
(an int, a ``numpy.random.SeedSequence``) and as a result records it."""

import numpy as np

from ..settings import whole_number


def _root_seed(seed):
    """The root seed of a run, what reproduces it: ``seed`` as given (an int >= 0 or a
    ``numpy.random.SeedSequence``), or for None a fresh int of the system's entropy."""
    if seed is None:
        return int(np.random.SeedSequence().entropy)
    if isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(
            f"seed must be an int >= 0, a numpy.random.SeedSequence or None, got {seed!r}"
        )
    return whole_number(seed, "seed", 0)


def _seed_record(seed):
    """``seed`` (an int or a SeedSequence) as JSON-ready data: the int, or the SeedSequence's
    entropy, spawn key and pool size (``_seed_from_record`` inverts it)."""
    if not isinstance(seed, np.random.SeedSequence):
        return int(seed)
    entropy = seed.entropy
    entropy = (
        int(entropy)
        if isinstance(entropy, (int, np.integer))
        else [int(value) for value in np.ravel(entropy)]
    )
    return {
        "entropy": entropy,
        "spawn_key": [int(key) for key in seed.spawn_key],
        "pool_size": int(seed.pool_size),
    }


def _seed_from_record(record):
    """The seed of ``_seed_record``'s data."""
    if isinstance(record, dict):
        return np.random.SeedSequence(
            entropy=record["entropy"],
            spawn_key=tuple(record["spawn_key"]),
            pool_size=record["pool_size"],
        )
    return whole_number(record, "seed", 0)


def _seed_text(seed) -> str:
    """``seed`` as the repr shows it, on one line."""
    if not isinstance(seed, np.random.SeedSequence):
        return str(seed)
    record = _seed_record(seed)
    pool = "" if record["pool_size"] == 4 else f", pool_size={record['pool_size']}"
    return (
        f"SeedSequence(entropy={record['entropy']}, spawn_key={tuple(record['spawn_key'])}{pool})"
    )
