"""simulate under a Ctrl-C and a killed parent, and the shard times it refuses: an interrupt
keeps the finished shards (a partial SimulationResult) and stops at once, with worker
processes and in this process (the shard under way stopped), the workers die with their
parent, a shard with no collision is refused."""

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import bouncing_ball as bb
from bouncing_ball.simulation import SimulationResult

# shards of a few relaxation times: what is tested is how runs stop, not their errors
pytestmark = pytest.mark.filterwarnings(
    "ignore::bouncing_ball.simulation.equilibration.EquilibrationWarning"
)

# a child that interrupts itself (SIGINT, as a terminal or a notebook kernel gets it) `delay`
# seconds after `after` shards have finished, and reports what simulate raised and how long it
# took to stop
_INTERRUPTED_CHILD = """
import os, signal, sys, threading, time
import bouncing_ball as bb
from bouncing_ball.simulation import run

def interrupt():
    run.sent = time.perf_counter()
    os.killpg(0, signal.SIGINT) if {group} else os.kill(os.getpid(), signal.SIGINT)

def interrupt_after(self, done):
    if done == {after} and not hasattr(run, "scheduled"):
        run.scheduled = True
        threading.Timer({delay}, interrupt).start() if {delay} else interrupt()

run._Progress.show = interrupt_after
if __name__ == "__main__":
    try:
        bb.simulate(0.6, shards={shards}, shard_time={shard_time}, seed=1, processes={processes},
                    settings={{"equilibration_time": 10.0}}, progress=False)
        print("RETURNED")
    except KeyboardInterrupt as error:
        stopped = time.perf_counter() - run.sent
        result = error.result
        if result is None:
            print(type(error).__name__, f"{{stopped:.3f}}", len(error.finished), error)
            sys.exit()
        print(type(error).__name__, f"{{stopped:.3f}}", result.shards, result.requested_shards,
              result.partial, "PARTIAL" in repr(result), bool(result.summary_table.partial.iloc[0]))
"""


