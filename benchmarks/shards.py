"""One shard as every benchmark runs it: the default config's settings with a short
equilibration (``SHARD_SETTINGS``), the paper's criterion c beside them, and ``run_shard``, which
``benchmark`` and ``efficiency`` both time."""

from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[1]
PAPER_CRITERION_C = 5.0


def _default_shard_settings():
    """The default config's shard settings (c, the delta rule, the bins), with a short
    equilibration and no step budget to speak of."""
    from bouncing_ball.workflow.config import read_config, shard_settings

    config = read_config(REPOSITORY / "config" / "config.yaml")
    return shard_settings(config, "0.5").replace(equilibration_time=100.0, max_steps=10**13)


SHARD_SETTINGS = _default_shard_settings()


def run_shard(r, recorded_time, shard=0, seed=1, loop=None, **changes):
    """One shard of r with the default settings, ``changes`` applied (``loop``: another
    implementation of ``simulation.simulate_shard``, e.g. the C reference)."""
    from bouncing_ball.restitution import restitution_label
    from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

    settings = SHARD_SETTINGS.replace(shard_time=recorded_time, **changes)
    stream = shard_seed_sequence(seed, restitution_label(r), shard)
    return (loop or simulate_shard)(r, stream, settings)
