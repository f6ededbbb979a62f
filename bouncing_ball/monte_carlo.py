"""The Monte Carlo simulation of the paper's Sec. IV from Python: ``simulate`` runs shards (in
this process or on several) and returns a ``SimulationResult`` with the observables of
``Equilibrium`` and their jackknife errors.

It is the workflow's machinery, called directly: shard k of r draws from
``simulation.shard_seed_sequence(seed, label of r, k)`` (``workflow.batches.simulate_batch``), so a
shard of ``simulate`` is the workflow's shard k for the same seed and settings, whatever the
number of processes; the tables are ``histograms``' (the workflow's merge stage).

A Ctrl-C stops the run at once and keeps the shards that finished (``SimulationInterrupted``):
in this process a shard runs in a thread of its own, which the Ctrl-C stops (``_run_here``), and
the worker processes are killed; they never outlive the process that started them
(``_watch_parent``).
"""

import contextlib
import math
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property

import numpy as np

from .restitution import parse_restitution, restitution_label
from .settings import MAX_SHARDS, ShardSettings, real_number
from .units import PhysicalUnits

__all__ = [
    "simulate",
    "SimulationResult",
    "SimulationInterrupted",
    "load",
    "DEFAULT_SETTINGS",
    "SCALARS",
    "COLUMN_DIMENSIONS",
]

# the shard settings ``simulate`` uses where it is not told otherwise (the default config's
# ``simulation`` section holds the workflow's); every bin set is ``ShardSettings``' default,
# and equilibration_time follows from the relaxation time at r
# (``equilibration.default_equilibration_time``)
DEFAULT_SETTINGS = {
    "criterion_c": 3.0,
    "min_step_divisor": 500.0,
    "max_steps": 10**9,
}


def _shard_settings(shard_time, settings, restitution):
    """The ``ShardSettings`` of a call at r = ``restitution``: ``settings`` (a ShardSettings,
    whose own shard_time must be ``shard_time``, or a mapping of overrides of
    DEFAULT_SETTINGS and of the default equilibration time) with ``shard_time``."""
    shard_time = real_number(shard_time, "shard_time")
    if not 0.0 < shard_time < math.inf:
        raise ValueError(f"shard_time must be positive and finite, got {shard_time!r}")
    if isinstance(settings, ShardSettings):
        if float(settings.shard_time) != shard_time:
            raise ValueError(
                f"shard_time = {shard_time!r} and settings.shard_time = {settings.shard_time!r} "
                "differ; a ShardSettings' shard_time must be simulate's shard_time "
                "(settings.replace(shard_time=...) makes one that is)"
            )
        return settings
    if settings is not None and not isinstance(settings, dict):
        raise TypeError(
            f"settings must be a ShardSettings or a dict of shard settings, got {settings!r}"
        )
    overrides = dict(settings or {})
    unknown = sorted(set(overrides) - set(ShardSettings.names()))
    if unknown:
        raise ValueError(
            f"settings: unknown key(s) {', '.join(unknown)}; the shard settings are "
            f"{', '.join(ShardSettings.names())}"
        )
    if "shard_time" in overrides:
        raise ValueError("settings: give shard_time as simulate's own argument, not in settings")
    if "equilibration_time" not in overrides:
        from .equilibration import default_equilibration_time

        overrides["equilibration_time"] = default_equilibration_time(restitution)
    try:
        return ShardSettings.from_mapping(
            {**DEFAULT_SETTINGS, **overrides, "shard_time": shard_time}
        )
    except (KeyError, TypeError) as error:
        raise ValueError(f"settings: {error}") from None


def _settings_in_paper_units(shard_time, settings, units):
    """``shard_time`` and the ``settings`` mapping's equilibration_time (in ``units``) in the
    paper's units, which the shards run in; a ``ShardSettings`` (the shards' own settings, in
    the paper's units) is refused in other units."""
    if units.is_paper:
        return shard_time, settings
    if isinstance(settings, ShardSettings):
        raise ValueError(
            "settings: a ShardSettings is in the paper's units (the shards'); with gravity and "
            "noise give settings as a dict (its equilibration_time in those units)"
        )
    shard_time = units.to_paper(real_number(shard_time, "shard_time"), "time")
    if isinstance(settings, dict) and "equilibration_time" in settings:
        given = real_number(settings["equilibration_time"], "settings.equilibration_time")
        settings = {**settings, "equilibration_time": units.to_paper(given, "time")}
    return shard_time, settings


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
    return _whole_number(seed, "seed", 0)


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
    return _whole_number(record, "seed", 0)


def _seed_text(seed) -> str:
    """``seed`` as the repr shows it, on one line."""
    if not isinstance(seed, np.random.SeedSequence):
        return str(seed)
    record = _seed_record(seed)
    pool = "" if record["pool_size"] == 4 else f", pool_size={record['pool_size']}"
    return (
        f"SeedSequence(entropy={record['entropy']}, spawn_key={tuple(record['spawn_key'])}{pool})"
    )


def _whole_number(value, name, least, most=None):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be a whole number, got {value!r}")
    if value < least:
        raise ValueError(f"{name} must be >= {least}, got {value}")
    if most is not None and value > most:
        raise ValueError(f"{name} must be <= {most}, got {value}")
    return int(value)


def _run_shard(restitution, seed, label, settings, shard, stop=None):
    """One shard on its own stream (a module-level function: picklable for spawned workers);
    ``stop``: ``simulation.simulate_shard``'s."""
    from .simulation import shard_seed_sequence, simulate_shard  # numba: only where it runs

    return shard, simulate_shard(
        restitution, shard_seed_sequence(seed, label, shard), settings, stop=stop
    )


#: Seconds between a worker's checks that the process that started it is alive.
PARENT_CHECK_INTERVAL = 0.2