def _interrupted_run(processes, group, shards, shard_time, after=2, delay=0.0):
    script = _INTERRUPTED_CHILD.format(
        group=group,
        shards=shards,
        shard_time=shard_time,
        processes=processes,
        after=after,
        delay=delay,
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, for a terminal's Ctrl-C
        # as in a terminal: under a background job of a non-interactive shell (a CI script,
        # nohup ... &) SIGINT arrives ignored, and Python then never raises KeyboardInterrupt
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        stdout, stderr = child.communicate(timeout=120)
    finally:  # whatever happened, nothing of the child's group outlives the test
        with contextlib.suppress(ProcessLookupError):
            os.killpg(child.pid, signal.SIGKILL)
    assert child.returncode == 0, stderr
    return stdout.split()


@pytest.mark.parametrize("group", [False, True], ids=["notebook", "terminal"])
def test_ctrl_c_stops_the_workers_at_once_and_keeps_the_finished_shards(group):
    """With 2 workers, 100 shards would run far longer than the test waits: a Ctrl-C after
    the first two stops the workers at once, with those two (or more that finished meanwhile)
    as a partial result."""
    words = _interrupted_run(processes=2, group=group, shards=100, shard_time=2.0e6)
    name, stopped, finished, requested, partial, shown, in_summary = words
    assert name == "SimulationInterrupted"
    assert float(stopped) < 5.0  # the 98 queued shards need tens of seconds
    assert 2 <= int(finished) < 100 and int(requested) == 100
    assert (partial, shown, in_summary) == ("True", "True", "True")


def test_ctrl_c_in_this_process_between_shards_keeps_the_finished_ones():
    words = _interrupted_run(processes=1, group=False, shards=50, shard_time=1.0e5)
    name, _, finished, requested, partial, shown, in_summary = words
    assert name == "SimulationInterrupted"
    assert (int(finished), int(requested)) == (2, 50)  # the interrupt came with shard 2's end
    assert (partial, shown, in_summary) == ("True", "True", "True")


@pytest.mark.parametrize("group", [False, True], ids=["notebook", "terminal"])
def test_ctrl_c_in_this_process_stops_the_shard_under_way_at_once(group):
    """processes=1: a Ctrl-C a quarter of the way into shard 1 stops it at once, its work
    discarded, and keeps shard 0 (too few for a result); waiting for shard 1 to end would keep
    it too."""
    words = _interrupted_run(
        processes=1, group=group, shards=4, shard_time=1.2e6, after=1, delay=0.25
    )
    name, stopped, finished = words[:3]
    assert name == "SimulationInterrupted"
    assert int(finished) == 1
    assert float(stopped) < 0.5  # the loop looks at its stop flag every STOP_CHECK_STEPS steps
    assert "1 of 4 shards finished: too few for a result" in " ".join(words)


def _children(pid):
    """The pids of the processes whose parent is ``pid`` (from /proc)."""
    children = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as stat:
                    fields = stat.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != "Z":
                children.append(int(entry))
    return children


def _command_line(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as command:
            return command.read()
    except OSError:
        return b""


def _alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_workers_exit_when_their_parent_is_killed():
    """SIGKILL to a process running simulate(processes=2), its workers busy in shards: they
    exit within seconds instead of waiting for work forever."""
    script = textwrap.dedent(
        """
        import bouncing_ball as bb
        if __name__ == "__main__":
            bb.simulate(0.6, shards=8, shard_time=1.0e8, seed=1, processes=2, progress=False)
        """
    )
    parent = subprocess.Popen([sys.executable, "-c", script])
    workers = []
    try:
        deadline = time.monotonic() + 60.0
        while len(workers) < 2 and time.monotonic() < deadline:  # both spawned and busy
            time.sleep(0.2)
            workers = [
                pid
                for pid in _children(parent.pid)
                if b"resource_tracker" not in _command_line(pid)
            ]
        assert len(workers) == 2, "the workers did not start"
        time.sleep(1.0)  # into their shards
        parent.kill()
        parent.wait()
        deadline = time.monotonic() + 5.0
        while any(_alive(pid) for pid in workers) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(_alive(pid) for pid in workers)
    finally:
        parent.kill()
        for pid in workers:
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)


def test_a_shard_time_too_short_for_a_collision_is_refused():
    """shard_time = 1e-6 records no collision: I = 0 +- 0 would claim an exact zero."""
    with pytest.raises(ValueError, match="shard_time = 1e-06 is too short.*no collision"):
        bb.simulate(0.6, shards=2, shard_time=1e-6, seed=1, progress=False)


@pytest.mark.parametrize("shard_time", [np.int64(50), np.float32(50.0), np.float64(50.0)])
def test_numpy_scalars_are_shard_times(shard_time):
    result = bb.simulate(
        0.6,
        shards=2,
        shard_time=shard_time,
        seed=1,
        progress=False,
        settings={"equilibration_time": 10.0},
    )
    assert result.total_time == 100.0


@pytest.mark.parametrize(
    ("settings", "named"),
    [({"min_step_floor": 1e-3}, "min_step_floor"), ({"criterion_c": 0.5}, "criterion_c")],
)
def test_settings_the_pipeline_refuses_are_refused(settings, named):
    with pytest.raises(ValueError, match=named):
        bb.simulate(0.6, shards=2, shard_time=50.0, seed=1, settings=settings, progress=False)


def test_a_partial_result_says_so_and_keeps_its_shard_indices():
    full = bb.simulate(
        0.6,
        shards=3,
        shard_time=50.0,
        seed=1,
        progress=False,
        settings={"equilibration_time": 10.0},
    )
    assert not full.partial and "PARTIAL" not in repr(full)
    assert (
        not full.summary_table.partial.iloc[0] and full.summary_table.requested_shards.iloc[0] == 3
    )
    partial = SimulationResult(
        restitution=full.restitution,
        seed=full.seed,
        settings=full.settings,
        tallies=(full.tallies[0], full.tallies[2]),
        shard_indices=(0, 2),
        requested_shards=3,
    )
    assert partial.partial and "PARTIAL: shards=2 of 3 (interrupted)" in repr(partial)
    assert bool(partial.summary_table.partial.iloc[0])
    assert sorted(set(partial.batch_frame().shard)) == [0, 2]
