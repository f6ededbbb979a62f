"""The benchmark's Markdown report (benchmarks/report.py) from a small made-up result dict:
no benchmark is run here."""

import pandas as pd

from benchmarks.benchmark import write_markdown
from benchmarks.report import machine_info, markdown_report

MACHINE = {
    "cpu_model": "Test CPU 9000",
    "cores": 2,
    "platform": "Linux-test",
    "python": "3.11.7",
    "numba": "0.60.0",
    "numpy": "2.0.0",
    "scipy": "1.14.0",
    "snakemake": "8.0.0",
}


def _part(name, ns, collisions, extra=None):
    part = {"part": name, "ns_per_step": ns, "collisions_per_cpu_second": collisions}
    if extra is not None:
        part["extra_ns_per_step"] = extra
    return part


def fake_results(hand_tuned=True, scaling=False):
    breakdown = {
        "r": 0.5,
        "criterion_c": 5.0,
        "parts": [_part("stepping", 40.0, 9.0e5), _part("every tally", 100.0, 4.0e5, 60.0)],
        "criterion_root_ns": 20.0,
        "criterion_root_cold_start_ns": 30.0,
        "two_normals_ns": 8.0,
    }
    if hand_tuned:
        breakdown["hand_tuned_collisions_per_cpu_second"] = 1.0e6
        breakdown["against_hand_tuned"] = {"stepping": 0.9, "every tally": 0.4}
    else:
        breakdown["hand_tuned_skipped"] = "the C compiler 'gcc' was not found on PATH"
    efficiency = {
        "shards": 64,
        "shard_times": {"0.5": 1.0e5},
        "criterion_c": {"paper": 5.0, "default": 3.0},
        "speeds": [0.01, 5.0],
        "positions": [1.0e-3, 50.0],
        "cpu_seconds": {"paper r=0.5": 6.0, "default r=0.5": 5.0},
        "rows": [
            {
                "observable": "<x>",
                "r": 0.5,
                "paper": 8.0e-5,
                "paper_err": 2.0e-5,
                "default": 2.0e-6,
                "default_err": 5.0e-7,
                "gain": 40.0,
                "gain_err": 14.1,
            }
        ],
    }
    results = {
        "started_utc": "2000-01-01 12:00:00",
        "seconds": 75.0,
        "machine": MACHINE,
        "simulation": {
            "rows": [
                {
                    "r": 0.5,
                    "criterion_c": c,
                    "cpu_seconds": 2.0,
                    "collisions_per_cpu_second": 1.0e6,
                    "simulated_time_per_cpu_second": rate,
                    "steps_per_collision": 10.0,
                    "ns_per_step": 50.0,
                }
                for c, rate in ((3.0, 4.0e5), (5.0, 3.0e5))
            ],
            "default_c": 3.0,
            "paper_c": 5.0,
            "min_step_divisor": 500.0,
        },
        "breakdown": [breakdown],
        "reference": {
            "r": 0.5,
            "simulated_time": 2.0e6,
            "criterion_c": 3.0,
            "compiler": "-O3",
            "rows": [
                {
                    "case": "with tallies",
                    "numba_cpu_seconds": 1.0,
                    "c_cpu_seconds": 0.95,
                    "speed_ratio": 0.95,
                    "identical_tallies": True,
                }
            ],
            "worst_speed_ratio": 0.95,
            "target_met": True,
        },
        "efficiency": efficiency,
        "compile": {
            "first_shard_compile_seconds": 30.0,
            "later_shard_load_seconds": 0.3,
            "import_seconds": 1.0,
            "peak_memory_mib": 200.0,
            "memory_before_shard_mib": 150.0,
            "memory_shard_time": 2.0e5,
        },
        "solver": {
            "rows": [
                {
                    "r": 0.5,
                    "nodes": 100,
                    "solve_ms": 10.0,
                    "solve_and_401_outputs_ms": 12.0,
                    "energy_balance_residual": 1e-12,
                    "error_vs_exact": 1e-10,
                },
                {
                    "r": 0.75,
                    "nodes": 120,
                    "solve_ms": 60.0,
                    "solve_and_401_outputs_ms": 70.0,
                    "energy_balance_residual": 1e-12,
                },
            ],
            "worst_solve_ms": 60.0,
            "worst_error_vs_exact": 1e-10,
            "accuracy_target": 1e-8,
            "target_met": False,
        },
        "distribution": {
            "rows": [
                {
                    "r": 0.5,
                    "weight_function_seconds": 1.0,
                    "position_and_weight_tables_seconds": 0.5,
                    "distribution_table_seconds": 2.0,
                    "collision_tables_seconds": 0.25,
                    "total_seconds": 3.75,
                }
            ]
        },
        "first_curve": {
            "rows": [
                {
                    "r": 0.6,
                    "points": 1000,
                    "first_cold_seconds": 1.5,
                    "first_warm_seconds": 0.5,
                    "second_seconds": 0.02,
                },
                {
                    "r": 0.99,
                    "points": 1000,
                    "first_cold_seconds": 3.0,
                    "first_warm_seconds": 1.5,
                    "second_seconds": 0.02,
                },
            ],
            "worst_first_warm_seconds": 1.5,
            "target_met": False,
        },
        "workflow": {
            "grid_shard_jobs": 320,
            "grid_dry_run_seconds": 4.0,
            "default_results_complete": False,
            "noop_seconds": None,
            "default_dry_run_seconds": 2.0,
        },
    }
    if scaling:
        results["scaling"] = {
            "shards": 16,
            "shard_time": 5.0e6,
            "cores_1_seconds": 100.0,
            "cores_2_seconds": 50.0,
            "speedup": 2.0,
        }
    return results