def _exit_with_parent_on_linux():
    """Ask Linux to SIGKILL this process when the thread that started it ends (prctl's
    PR_SET_PDEATHSIG): it reaches a worker busy in compiled code, which holds the GIL and so
    keeps its watch thread from running.  Elsewhere a no-op."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # 1: PR_SET_PDEATHSIG


def _watch_parent(parent):
    """The initializer of a worker of ``simulate``: ignore Ctrl-C, which the parent handles
    (a terminal sends it to every process of the job), and exit as soon as the parent
    ``parent`` (its pid) is gone, whatever killed it: on Linux at once, elsewhere at the
    worker's next check (``PARENT_CHECK_INTERVAL``) outside compiled code."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _exit_with_parent_on_linux()

    def watch():
        while os.getppid() == parent:
            time.sleep(PARENT_CHECK_INTERVAL)
        os._exit(1)

    threading.Thread(target=watch, name="watch-parent", daemon=True).start()
    if os.getppid() != parent:  # died before the watch began
        os._exit(1)


def _stop_workers(pool):
    """Cancel the queued shards of ``pool`` and kill its workers (mid-shard: their work is
    lost, the finished shards are not)."""
    # the executor's own list of its workers (no public way to stop them before Python 3.14's
    # ``kill_workers``); taken before ``shutdown``, which forgets it
    workers = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for worker in workers:
        with contextlib.suppress(OSError, ValueError):
            worker.kill()
    for worker in workers:
        with contextlib.suppress(OSError, ValueError):
            worker.join(timeout=5.0)


