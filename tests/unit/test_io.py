"""Tables and files: written atomically, readable by colleagues, refused with the file named."""

import os
import stat

import pandas as pd
import pytest

from bouncing_ball.workflow.io import (
    EXPONENTS,
    UnreadableFileError,
    atomic_paths,
    read_table,
    write_csv_and_markdown,
    write_table,
    write_tables,
)


@pytest.fixture
def umask_022():
    previous = os.umask(0o022)
    yield
    os.umask(previous)


def _mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def test_results_get_the_mode_the_umask_gives_not_a_private_one(tmp_path, umask_022):
    table = tmp_path / "table.parquet"
    write_table(pd.DataFrame({"v": [1.0]}), table, {"r": "1/2"})
    assert _mode(table) == 0o644
    with atomic_paths(tmp_path / "figure.pdf") as (temporary,), open(temporary, "w") as handle:
        handle.write("%PDF")
    assert _mode(tmp_path / "figure.pdf") == 0o644
    os.umask(0o077)
    write_table(pd.DataFrame({"v": [1.0]}), tmp_path / "private.parquet", {})
    assert _mode(tmp_path / "private.parquet") == 0o600
    assert read_table(table)[1]["r"] == "1/2"


def test_a_rules_outputs_appear_together_or_not_at_all(tmp_path):
    """A solve whose summary cannot be written leaves no P(0,v) table either."""
    (tmp_path / "summary.parquet").mkdir()  # a directory where the summary should go
    frames = {
        tmp_path / "p0v.parquet": pd.DataFrame({"v": [1.0], "p0v": [0.5]}),
        tmp_path / "summary.parquet": pd.DataFrame({"r": [0.5]}),
    }
    with pytest.raises(OSError):
        write_tables(frames, {"r": "1/2"})
    assert not (tmp_path / "p0v.parquet").exists()
    assert sorted(path.name for path in tmp_path.iterdir()) == ["summary.parquet"]


def test_a_failed_csv_and_markdown_pair_leaves_neither(tmp_path):
    (tmp_path / "table.md").mkdir()
    with pytest.raises(OSError):
        write_csv_and_markdown(
            pd.DataFrame({"r": [0.5]}), tmp_path / "table.csv", tmp_path / "table.md", "| r |"
        )
    assert not (tmp_path / "table.csv").exists()


def test_a_reader_refuses_a_table_of_another_kind_naming_the_file(tmp_path):
    path = tmp_path / "exponents.parquet"
    write_table(pd.DataFrame({"v": [1.0], "p0v": [0.5]}), path, {"rule": "solve"})
    with pytest.raises(UnreadableFileError, match="exponents.parquet: not a exponents table"):
        read_table(path, EXPONENTS)
    write_table(pd.DataFrame({"r": [0.5], "beta": [1.0]}), path, {"rule": "theory"})
    with pytest.raises(UnreadableFileError, match="exponents.parquet: .*lacks the columns m, q"):
        read_table(path, EXPONENTS)
    assert read_table(path)[1]["rule"] == "theory"  # no kind asked: read as it is


def _save_in_a_loop(path, saves, start, failures):
    import pandas as pd

    from bouncing_ball.parquet import write_table as write

    start.wait()
    for k in range(saves):
        try:
            write(pd.DataFrame({"v": [float(k)] * 2000}), path, {"save": k})
        except OSError as error:
            failures.put(f"{path.name} save {k}: {type(error).__name__}: {error}")


def test_two_writers_in_one_folder_never_remove_each_others_temporaries(tmp_path):
    """run1.parquet's writer took run1.seed2.parquet's temporaries for stale ones (a glob
    .run1.*.parquet) and removed them mid-write: a save of the other failed."""
    import multiprocessing

    context = multiprocessing.get_context("fork")
    start, failures = context.Event(), context.Queue()
    writers = [
        context.Process(target=_save_in_a_loop, args=(tmp_path / name, 60, start, failures))
        for name in ("run1.parquet", "run1.seed2.parquet")
    ]
    for writer in writers:
        writer.start()
    start.set()
    for writer in writers:
        writer.join(timeout=120)
    found = []
    while not failures.empty():
        found.append(failures.get())
    assert [writer.exitcode for writer in writers] == [0, 0]
    assert found == []
    assert sorted(path.name for path in tmp_path.iterdir()) == [
        "run1.parquet",
        "run1.seed2.parquet",
    ]


def test_only_a_targets_own_temporaries_of_a_gone_writer_are_removed(tmp_path):
    """A killed writer's temporary of the same file goes; another target's, or a live
    writer's, stays."""
    import subprocess
    import sys

    from bouncing_ball import parquet

    gone = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True
    )
    dead_pid = int(gone.stdout)
    host = parquet._host_tag()
    suffix = parquet.TEMPORARY_MARK + ".parquet"
    left = tmp_path / f".run1.parquet.{host}.{dead_pid}.abc_12{suffix}"
    other = tmp_path / f".run1.seed2.parquet.{host}.{dead_pid}.abc_12{suffix}"
    live = tmp_path / f".run1.parquet.{host}.{os.getppid()}.xyz{suffix}"
    for path in (left, other, live):
        path.write_text("half a file")
    write_table(pd.DataFrame({"v": [1.0]}), tmp_path / "run1.parquet", {})
    assert not left.exists()
    assert other.exists() and live.exists()
