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

__all__ = ["simulate", "SimulationResult", "SimulationInterrupted", "DEFAULT_SETTINGS"]

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
    or a mapping of overrides of DEFAULT_SETTINGS and of the default equilibration time) with
    ``shard_time``."""
    if isinstance(settings, ShardSettings):
        if shard_time is None:
            return settings
        if float(settings.shard_time) != float(shard_time):
            raise ValueError(
                f"shard_time = {shard_time!r} and settings.shard_time = {settings.shard_time!r} "
                "differ; give one of them"
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
    if shard_time is None:
        raise TypeError("simulate needs shard_time, the simulated time each shard records")
    shard_time = real_number(shard_time, "shard_time")
    if not 0.0 < shard_time < math.inf:
        raise ValueError(f"shard_time must be positive and finite, got {shard_time!r}")
    if "equilibration_time" not in overrides:
        from .equilibration import default_equilibration_time

        overrides["equilibration_time"] = default_equilibration_time(restitution)
    try:
        return ShardSettings.from_mapping(
            {**DEFAULT_SETTINGS, **overrides, "shard_time": shard_time}
        )
    except (KeyError, TypeError) as error:
        raise ValueError(f"settings: {error}") from None


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


def _interrupted(exact, seed, settings, finished, requested):
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
            )
    if result is not None:
        message = (
            f"{head} ({', '.join(map(str, done))}); their SimulationResult, marked partial, "
            "is this exception's `result` (in IPython or Jupyter: `sys.last_value.result`)"
        )
    else:
        message = f"{head}: {why}; their tallies are this exception's `finished`"
    return SimulationInterrupted(message, result, dict(finished), requested)


class _Progress:
    """'simulate r=0.6: 3/8 shards, 12 s' on stderr, rewritten in place, on a terminal only."""

    def __init__(self, label, total, enabled):
        self.label, self.total = label, total
        self.enabled = bool(enabled) and sys.stderr.isatty()
        self.started = time.perf_counter()

    def show(self, done):
        if self.enabled:
            elapsed = time.perf_counter() - self.started
            sys.stderr.write(
                f"\rsimulate r={self.label}: {done}/{self.total} shards, {elapsed:.0f} s"
            )
            sys.stderr.flush()

    def close(self):
        if self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()


def simulate(r, *, shards, shard_time=None, seed=None, settings=None, processes=1, progress=True):
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
        (a Python or numpy scalar; may be left out when ``settings`` is a ``ShardSettings``,
        which holds one).  Every shard must record collisions: a run whose shards are too
        short for that is refused after it ran (ValueError).
    seed : int, optional
        Root seed of the random streams; shard k draws from
        ``simulation.shard_seed_sequence(seed, label of r, k)``, as in the workflow.  None
        draws fresh entropy (``numpy.random.SeedSequence``), recorded in the result's ``seed``.
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
        Show the shards done on stderr, when stderr is a terminal.

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
        Naming the argument out of its range; or, after the run, a shard_time too short for
        a collision in every shard.

    Examples
    --------
    >>> from bouncing_ball import simulate
    >>> result = simulate("1/2", shards=4, shard_time=200.0, seed=1, progress=False)
    >>> result.shards, result.total_time, result.partial, result.settings.equilibration_time
    (4, 800.0, False, 1000.0)
    >>> sorted(result.summary.columns)[:4]
    ['collision_rate', 'collision_rate_controlled', 'collision_rate_controlled_err', 'collision_rate_err']

    A Ctrl-C keeps what finished:

    >>> try:                                                      # doctest: +SKIP
    ...     result = simulate(0.6, shards=64, shard_time=1e7)
    ... except KeyboardInterrupt as error:
    ...     result = error.result  # the finished shards, result.partial is True
    """
    from .asymptotics import CRITICAL_RESTITUTION

    exact = parse_restitution(r, "r")
    label = restitution_label(exact)
    shards = _whole_number(shards, "shards", 2, MAX_SHARDS)
    processes = _whole_number(processes, "processes", 1)
    run_settings = _shard_settings(shard_time, settings, exact)
    if exact < CRITICAL_RESTITUTION and not run_settings.min_step_floor > 0.0:
        raise ValueError(
            f"r = {r!r} is below r_c = {CRITICAL_RESTITUTION:.4f}: the ball collapses onto the "
            "floor (infinitely many collisions in a finite time); give settings="
            '{"min_step_floor": 1e-10} (or another positive floor) to regularise it'
        )
    if seed is None:
        seed = int(np.random.SeedSequence().entropy)
    seed = _whole_number(seed, "seed", 0)
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
        raise _interrupted(exact, seed, run_settings, finished, shards) from None
    finally:
        progress_line.close()
    _check_recorded(finished, run_settings)
    return SimulationResult(
        restitution=exact,
        seed=seed,
        settings=run_settings,
        tallies=tuple(finished[index] for index in range(shards)),
    )


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """What ``simulate`` returns: the shards' tallies, their merged tables and the observables
    with their delete-one jackknife errors over the shards (``histograms``).

    Attributes
    ----------
    restitution : fractions.Fraction
        r exactly; ``r`` is it as a float, ``label`` the workflow's label of it.
    seed : int
        The root seed (pass it again for the same numbers).
    settings : settings.ShardSettings
    tallies : tuple of tallies.ShardTallies
        Each shard's tallies, in the order of the shards (the raw data).
    shard_indices : tuple of int
        The index of each shard of ``tallies`` (its random stream); 0 .. shards - 1 unless
        the run was interrupted.
    requested_shards : int
        The shards asked for; ``partial`` (shown in the repr and the summary) when fewer
        finished: a run stopped by Ctrl-C (``SimulationInterrupted``).
    merged : tallies.ShardTallies
        Their sum.
    collision_rate, mean_x, delta_x, mean_flight_time, flight_time_second_moment : float
        I (eq. (collrate)), <x>, Delta x (eq. (xandDeltax)), and <T>, <T^2> per flight; each
        with its jackknife error ``*_err``.
    collision_rate_controlled, mean_x_controlled, delta_x_controlled : float
        I, <x>, Delta x corrected by the martingale control variates (the same expectation,
        less variance), each with its ``*_err``; and ``mean_flight_time_controlled``,
        ``flight_time_second_moment_controlled``.  NaN with fewer than 15 shards.
    p0v : pandas.DataFrame
        P(0, v) on the speed bins (v_lo, v_hi, v, p0v, p0v_err, count).
    px, v2_given_x : pandas.DataFrame
        P(x) and <v^2>_x (eq. (moment2)) on the position bins (x_lo, x_hi, x, and the value
        with its ``_err``); ``position`` has both.
    pxv : pandas.DataFrame
        P(x, v) cell averages (x_lo, x_hi, v_lo, v_hi, pxv, pxv_err).
    flight_time_density : pandas.DataFrame
        rho(T) per flight on the flight-time bins (t_lo, t_hi, t, density, density_err).
    return_speed : pandas.DataFrame
        The return speed's bin probabilities given the outgoing speed's bin.
    bounce_autocorrelation : pandas.DataFrame
        The bounce chain's autocorrelation over lags 1 .. ``tallies.BOUNCE_LAGS`` (lag,
        autocorrelation of ln u_n, principal_correlation of (ln u_n, u_n), each with its
        ``_err``; ``histograms.bounce_autocorrelation``).
    bounce_chain_decay : dict
        The fitted decay rate -ln lambda of the bounce chain's correlations, lambda
        (``relaxation_eigenvalue``), n_c = 1 / rate (``correlation_bounces``), each with its
        ``_err``, and the lags of the fit (``histograms.bounce_chain_decay``); against
        ``Equilibrium.relaxation_eigenvalue``.
    relaxation_eigenvalue, relaxation_eigenvalue_err : float
        lambda of ``bounce_chain_decay`` and its jackknife error.
    summary : pandas.DataFrame
        One row: the scalars, their errors, the counts (as the workflow's summary table).

    Examples
    --------
    >>> from bouncing_ball import simulate
    >>> result = simulate(0.6, shards=2, shard_time=200.0, seed=3, progress=False)
    >>> list(result.px.columns)
    ['x_lo', 'x_hi', 'x', 'px', 'px_err']
    """

    restitution: Fraction
    seed: int
    settings: object
    tallies: tuple = field(repr=False)
    shard_indices: tuple = field(default=None, repr=False)
    requested_shards: int = None

    def __post_init__(self):
        if self.shard_indices is None:
            object.__setattr__(self, "shard_indices", tuple(range(len(self.tallies))))
        if self.requested_shards is None:
            object.__setattr__(self, "requested_shards", len(self.tallies))
        if len(self.shard_indices) != len(self.tallies):
            raise ValueError(
                f"shard_indices: {len(self.shard_indices)} indices for {len(self.tallies)} shards"
            )

    @property
    def partial(self) -> bool:
        """True when fewer shards finished than were asked for (an interrupted run)."""
        return self.shards < self.requested_shards

    @property
    def r(self) -> float:
        return float(self.restitution)

    @property
    def label(self) -> str:
        return restitution_label(self.restitution)

    @property
    def shards(self) -> int:
        return len(self.tallies)

    @cached_property
    def merged(self):
        from .tallies import merge_shards

        return merge_shards(self.tallies)

    @property
    def total_time(self) -> float:
        return float(self.merged.time)

    @cached_property
    def summary(self):
        from .histograms import position_moments_summary

        summary = position_moments_summary(list(self.tallies), self.r)
        return summary.assign(requested_shards=self.requested_shards, partial=self.partial)

    def _scalar(self, name) -> float:
        return float(self.summary[name].iloc[0])

    collision_rate = property(lambda self: self._scalar("collision_rate"))
    collision_rate_err = property(lambda self: self._scalar("collision_rate_err"))
    collision_rate_controlled = property(lambda self: self._scalar("collision_rate_controlled"))
    collision_rate_controlled_err = property(
        lambda self: self._scalar("collision_rate_controlled_err")
    )
    mean_x_controlled = property(lambda self: self._scalar("mean_x_controlled"))
    mean_x_controlled_err = property(lambda self: self._scalar("mean_x_controlled_err"))
    delta_x_controlled = property(lambda self: self._scalar("delta_x_controlled"))
    delta_x_controlled_err = property(lambda self: self._scalar("delta_x_controlled_err"))
    mean_flight_time_controlled = property(lambda self: self._scalar("mean_flight_time_controlled"))
    mean_flight_time_controlled_err = property(
        lambda self: self._scalar("mean_flight_time_controlled_err")
    )
    flight_time_second_moment_controlled = property(
        lambda self: self._scalar("flight_time_second_moment_controlled")
    )
    flight_time_second_moment_controlled_err = property(
        lambda self: self._scalar("flight_time_second_moment_controlled_err")
    )
    mean_x = property(lambda self: self._scalar("mean_x"))
    mean_x_err = property(lambda self: self._scalar("mean_x_err"))
    delta_x = property(lambda self: self._scalar("delta_x"))
    delta_x_err = property(lambda self: self._scalar("delta_x_err"))
    mean_flight_time = property(lambda self: self._scalar("mean_flight_time"))
    mean_flight_time_err = property(lambda self: self._scalar("mean_flight_time_err"))
    flight_time_second_moment = property(lambda self: self._scalar("flight_time_second_moment"))
    flight_time_second_moment_err = property(
        lambda self: self._scalar("flight_time_second_moment_err")
    )

    @cached_property
    def p0v(self):
        from .histograms import outgoing_speed_histogram

        return outgoing_speed_histogram(list(self.tallies), self.restitution)

    @cached_property
    def position(self):
        from .histograms import position_histogram

        return position_histogram(list(self.tallies))

    @property
    def px(self):
        return self.position[["x_lo", "x_hi", "x", "px", "px_err"]]

    @property
    def v2_given_x(self):
        return self.position[["x_lo", "x_hi", "x", "v2_given_x", "v2_given_x_err"]]

    @cached_property
    def pxv(self):
        from .histograms import distribution_histogram

        return distribution_histogram(list(self.tallies))

    @cached_property
    def flight_time_density(self):
        from .histograms import flight_time_histogram

        return flight_time_histogram(list(self.tallies))

    @cached_property
    def return_speed(self):
        from .histograms import return_speed_table

        return return_speed_table(list(self.tallies))

    @cached_property
    def bounce_autocorrelation(self):
        from .histograms import bounce_autocorrelation

        return bounce_autocorrelation(list(self.tallies))

    @cached_property
    def bounce_chain_decay(self):
        from .histograms import bounce_chain_decay

        return bounce_chain_decay(list(self.tallies))

    relaxation_eigenvalue = property(lambda self: self.bounce_chain_decay["relaxation_eigenvalue"])
    relaxation_eigenvalue_err = property(
        lambda self: self.bounce_chain_decay["relaxation_eigenvalue_err"]
    )

    def batch_frame(self):
        """The shards as one table in the workflow's batch format (``tallies.batch_to_frame``;
        ``results/simulation/r{r}/shards{first}-{last}.parquet``)."""
        from .tallies import batch_to_frame

        return batch_to_frame(dict(zip(self.shard_indices, self.tallies)))

    def __repr__(self):
        row = self.summary.iloc[0]

        def shown(name, symbol):
            return f"{symbol} = {row[name]:.6g} +- {row[name + '_err']:.2g}"

        return (
            f"SimulationResult(r={self.restitution}, "
            + (
                f"PARTIAL: shards={self.shards} of {self.requested_shards} (interrupted), "
                if self.partial
                else f"shards={self.shards}, "
            )
            + f"seed={self.seed}, "
            f"total time {row.total_time:.6g}, {int(row.collisions)} collisions, "
            f"{int(row.steps)} steps): "
            + ", ".join(
                shown(name, symbol)
                for name, symbol in (
                    ("collision_rate", "I"),
                    ("mean_x", "<x>"),
                    ("delta_x", "Delta x"),
                    ("mean_flight_time", "<T>"),
                    ("flight_time_second_moment", "<T^2>"),
                )
            )
            + (
                f"; {int(row.shards_out_of_budget)} shards stopped early (max_steps)"
                if row.shards_out_of_budget
                else ""
            )
        )