def _run_in_workers(arguments, shards, processes, finished, on_finished):
    """Run shards 0 .. ``shards`` - 1 on ``processes`` spawned workers, putting each shard's
    tallies in ``finished`` as it ends; on any exception (a Ctrl-C) the finished ones are
    kept, the rest cancelled and the workers killed before it propagates."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    pool = ProcessPoolExecutor(
        max_workers=processes,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_watch_parent,
        initargs=(os.getpid(),),
    )
    futures = []
    try:
        futures.extend(pool.submit(_run_shard, *arguments, index) for index in range(shards))
        for future in as_completed(futures):
            index, shard_tallies = future.result()
            finished[index] = shard_tallies
            on_finished()
    except BaseException:
        for future in futures:  # done while the exception was raised
            if future.done() and not future.cancelled() and future.exception() is None:
                index, shard_tallies = future.result()
                finished[index] = shard_tallies
        _stop_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


#: Seconds between the waiting thread's wake-ups while a shard runs in its own thread: where
#: a wait cannot be interrupted by a signal, the longest a Ctrl-C waits to be seen.
WAIT_INTERVAL = 0.1


def _shard_in_thread(arguments, index, outcome, stop):
    """The body of a shard's thread: ``outcome["tallies"]``, or ``outcome["error"]`` (not when
    ``stop`` stopped it: it has nothing to give)."""
    from .simulation import ShardStopped

    try:
        outcome["tallies"] = _run_shard(*arguments, index, stop=stop)[1]
    except ShardStopped:
        pass
    except BaseException as error:  # raised again by the waiting thread
        outcome["error"] = error


def _run_here(arguments, shards, finished, on_finished):
    """Run the shards one after the other in this process, each in a thread of its own (the
    compiled loop releases the GIL) while this thread waits for it in short waits, where a
    Ctrl-C (Python raises KeyboardInterrupt in the main thread, in a terminal and in a
    notebook) lands at once.  On it, or any exception, the shard under way is stopped
    (``simulation.ShardStop``) and waited for, its part of a shard discarded, and the
    finished shards are kept, before it propagates."""
    from .simulation import ShardStop

    for index in range(shards):
        outcome, stop = {}, ShardStop()
        runner = threading.Thread(
            target=_shard_in_thread,
            args=(arguments, index, outcome, stop),
            name=f"simulate shard {index}",
            daemon=True,
        )
        try:
            runner.start()
            while runner.is_alive():
                runner.join(WAIT_INTERVAL)
        finally:
            stop.set()  # changes nothing if it finished
            if runner.ident is not None:  # started
                runner.join()
            if "tallies" in outcome:  # finished, if just before an interrupt: a whole shard
                finished[index] = outcome["tallies"]
        if "error" in outcome:
            raise outcome["error"]
        on_finished()


def _check_recorded(tallies, settings):
    """Refuse shards (``{index: ShardTallies}``) that recorded no time (the step budget ran
    out in equilibration) or no flight: every estimate needs collisions in every shard (the
    jackknife error is the scatter between the shards), and I = 0 +- 0 would be a claim."""
    for index, shard_tallies in sorted(tallies.items()):
        if not shard_tallies.time > 0.0:
            raise RuntimeError(
                f"shard {index} recorded no time: its step budget (max_steps = "
                f"{settings.max_steps}) ran out during equilibration; raise max_steps or "
                "shorten equilibration_time"
            )
    empty = [index for index, shard_tallies in sorted(tallies.items()) if shard_tallies.flights < 1]
    if empty:
        raise ValueError(
            f"shard_time = {settings.shard_time!r} is too short: {len(empty)} of {len(tallies)} "
            f"shards (the first: shard {empty[0]}) recorded no collision ending a flight, and "
            "every estimate needs collisions in every shard (the errors are the scatter "
            "between shards); use a shard_time of many mean flight times <T> = 1/I "
            "(eq. (collrate))"
        )


class SimulationInterrupted(KeyboardInterrupt):
    """``simulate`` stopped by a Ctrl-C: a KeyboardInterrupt (a script stops as it would
    anyway) that holds the shards that finished.

    Attributes
    ----------
    result : SimulationResult or None
        The finished shards' result, marked partial (``result.partial``); None with fewer
        than 2 finished shards (an error needs two) or shards that recorded nothing.
    finished : dict
        {shard index: tallies.ShardTallies} of every shard that finished.
    requested : int
        The shards asked for.
    """

    def __init__(self, message, result, finished, requested):
        super().__init__(message)
        self.result, self.finished, self.requested = result, finished, requested


def _interrupted(exact, seed, settings, finished, requested, units=None):
    """The ``SimulationInterrupted`` of a run stopped with ``finished`` shards done."""
    done = sorted(finished)
    head = f"simulate r={exact} interrupted: {len(done)} of {requested} shards finished"
    result, why = None, None
    if len(done) < 2:
        why = "too few for a result (an error needs 2 shards)"
    else:
        try:
            _check_recorded(finished, settings)
        except (RuntimeError, ValueError) as error:
            why = f"no result: {error}"
        else:
            result = SimulationResult(
                restitution=exact,
                seed=seed,
                settings=settings,
                tallies=tuple(finished[index] for index in done),
                shard_indices=tuple(done),
                requested_shards=requested,
                units=units or PhysicalUnits(),
            )
    if result is not None:
        message = (
            f"{head} ({', '.join(map(str, done))}); their SimulationResult, marked partial, "
            "is this exception's `result` (in IPython or Jupyter: `sys.last_value.result`)"
        )
    else:
        message = f"{head}: {why}; their tallies are this exception's `finished`"
    return SimulationInterrupted(message, result, dict(finished), requested)


def _in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (IPython's kernel app), whose stderr is no
    terminal but shows a progress bar."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    return shell is not None and "IPKernelApp" in getattr(shell, "config", {})


class _Progress:
    """The shards done as a progress bar, ``tqdm.auto``'s: a widget in a notebook (a text bar
    where ipywidgets is not installed), a line rewritten in place on a terminal.  Shown when
    ``enabled`` and stderr is a terminal or this runs in a notebook; silent otherwise (stderr
    a log file or a pipe).  ``show`` and ``close`` are what ``simulate`` calls."""

    def __init__(self, label, total, enabled):
        self.bar = None
        if enabled and (sys.stderr.isatty() or _in_notebook()):
            from tqdm.auto import tqdm  # loaded only for a bar

            self.bar = tqdm(total=total, desc=f"simulate r={label}", unit="shard")

    def show(self, done):
        if self.bar is not None:
            self.bar.update(done - self.bar.n)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def simulate(
    r,
    *,
    shards,
    shard_time,
    seed=None,
    settings=None,
    processes=1,
    progress=True,
    gravity=1.0,
    noise=1.0,
):
    """Simulate the bouncing ball at r (the paper's Sec. IV) in independent shards, and
    estimate the equilibrium observables with their jackknife errors.

    Parameters
    ----------
    r : float or str
        The coefficient of restitution, eq. (restitution): a decimal or a fraction string such
        as ``"1/3"``, 0 < r < 1.  Below r_c (eq. (rc)) the collapse needs
        ``settings={"min_step_floor": ...}``.
    shards : int
        Independent shards, 2 to ``settings.MAX_SHARDS`` (every error bar is the scatter
        between them).
    shard_time : float
        Simulated time each shard records, after its equilibration time, positive and finite
        (a Python or numpy scalar).  When ``settings`` is a ``ShardSettings``, its
        shard_time must equal this one.  Every shard must record collisions: a run whose
        shards are too short for that is refused after it ran (ValueError).
    seed : int or numpy.random.SeedSequence, optional
        Root seed of the random streams, an int >= 0 or a SeedSequence; shard k draws from
        ``simulation.shard_seed_sequence(seed, label of r, k)``, as in the workflow: a
        SeedSequence root's entropy and pool size, with (label of r, k) appended to its spawn
        key, so ``SeedSequence(n)`` gives the same numbers as ``n``.  None draws fresh
        entropy (an int).  The result's ``seed`` is what reproduces the run.
    settings : ShardSettings or dict, optional
        The shard settings (``settings.ShardSettings``), or a dict overriding some of
        ``DEFAULT_SETTINGS`` and ``ShardSettings``' defaults (equilibration_time, criterion_c,
        min_step_divisor, max_steps, speed_bins, position_bins, velocity_bins,
        flight_time_bins, min_step_floor).  equilibration_time defaults to
        ``equilibration.default_equilibration_time(r)``: 20 relaxation times of the process
        at r, at least 1e3.  Their ranges are ``ShardSettings``', the
        workflow's config check's: c of eq. (criterion) at least ``MIN_CRITERION_C``,
        min_step_floor at most ``MAX_MIN_STEP_FLOOR``.
    processes : int, optional
        Worker processes (spawned), >= 1; 1 runs the shards in this process.  The numbers do
        not depend on it.  A script that uses more than one must call ``simulate`` under
        ``if __name__ == "__main__":``.  The workers exit when the process that started them
        dies, however it dies.
    progress : bool, optional
        Show the shards done as a progress bar (``tqdm.auto``): a widget in a notebook, a
        line on stderr in a terminal; nothing where stderr is a file or a pipe, or with
        False.
    gravity, noise : float, optional
        g > 0 and Lambda > 0, finite, of eq. (eqmo) (1: the paper's units), as
        ``Equilibrium``'s.  ``shard_time`` and ``settings``' equilibration_time are times in
        these units, and the result reports its observables and tables in them
        (``SimulationResult.units``).  The shards run in the paper's units on the same random
        streams, so a run's numbers are the paper-unit run's times their units.  The other
        settings (the bins, min_step_floor) are the shards' own, in the paper's units, and
        ``settings`` must then be a dict.

    Returns
    -------
    SimulationResult
        The merged tables and the observables with their errors.

    Warns
    -----
    equilibration.EquilibrationWarning
        Where equilibration_time is shorter than the default at an r above r_c, or
        shard_time is shorter than ``equilibration.SHARD_RELAXATION_TIMES`` relaxation times
        (``equilibration.equilibration_problems``): the estimates may carry the start's
        transient, or errors that cannot be trusted.  The message names r, the relaxation
        time and the setting.

    Raises
    ------
    SimulationInterrupted
        On Ctrl-C (a KeyboardInterrupt, in a terminal or a notebook), holding the shards
        that finished: ``error.result`` is their ``SimulationResult`` marked partial (None
        with fewer than 2), ``error.finished`` their tallies.  The run stops at once,
        whatever ``processes``: the shards under way are stopped and their work discarded
        (a shard's numbers do not depend on an interrupt).  A shard still being compiled
        (the first call in a fresh numba cache) stops when its compile ends.
    ValueError
        Naming the argument out of its range (a ShardSettings whose shard_time is not
        ``shard_time`` included); or, after the run, a shard_time too short for a collision
        in every shard.
    TypeError
        A seed that is not an int, a SeedSequence or None; settings not a ShardSettings or
        a dict.

    Examples
    --------
    >>> from bouncing_ball import simulate
    >>> result = simulate("1/2", shards=4, shard_time=200.0, seed=1, progress=False)
    >>> result.shards, result.total_time, result.partial, result.settings.equilibration_time
    (4, 800.0, False, 1000.0)
    >>> result.observables().columns.tolist()
    ['observable', 'symbol', 'estimator', 'value', 'error', 'shards', 'dof']

    A ``numpy.random.SeedSequence`` is a root seed too; ``SeedSequence(1)`` is the seed 1:

    >>> import numpy as np
    >>> again = simulate("1/2", shards=4, shard_time=200.0, seed=np.random.SeedSequence(1),
    ...                  progress=False)
    >>> again.mean_x == result.mean_x
    True

    A Ctrl-C keeps what finished:

    >>> try:                                                      # doctest: +SKIP
    ...     result = simulate(0.6, shards=64, shard_time=1e7)
    ... except KeyboardInterrupt as error:
    ...     result = error.result  # the finished shards, result.partial is True
    """
    from .asymptotics import CRITICAL_RESTITUTION

    exact = parse_restitution(r, "r")
    label = restitution_label(exact)
    units = PhysicalUnits(gravity, noise)
    shards = _whole_number(shards, "shards", 2, MAX_SHARDS)
    processes = _whole_number(processes, "processes", 1)
    shard_time, settings = _settings_in_paper_units(shard_time, settings, units)
    run_settings = _shard_settings(shard_time, settings, exact)
    if exact < CRITICAL_RESTITUTION and not run_settings.min_step_floor > 0.0:
        raise ValueError(
            f"r = {r!r} is below r_c = {CRITICAL_RESTITUTION:.4f}: the ball collapses onto the "
            "floor (infinitely many collisions in a finite time); give settings="
            '{"min_step_floor": 1e-10} (or another positive floor) to regularise it'
        )
    seed = _root_seed(seed)
    from .equilibration import warn_equilibration_problems

    warn_equilibration_problems(r, run_settings.shard_time, run_settings.equilibration_time)
    progress_line = _Progress(label, shards, progress)
    finished = {}
    arguments = (float(exact), seed, label, run_settings)
    progress_line.show(0)
    try:
        if processes == 1:
            _run_here(arguments, shards, finished, lambda: progress_line.show(len(finished)))
        else:
            _run_in_workers(
                arguments, shards, processes, finished, lambda: progress_line.show(len(finished))
            )
    except KeyboardInterrupt:
        raise _interrupted(exact, seed, run_settings, finished, shards, units) from None
    finally:
        progress_line.close()
    _check_recorded(finished, run_settings)
    return SimulationResult(
        restitution=exact,
        seed=seed,
        settings=run_settings,
        tallies=tuple(finished[index] for index in range(shards)),
        units=units,
    )


#: The scalars of a result, name: (symbol, what it is): the plain estimate, its
#: ``_controlled`` twin and each one's ``_err`` are columns of ``summary_table``.
SCALARS = {
    "collision_rate": ("I", "collisions per unit time, eq. (collrate)"),
    "mean_x": ("<x>", "the mean height, eq. (xandDeltax)"),
    "delta_x": ("Delta x", "the height's standard deviation, eq. (xandDeltax)"),
    "mean_flight_time": ("<T>", "the mean time of flight between collisions"),
    "flight_time_second_moment": ("<T^2>", "the mean squared time of flight"),
}

#: The dimension (a key of ``units.DIMENSIONS``) of each column of the result's tables that has
#: one, by its name without ``_err``, ``_controlled``: the scalars of ``SCALARS``, the bins'
#: edges and centres, and the tables' values.  The other columns (counts, probabilities,
#: correlations, r) have none.
COLUMN_DIMENSIONS = {
    "collision_rate": "rate",
    "mean_x": "length",
    "delta_x": "length",
    "mean_flight_time": "time",
    "flight_time_second_moment": "time_squared",
    "total_time": "time",
    **dict.fromkeys(("x_lo", "x_hi", "x"), "length"),
    **dict.fromkeys(("v_lo", "v_hi", "v", "u_lo", "u_hi"), "speed"),
    **dict.fromkeys(("t_lo", "t_hi", "t"), "time"),
    "p0v": "phase_space_density",
    "pxv": "phase_space_density",
    "px": "per_length",
    "v2_given_x": "speed_squared",
    "density": "rate",  # rho(T) per flight
}


def _estimated_quantity(column: str) -> str:
    """The quantity a table's ``column`` estimates: the column without its estimator's suffix
    (``_martingale``, ``_controlled``) and its error's (``_err``)."""
    return column.removesuffix("_err").removesuffix("_controlled").removesuffix("_martingale")


def _column_dimension(column: str):
    """The dimension of a table's ``column`` (``COLUMN_DIMENSIONS``), None if it has none."""
    return COLUMN_DIMENSIONS.get(_estimated_quantity(column))


def _in_units(table, units):
    """A table of the paper's units in ``units``: each column with a dimension times its
    unit (``table`` itself in the paper's units)."""
    if units.is_paper:
        return table
    converted = table.copy()
    for column in converted.columns:
        dimension = _column_dimension(column)
        if dimension is not None:
            converted[column] = units.to_physical(converted[column].to_numpy(float), dimension)
    return converted


#: The names of the tables in other releases' spelling, and the table each is.
_TABLE_NAMES = {
    "p0v": "p0v_histogram",
    "px": "px_histogram",
    "v2_given_x": "v2_given_x_histogram",
    "pxv": "pxv_histogram",
    "position": "position_histogram",
    "flight_time_density": "flight_time_histogram",
    "return_speed": "return_speed_histogram",
    "summary": "summary_table",
}

#: What ``SimulationResult.save`` writes in its file's provenance under ``kind``.
RESULT_KIND = "SimulationResult"


def _summary_scalar(column):
    """A read-only attribute: ``column`` of ``summary_table``'s one row, as a float; its
    docstring says which scalar of ``SCALARS`` it is and which estimate."""
    name = _estimated_quantity(column)
    symbol, what = SCALARS[name]
    if column == name:
        doc = f"{symbol}, {what}: the shards' estimate."
    elif column == f"{name}_err":
        doc = f"The delete-one jackknife error of ``{name}`` over the shards."
    elif column == f"{name}_martingale":
        doc = (
            f"{symbol} corrected by the martingale (noise-sum) control variates: the same "
            "expectation for the simulated process, less variance, independent of the theory "
            "(the estimate that judges agreement); NaN with too few shards to fit them "
            "(``tallies.SHARDS_PER_CONTROL`` per control)."
        )
    elif column == f"{name}_controlled":
        doc = (
            f"{symbol} corrected by every control variate, the flight-law controls of "
            "eq. (kernel3) included where r is in the solver's range (the summary's "
            "``kernel3_controls``): built from the theory under test; NaN with too few shards."
        )
    else:
        doc = (
            f"The delete-one jackknife error of ``{column.removesuffix('_err')}``; NaN where it is."
        )

    def value(self) -> float:
        return float(self.summary_table[column].iloc[0])

    value.__doc__ = doc
    return property(value)


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """What ``simulate`` returns: the shards' tallies, their merged tables and the observables
    with their delete-one jackknife errors over the shards (``histograms``).

    The raw data are the shards' tallies with the settings, the seed and r: ``save`` writes
    them to a Parquet file and ``bouncing_ball.load`` reads them back to an equal result.
    Every table is a ``pandas.DataFrame`` over bins or lags, named ``*_histogram`` or
    ``*_table`` (``Equilibrium``'s ``p0v``, ``px``, ... are functions; these are the
    simulation's bin averages of them).

    Attributes
    ----------
    restitution : fractions.Fraction
        r exactly.
    r : float
        r as a float.
    label : str
        The workflow's label of r (``restitution.restitution_label``).
    seed : int or numpy.random.SeedSequence
        The root seed: pass it to ``simulate`` again, with the same r, shard_time and
        settings, for the same numbers.
    settings : settings.ShardSettings
        The shard settings of the run.
    tallies : tuple of tallies.ShardTallies
        Each shard's tallies, in the order of the shards (the raw data).
    shard_indices : tuple of int
        The index of each shard of ``tallies`` (its random stream); 0 .. shards - 1 unless
        the run was interrupted.
    requested_shards : int
        The shards asked for; ``partial`` (shown in the repr and the summary) when fewer
        finished: a run stopped by Ctrl-C (``SimulationInterrupted``).
    units : units.PhysicalUnits
        The gravity and noise of ``simulate`` (the paper's g = Lambda = 1 by default): the
        scalars, ``total_time``, ``observables()`` and every table are in these units, each
        column times its unit (``COLUMN_DIMENSIONS``).  ``settings`` and ``tallies`` are
        the shards' own, in the paper's units.
    shards : int
        The shards of ``tallies``.
    partial : bool
        True when fewer shards finished than were asked for.
    merged : tallies.ShardTallies
        The shards' tallies summed.
    total_time : float
        The simulated time recorded, summed over the shards.
    collision_rate, mean_x, delta_x, mean_flight_time, flight_time_second_moment : float
        I (eq. (collrate)), <x>, Delta x (eq. (xandDeltax)), and <T>, <T^2> per flight.
    collision_rate_err, mean_x_err, delta_x_err, mean_flight_time_err, flight_time_second_moment_err : float
        Their delete-one jackknife errors over the shards.
    collision_rate_martingale, mean_x_martingale, delta_x_martingale, mean_flight_time_martingale, flight_time_second_moment_martingale : float
        The same corrected by the martingale (noise-sum) control variates: the same
        expectation for the simulated process, less variance, independent of the theory (the
        estimates that judge agreement); NaN with too few shards to fit the controls
        (``tallies.SHARDS_PER_CONTROL`` per control); each with ``*_err``.
    collision_rate_controlled, mean_x_controlled, delta_x_controlled, mean_flight_time_controlled, flight_time_second_moment_controlled : float
        The same corrected by every control, the flight-law controls of eq. (kernel3)
        included where r is in the solver's range: built from the theory under test, shown
        beside the independent estimates, never instead of them.
    collision_rate_controlled_err, mean_x_controlled_err, delta_x_controlled_err, mean_flight_time_controlled_err, flight_time_second_moment_controlled_err : float
        Their jackknife errors; NaN as they are.
    relaxation_eigenvalue, relaxation_eigenvalue_err : float
        lambda of ``bounce_chain_decay`` and its jackknife error (NaN where fewer than 2
        lags are resolved); against ``Equilibrium.relaxation_eigenvalue``.
    p0v_histogram : pandas.DataFrame
        P(0, v) on the speed bins (v_lo, v_hi, v, p0v, p0v_err, count).
    px_histogram, v2_given_x_histogram : pandas.DataFrame
        P(x) and <v^2>_x (eq. (moment2)) on the position bins (x_lo, x_hi, x, and the value
        with its ``_err``); ``position_histogram`` has both.
    pxv_histogram : pandas.DataFrame
        P(x, v) cell averages (x_lo, x_hi, v_lo, v_hi, pxv, pxv_err).
    flight_time_histogram : pandas.DataFrame
        rho(T) per flight on the flight-time bins (t_lo, t_hi, t, density, density_err).
    return_speed_histogram : pandas.DataFrame
        The return speed's bin probabilities given the outgoing speed's bin.
    bounce_autocorrelation : pandas.DataFrame
        The bounce chain's autocorrelation over lags 1 .. ``tallies.BOUNCE_LAGS`` (lag,
        autocorrelation of ln u_n, principal_correlation of (ln u_n, u_n), each with its
        ``_err``; ``histograms.bounce_autocorrelation``).
    bounce_chain_decay : dict
        The fitted decay rate -ln lambda of the bounce chain's correlations, lambda
        (``relaxation_eigenvalue``), n_c = 1 / rate (``correlation_bounces``), each with its
        ``_err``, and the lags of the fit (``histograms.bounce_chain_decay``).
    summary_table : pandas.DataFrame
        One row: the scalars, their errors, the counts (as the workflow's summary table);
        ``observables()`` is the same scalars as a tidy table.

    Examples
    --------
    >>> from bouncing_ball import simulate
    >>> result = simulate(0.6, shards=2, shard_time=200.0, seed=3, progress=False)
    >>> list(result.px_histogram.columns)
    ['x_lo', 'x_hi', 'x', 'px', 'px_err']
    """

    restitution: Fraction
    seed: object
    settings: object
    tallies: tuple = field(repr=False)
    shard_indices: tuple = field(default=None, repr=False)
    requested_shards: int = None
    units: PhysicalUnits = field(default_factory=PhysicalUnits)

    def __post_init__(self):
        if not isinstance(self.units, PhysicalUnits):
            raise TypeError(f"units must be a units.PhysicalUnits, got {self.units!r}")
        if self.shard_indices is None:
            object.__setattr__(self, "shard_indices", tuple(range(len(self.tallies))))
        if self.requested_shards is None:
            object.__setattr__(self, "requested_shards", len(self.tallies))
        if len(self.shard_indices) != len(self.tallies):
            raise ValueError(
                f"shard_indices: {len(self.shard_indices)} indices for {len(self.tallies)} shards"
            )

    def __getattr__(self, name):
        # only for names not found otherwise: a table under another spelling
        if name in _TABLE_NAMES:
            raise AttributeError(
                f"'SimulationResult' object has no attribute {name!r}: the table is "
                f"{_TABLE_NAMES[name]!r} (Equilibrium.{name} is the function)"
            )
        raise AttributeError(f"'SimulationResult' object has no attribute {name!r}")

    collision_rate = _summary_scalar("collision_rate")
    collision_rate_err = _summary_scalar("collision_rate_err")
    collision_rate_martingale = _summary_scalar("collision_rate_martingale")
    collision_rate_martingale_err = _summary_scalar("collision_rate_martingale_err")
    collision_rate_controlled = _summary_scalar("collision_rate_controlled")
    collision_rate_controlled_err = _summary_scalar("collision_rate_controlled_err")
    mean_x = _summary_scalar("mean_x")
    mean_x_err = _summary_scalar("mean_x_err")
    mean_x_martingale = _summary_scalar("mean_x_martingale")
    mean_x_martingale_err = _summary_scalar("mean_x_martingale_err")
    mean_x_controlled = _summary_scalar("mean_x_controlled")
    mean_x_controlled_err = _summary_scalar("mean_x_controlled_err")
    delta_x = _summary_scalar("delta_x")
    delta_x_err = _summary_scalar("delta_x_err")
    delta_x_martingale = _summary_scalar("delta_x_martingale")
    delta_x_martingale_err = _summary_scalar("delta_x_martingale_err")
    delta_x_controlled = _summary_scalar("delta_x_controlled")
    delta_x_controlled_err = _summary_scalar("delta_x_controlled_err")
    mean_flight_time = _summary_scalar("mean_flight_time")
    mean_flight_time_err = _summary_scalar("mean_flight_time_err")
    mean_flight_time_martingale = _summary_scalar("mean_flight_time_martingale")
    mean_flight_time_martingale_err = _summary_scalar("mean_flight_time_martingale_err")
    mean_flight_time_controlled = _summary_scalar("mean_flight_time_controlled")
    mean_flight_time_controlled_err = _summary_scalar("mean_flight_time_controlled_err")
    flight_time_second_moment = _summary_scalar("flight_time_second_moment")
    flight_time_second_moment_err = _summary_scalar("flight_time_second_moment_err")
    flight_time_second_moment_martingale = _summary_scalar("flight_time_second_moment_martingale")
    flight_time_second_moment_martingale_err = _summary_scalar(
        "flight_time_second_moment_martingale_err"
    )
    flight_time_second_moment_controlled = _summary_scalar("flight_time_second_moment_controlled")
    flight_time_second_moment_controlled_err = _summary_scalar(
        "flight_time_second_moment_controlled_err"
    )

    @property
    def partial(self) -> bool:
        """True when fewer shards finished than were asked for (an interrupted run)."""
        return self.shards < self.requested_shards

    @property
    def r(self) -> float:
        """r as a float."""
        return float(self.restitution)

    @property
    def label(self) -> str:
        """The workflow's label of r (``restitution.restitution_label``)."""
        return restitution_label(self.restitution)

    @property
    def shards(self) -> int:
        """The shards of ``tallies``."""
        return len(self.tallies)

    @cached_property
    def merged(self):
        """The shards' tallies summed (``tallies.merge_shards``)."""
        from .tallies import merge_shards

        return merge_shards(self.tallies)

    @property
    def total_time(self) -> float:
        """The simulated time recorded, summed over the shards, in ``units``."""
        return float(self.units.to_physical(float(self.merged.time), "time"))

    @cached_property
    def _summary_paper(self):
        """``summary_table`` in the paper's units."""
        from .histograms import position_moments_summary

        summary = position_moments_summary(list(self.tallies), self.r)
        return summary.assign(requested_shards=self.requested_shards, partial=self.partial)

    @cached_property
    def summary_table(self):
        """One row: the scalars, their errors and the counts
        (``histograms.position_moments_summary``), with ``requested_shards`` and
        ``partial``; in ``units``."""
        return _in_units(self._summary_paper, self.units)

    def observables(self):
        """Every scalar with its error, as a tidy table: a row per (observable, estimator).

        The plain estimates and their delete-one jackknife errors over the shards, with
        ``dof`` = shards - 1; the estimates corrected by the martingale (noise-sum) controls
        (``*_martingale``, independent of the theory: the ones that judge agreement,
        ``comparison.independent_estimate``) and by every control, those of eq. (kernel3)
        included where r is in the solver's range (``*_controlled``), each with ``dof`` =
        shards - 1 - the controls fitted (``histograms.moment_controls``, at most); and the
        bounce chain's relaxation eigenvalue lambda (``bounce_chain_decay``), dof =
        shards - 1.  Only the estimates that exist are rows: a controlled one needs
        ``tallies.SHARDS_PER_CONTROL`` shards per control and a finite error, lambda two
        resolved lags.  A z-score against a prediction is (value - prediction) / error,
        Student-t with ``dof`` degrees of freedom.

        Returns
        -------
        pandas.DataFrame
            Columns ``observable`` (the attribute's name: ``collision_rate``, ``mean_x``,
            ``delta_x``, ``mean_flight_time``, ``flight_time_second_moment``,
            ``relaxation_eigenvalue``), ``symbol``, ``estimator`` (``"plain"``,
            ``"martingale"``, ``"controlled"``, or ``"bounce-chain fit"`` for lambda),
            ``value``, ``error``
            (finite and positive), ``shards`` and ``dof``.

        Examples
        --------
        >>> from bouncing_ball import simulate
        >>> result = simulate("1/2", shards=4, shard_time=200.0, seed=1, progress=False)
        >>> table = result.observables()
        >>> int(table.set_index(["observable", "estimator"]).loc["mean_x", "plain"].dof)
        3
        """
        import pandas as pd

        row = self.summary_table.iloc[0]
        shards = self.shards
        rows = []
        for name, (symbol, _) in SCALARS.items():
            rows.append((name, symbol, "plain", row[name], row[f"{name}_err"], shards - 1))
            for estimator in ("martingale", "controlled"):
                column = f"{name}_{estimator}"
                dof = shards - 1 - int(row["control_variates"])
                rows.append((name, symbol, estimator, row[column], row[f"{column}_err"], dof))
        decay = self.bounce_chain_decay
        rows.append(
            (
                "relaxation_eigenvalue",
                "lambda",
                "bounce-chain fit",
                decay["relaxation_eigenvalue"],
                decay["relaxation_eigenvalue_err"],
                shards - 1,
            )
        )
        table = pd.DataFrame(
            rows, columns=["observable", "symbol", "estimator", "value", "error", "dof"]
        )
        table.insert(5, "shards", shards)
        value, error = table["value"].to_numpy(float), table["error"].to_numpy(float)
        present = np.isfinite(value) & np.isfinite(error) & (error > 0.0)
        return table[present].reset_index(drop=True)

    @cached_property
    def _p0v_paper(self):
        """``p0v_histogram`` in the paper's units."""
        from .histograms import outgoing_speed_histogram

        return outgoing_speed_histogram(list(self.tallies), self.restitution)

    @cached_property
    def p0v_histogram(self):
        """P(0, v) averaged over the speed bins (``histograms.outgoing_speed_histogram``):
        v_lo, v_hi, v, p0v, p0v_err, count; in ``units``."""
        return _in_units(self._p0v_paper, self.units)

    @cached_property
    def _position_paper(self):
        """``position_histogram`` in the paper's units."""
        from .histograms import position_histogram

        return position_histogram(list(self.tallies))

    @cached_property
    def position_histogram(self):
        """P(x) and <v^2>_x averaged over the position bins (``histograms.position_histogram``),
        in ``units``."""
        return _in_units(self._position_paper, self.units)

    @property
    def px_histogram(self):
        """P(x) averaged over the position bins: x_lo, x_hi, x, px, px_err."""
        return self.position_histogram[["x_lo", "x_hi", "x", "px", "px_err"]]

    @property
    def v2_given_x_histogram(self):
        """<v^2>_x (eq. (moment2)) over the position bins: x_lo, x_hi, x, v2_given_x,
        v2_given_x_err."""
        return self.position_histogram[["x_lo", "x_hi", "x", "v2_given_x", "v2_given_x_err"]]

    @cached_property
    def pxv_histogram(self):
        """P(x, v) averaged over the cells (``histograms.distribution_histogram``): x_lo, x_hi,
        v_lo, v_hi, pxv, pxv_err; in ``units``."""
        from .histograms import distribution_histogram

        return _in_units(distribution_histogram(list(self.tallies)), self.units)

    @cached_property
    def flight_time_histogram(self):
        """rho(T) per flight averaged over the flight-time bins
        (``histograms.flight_time_histogram``): t_lo, t_hi, t, density, density_err; in
        ``units``."""
        from .histograms import flight_time_histogram

        return _in_units(flight_time_histogram(list(self.tallies)), self.units)

    @cached_property
    def return_speed_histogram(self):
        """The return speed's bin probabilities given the outgoing speed's bin
        (``histograms.return_speed_table``), the bins' edges in ``units``."""
        from .histograms import return_speed_table

        return _in_units(return_speed_table(list(self.tallies)), self.units)

    @cached_property
    def bounce_autocorrelation(self):
        """The bounce chain's autocorrelations by lag (``histograms.bounce_autocorrelation``)."""
        from .histograms import bounce_autocorrelation

        return bounce_autocorrelation(list(self.tallies))

    @cached_property
    def bounce_chain_decay(self):
        """The fitted decay of the bounce chain's correlations
        (``histograms.bounce_chain_decay``)."""
        from .histograms import bounce_chain_decay

        return bounce_chain_decay(list(self.tallies))

    @property
    def relaxation_eigenvalue(self) -> float:
        """lambda, the bounce chain's relaxation eigenvalue fitted to its correlations
        (``bounce_chain_decay``); NaN where fewer than 2 lags are resolved."""
        return float(self.bounce_chain_decay["relaxation_eigenvalue"])

    @property
    def relaxation_eigenvalue_err(self) -> float:
        """The jackknife error of ``relaxation_eigenvalue``."""
        return float(self.bounce_chain_decay["relaxation_eigenvalue_err"])

    def batch_frame(self):
        """The shards as one table in the workflow's batch format (``tallies.batch_to_frame``;
        ``results/simulation/r{r}/shards{first}-{last}.parquet``)."""
        from .tallies import batch_to_frame

        return batch_to_frame(dict(zip(self.shard_indices, self.tallies)))

    def provenance(self) -> dict:
        """What ``save`` records with the shards: the kind, r, the seed (an int, or a
        SeedSequence's entropy, spawn key and pool size), the settings, the shard indices,
        the shards asked for and the units (gravity and noise) (JSON-ready)."""
        from .restitution import exact_string

        return {
            "kind": RESULT_KIND,
            "r": exact_string(self.restitution),
            "r_label": self.label,
            "seed": _seed_record(self.seed),
            "settings": self.settings.as_mapping(),
            "shard_indices": [int(index) for index in self.shard_indices],
            "requested_shards": int(self.requested_shards),
            "units": {"gravity": self.units.gravity, "noise": self.units.noise},
        }

    def save(self, path):
        """Write the result to a Parquet file: its shards' tallies in the workflow's batch
        table (``tallies.batch_to_table``), with ``provenance()`` and the package version in
        the file's metadata (``parquet.write_table``: atomic, a reader never sees half a
        file).  ``bouncing_ball.load(path)`` gives it back, every observable bit-identical.

        Parameters
        ----------
        path : str or os.PathLike
            The file to write (conventionally ``*.parquet``); its folder is made if missing,
            an existing file replaced.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from bouncing_ball import load, simulate
        >>> result = simulate("1/2", shards=2, shard_time=200.0, seed=1, progress=False)
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "half.parquet"
        >>> result.save(path)
        >>> load(path).mean_x == result.mean_x
        True
        """
        from .parquet import write_table
        from .tallies import batch_to_table

        write_table(
            batch_to_table(dict(zip(self.shard_indices, self.tallies))),
            path,
            self.provenance(),
        )

    def __repr__(self):
        row = self.summary_table.iloc[0]

        def shown(name, symbol):
            return f"{symbol} = {row[name]:.6g} +- {row[name + '_err']:.2g}"

        units = self.units
        given = "" if units.is_paper else f"gravity={units.gravity!r}, noise={units.noise!r}, "
        return (
            f"SimulationResult(r={self.restitution}, {given}"
            + (
                f"PARTIAL: shards={self.shards} of {self.requested_shards} (interrupted), "
                if self.partial
                else f"shards={self.shards}, "
            )
            + f"seed={_seed_text(self.seed)}, "
            f"total time {row.total_time:.6g}, {int(row.collisions)} collisions, "
            f"{int(row.steps)} steps): "
            + ", ".join(shown(name, symbol) for name, (symbol, _) in SCALARS.items())
            + (
                f"; {int(row.shards_out_of_budget)} shards stopped early (max_steps)"
                if row.shards_out_of_budget
                else ""
            )
        )


def load(path) -> SimulationResult:
    """The ``SimulationResult`` a file of ``SimulationResult.save`` holds: its shards'
    tallies, settings, seed, r and units, so every table and observable is bit-identical to
    the saved result's.

    Parameters
    ----------
    path : str or os.PathLike
        A Parquet file written by ``SimulationResult.save``.

    Returns
    -------
    SimulationResult

    Raises
    ------
    parquet.UnreadableFileError
        Naming the file: missing, not a readable Parquet file (truncated, corrupt), without
        bouncing_ball's provenance, of another kind (e.g. a table of the workflow), or whose
        shards are not on its settings' bins.

    Examples
    --------
    See ``SimulationResult.save``.
    """
    from pathlib import Path

    import pyarrow.parquet as pq

    from .parquet import UnreadableFileError, provenance_of, read_parquet
    from .tallies import batch_from_table

    path = Path(path)
    table = read_parquet(pq.read_table, path)
    provenance = provenance_of(path, table.schema)
    if provenance.get("kind") != RESULT_KIND:
        written_by = provenance.get("rule") or provenance.get("kind") or "unknown"
        raise UnreadableFileError(
            f"{path}: not a saved SimulationResult (written by {written_by}); "
            "bouncing_ball.load reads the files of SimulationResult.save"
        )
    try:
        settings = ShardSettings.from_mapping(provenance["settings"])
        restitution = parse_restitution(provenance["r"], "r")
        seed = _seed_from_record(provenance["seed"])
        shards = batch_from_table(table, settings, source=str(path))
        indices = tuple(int(index) for index in provenance["shard_indices"])
        if sorted(shards) != sorted(indices):
            raise ValueError(
                f"its shards {sorted(shards)} are not its provenance's {sorted(indices)}"
            )
        return SimulationResult(
            restitution=restitution,
            seed=seed,
            settings=settings,
            tallies=tuple(shards[index] for index in indices),
            shard_indices=indices,
            requested_shards=int(provenance["requested_shards"]),
            units=PhysicalUnits(**provenance.get("units", {})),
        )
    except (KeyError, TypeError, ValueError) as error:
        raise UnreadableFileError(f"{path}: not a readable SimulationResult ({error})") from None