def _tables(markdown):
    """Each pipe table of a Markdown page, as a list of rows of cells (header first)."""
    tables, current = [], []
    for line in markdown.splitlines() + [""]:
        if line.startswith("|"):
            cells = [cell.strip() for cell in line.strip("|").split("|")]
            if not set("".join(cells)) <= set("-:"):  # not the separator row
                current.append(cells)
        elif current:
            tables.append(current)
            current = []
    return tables


def test_the_report_names_the_machine_and_the_time_of_the_run():
    page = markdown_report(fake_results())
    assert page.startswith("# Benchmark\n")
    assert "started 2000-01-01 12:00:00 (UTC)" in page
    machine = dict(row for row in _tables(page)[0][1:])
    assert machine["CPU"] == "Test CPU 9000" and machine["cores"] == "2"
    assert machine["Python"] == "3.11.7" and machine["numba"] == "0.60.0"


def test_the_report_has_a_table_per_measurement_with_its_values():
    page = markdown_report(fake_results())
    tables = _tables(page)
    headers = [table[0] for table in tables]
    simulation = tables[headers.index(["r", "c", "CPU s", "collisions / CPU s",
                                       "simulated time / CPU s", "steps / collision",
                                       "ns / step"])]  # fmt: skip
    assert simulation[1:] == [
        ["0.5", "3", "2.00", "1e+06", "4e+05", "10.0", "50"],
        ["0.5", "5", "2.00", "1e+06", "3e+05", "10.0", "50"],
    ]
    assert "c = 3 over c = 5: 25% at r = 0.5" in page  # 1 - 3e5 / 4e5
    parts = next(table for table in tables if table[0][0] == "part")
    assert parts[1:] == [
        ["stepping", "40.0", "", "9e+05"],
        ["every tally", "100.0", "60.0", "4e+05"],
    ]
    anchor = next(table for table in tables if "stepping / hand-tuned" in table[0])
    assert anchor[1] == ["5", "1e+06", "0.90", "met", "0.40"]
    reference = next(table for table in tables if table[0][0] == "case")
    assert reference[1] == ["with tallies", "1.00", "0.95", "0.95", "True"]
    solver = next(table for table in tables if table[0][:2] == ["r", "nodes"])
    assert solver[1][-1] == "1.0e-10" and solver[2][-1] == ""  # no exact solution at 3/4
    assert "Target: <= 50 ms per r at <= 1e-08: MISSED (worst 60.0 ms" in page
    efficiency = next(table for table in tables if table[0][0] == "observable")
    assert efficiency[0] == ["observable", "r", "paper", "default", "gain", "target"]
    assert efficiency[1] == [
        "<x>",
        "0.5",
        "8.00e-05 +- 2e-05",
        "2.00e-06 +- 5e-07",
        "40.0 +- 14.1",
        ">= 4: met",
    ]
    first = next(table for table in tables if "first, warm cache CPU s" in table[0])
    assert first[1] == ["0.6", "1000", "1.50", "0.50", "0.020", "<= 1 s: met"]
    assert first[2] == ["0.99", "1000", "3.00", "1.50", "0.020", "<= 1 s: MISSED"]
    workflow = next(table for table in tables if table[0][1:] == ["seconds", "target"])
    assert workflow[1] == ["dry run of 20 r x 16 shards (320 shard jobs)", "4.0", "< 5 s: met"]
    assert workflow[2][2] == "not measured: its results are not complete"
    assert not any("--cores 1 s" in header for header in headers)


def test_the_report_says_what_was_not_measured_and_shows_the_scaling():
    results = fake_results(hand_tuned=False, scaling=True)
    results["reference"] = {"skipped": "no gcc"}
    page = markdown_report(results)
    assert "Not measured: no gcc." in page
    anchor = next(table for table in _tables(page) if table[0][0] == "c")
    assert anchor[1] == ["5", "the C compiler 'gcc' was not found on PATH"]
    scaling = next(table for table in _tables(page) if "--cores 1 s" in table[0])
    assert scaling[1][1:] == ["100.0", "50.0", "2.00", ">= 1.8: met"]


def test_the_tables_are_markdown_that_pandas_reads_back(tmp_path):
    path = tmp_path / "results" / "benchmarks" / "benchmark.md"
    write_markdown(markdown_report(fake_results()), path)  # makes the folders
    for table in _tables(path.read_text()):
        frame = pd.DataFrame(table[1:], columns=table[0])
        assert len(frame.columns) == len(table[0]) and all(
            len(row) == len(table[0]) for row in table
        )


def test_machine_info_names_the_cpu_and_the_versions():
    machine = machine_info()
    assert machine["cpu_model"] and machine["cores"] >= 1
    assert machine["python"].count(".") == 2 and machine["numba"][0].isdigit()


def test_the_efficiency_only_report_has_the_header_and_the_efficiency_table():
    everything = fake_results()
    results = {key: everything[key] for key in ("started_utc", "seconds", "machine", "efficiency")}
    page = markdown_report(results)
    assert [table[0][0] for table in _tables(page)] == ["", "observable"]
