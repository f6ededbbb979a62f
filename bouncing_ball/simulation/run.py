"""``simulate``: shards run in this process or on several, stopped by a Ctrl-C, returned as a
``SimulationResult``."""

import contextlib
import math
import os
import signal
import sys
import threading
import time

from ..restitution import parse_restitution, restitution_label
from ..scales import resolve_bins
from ..settings import MAX_SHARDS, ShardSettings, real_number, whole_number
from ..units import PhysicalUnits
from .result import SimulationResult
from .seeds import _root_seed

__all__ = [
    "simulate",
    "SimulationInterrupted",
    "DEFAULT_SETTINGS",
    "PARENT_CHECK_INTERVAL",
    "WAIT_INTERVAL",
]

# the shard settings ``simulate`` uses where it is not told otherwise (the default config's
# ``simulation`` section holds the workflow's); every bin set not given, or given as "auto",
# takes its range from r's scales (``scales.resolve_bins``), and equilibration_time follows
# from the relaxation time at r
# (``simulation.equilibration.default_equilibration_time``)
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
            resolve_bins({**DEFAULT_SETTINGS, **overrides, "shard_time": shard_time}, restitution)
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


def _run_shard(restitution, seed, label, settings, shard, stop=None):
    """One shard on its own stream (a module-level function: picklable for spawned workers);
    ``stop``: ``simulation.simulate_shard``'s."""
    from ..simulation import shard_seed_sequence, simulate_shard  # numba: only where it runs

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


def _main_unimportable_by_workers():
    """The path of the main module where spawned workers cannot import it again (a script
    read from standard input: ``python - < run.py`` gives ``'<stdin>'``), else None."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if getattr(main, "__spec__", None) is not None or path is None or os.path.isfile(path):
        return None
    return path


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
    from ..simulation import ShardStopped

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
    from ..simulation import ShardStop

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


def _check_recorded(tallies, settings, units=None):
    """Refuse shards (``{index: ShardTallies}``) that recorded no time (the step budget ran
    out in equilibration) or no flight: every estimate needs collisions in every shard (the
    jackknife error is the scatter between the shards), and I = 0 +- 0 would be a claim.  The
    messages quote shard_time in ``units`` (the paper's where None)."""
    for index, shard_tallies in sorted(tallies.items()):
        if not shard_tallies.time > 0.0:
            raise RuntimeError(
                f"shard {index} recorded no time: its step budget (max_steps = "
                f"{settings.max_steps}) ran out during equilibration; raise max_steps or "
                "shorten equilibration_time"
            )
    empty = [index for index, shard_tallies in sorted(tallies.items()) if shard_tallies.flights < 1]
    if empty:
        shard_time = settings.shard_time
        if units is not None:
            shard_time = float(units.to_physical(shard_time, "time"))
        raise ValueError(
            f"shard_time = {shard_time!r} is too short: {len(empty)} of {len(tallies)} "
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
            _check_recorded(finished, settings, units)
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
        flight_time_bins, min_step_floor).  A bin set not given, or ``"auto"`` (or a dict
        with some of its lo, hi, per_decade or width ``"auto"``), takes its range from r's
        scales (``scales.resolve_bins``): every shard of r shares it, and it leaves about
        1e-6 of the collisions, the time and the flights outside at each end (the result's
        ``outside_fractions`` says how much).  equilibration_time defaults to
        ``simulation.equilibration.default_equilibration_time(r)``: 20 relaxation times of the process
        at r, at least 1e3.  Their ranges are ``ShardSettings``', the
        workflow's config check's: c of eq. (criterion) at least ``MIN_CRITERION_C``,
        min_step_floor at most ``MAX_MIN_STEP_FLOOR``.
    processes : int, optional
        Worker processes (spawned), >= 1; 1 runs the shards in this process.  The numbers do
        not depend on it.  A script that uses more than one must call ``simulate`` under
        ``if __name__ == "__main__":``; one read from standard input (``python - < run.py``),
        which workers cannot import, runs its shards in this process, with a RuntimeWarning.
        The workers exit when the process that started them dies, however it dies.
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
    simulation.equilibration.EquilibrationWarning
        Where equilibration_time is shorter than the default at an r above r_c, or
        shard_time is shorter than ``simulation.equilibration.SHARD_RELAXATION_TIMES`` relaxation times
        (``simulation.equilibration.equilibration_problems``): the estimates may carry the start's
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
    from ..asymptotics import CRITICAL_RESTITUTION

    exact = parse_restitution(r, "r")
    label = restitution_label(exact)
    units = PhysicalUnits(gravity, noise)
    shards = whole_number(shards, "shards", 2, MAX_SHARDS)
    processes = whole_number(processes, "processes", 1)
    shard_time = real_number(shard_time, "shard_time")
    if not 0.0 < shard_time < math.inf:  # in the units given, before they are converted
        raise ValueError(f"shard_time must be positive and finite, got {shard_time!r}")
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

    warn_equilibration_problems(r, run_settings.shard_time, run_settings.equilibration_time, units)
    progress_line = _Progress(label, shards, progress)
    finished = {}
    arguments = (float(exact), seed, label, run_settings)
    progress_line.show(0)
    try:
        if processes > 1 and (main := _main_unimportable_by_workers()) is not None:
            import warnings

            warnings.warn(
                f"simulate: processes={processes} runs the shards in this process: spawned "
                f"workers re-run the main module from its file, and {main!r} is none (save the "
                "script to a file and run that for workers); the numbers are the same",
                RuntimeWarning,
                stacklevel=2,
            )
            processes = 1
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
    _check_recorded(finished, run_settings, units)
    return SimulationResult(
        restitution=exact,
        seed=seed,
        settings=run_settings,
        tallies=tuple(finished[index] for index in range(shards)),
        units=units,
    )


#: The scalars of a result, name: (symbol, what it is): the plain estimate, its
#: ``_controlled`` twin and each one's ``_err`` are columns of ``summary_table``.
