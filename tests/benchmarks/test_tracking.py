"""The tracking benchmark's path specs, suites and tables (no simulation: the runs are the benchmark's)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks import tracking


def test_path_specs() -> None:
    line = tracking.build_path("omni3", "line-90")
    assert line.length == pytest.approx(tracking.top_length("omni3"))
    assert line.end[:2] == pytest.approx((0.0, line.length), abs=1e-9)
    assert tracking.top_length("omni3") >= 2 * 5.0**2 / (0.7 * 2.5)  # cruises at 5 m/s
    assert np.ptp(tracking.build_path("omni4", "line-swing").theta) > math.pi / 2
    swing = tracking.build_path("omni4", "circle/swing")
    assert swing.length == pytest.approx(math.pi, rel=1e-3) and np.ptp(swing.theta) > 3.0
    a, b = tracking.build_path("omni4", "random-3"), tracking.build_path("omni4", "random-3")
    assert np.array_equal(a.y, b.y) and a.length == pytest.approx(tracking.ROBOTS["omni4"].random_length)


def test_suites_pair_seed002_with_the_tracker_at_the_top_speed() -> None:
    jobs = tracking.suite_jobs(
        "random",
        ["omni3"],
        ["wood"],
        ["seed002", "pure_pursuit", "tracker"],
        [1],
        paths=[],
        heading="fixed",
        random_count=3,
        calibrate=False,
        slip=True,
    )
    assert {(j[3], j[4]) for j in jobs} == {
        (f"random-{k}", f) for k in (1, 2, 3) for f in ("seed002", "tracker")
    }
    assert all(j[6] == 5.0 and j[7] for j in jobs)  # omni3's top speed, gyro calibration spin


def test_the_random_suite_adds_figure_eights_and_closed_curves_keeping_its_paths() -> None:
    jobs = tracking.suite_jobs(
        "random",
        ["omni4"],
        ["carpet"],
        ["tracker"],
        [1],
        paths=[],
        heading="fixed",
        random_count=2,
        calibrate=False,
        slip=True,
        families=tracking.FAMILIES,
    )
    assert [(j[3], j[5]) for j in jobs] == [
        (f"{fam}-{k}", k) for fam in ("random", "eight", "closed") for k in (1, 2)
    ]
    bench = tracking.ROBOTS["omni4"]
    eight, closed = tracking.build_path("omni4", "eight-2"), tracking.build_path("omni4", "closed-2")
    assert eight.length == pytest.approx(bench.eight_length, rel=1e-4)
    assert closed.length == pytest.approx(bench.random_length, rel=1e-4)
    for path in (eight, closed):
        assert path.end[:2] == pytest.approx(path.start[:2], abs=1e-12)
    assert tracking.family("closed-3") == "closed"
    # the smooth random paths are the suite's earlier ones, unchanged
    old = tracking.build_path("omni4", "random-2")
    assert old.length == pytest.approx(bench.random_length) and np.ptp(old.theta) > 0


def _run(path: str, follower: str, rms: float, mx: float, ratio: float) -> dict[str, object]:
    return {
        "robot": "omni4",
        "surface": "wood",
        "path": path,
        "follower": follower,
        "rms_cross_track_m": rms,
        "max_cross_track_m": mx,
        "time_ratio": ratio,
        "completed": True,
        "odometry_error_m": 0.001,
        "own_rms_cross_track_m": rms / 2,
    }


def test_random_table_and_goals_name_the_worst_path() -> None:
    runs = [_run("random-1", "tracker", 0.002, 0.01, 1.1), _run("random-2", "tracker", 0.012, 0.02, 1.3)]
    table = tracking.format_random(runs, ["tracker"])
    assert "1.20 (random-2)" in table and "| 1.30 (random-2) |" in table
    goals = tracking.suite_goals(runs, "random")
    assert "| RMS <= 1 cm | 1/2 | 1.20 cm (omni4 wood random-2) |" in goals
    assert "| time <= 1.25x minimum | 1/2 |" in goals
    eights = tracking.format_random(
        [_run("eight-1", "tracker", 0.002, 0.01, 1.1)], ["tracker"], "Figure eights"
    )
    assert "### Figure eights: the mean" in eights and "(eight-1)" in eights


def test_unknown_suite_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        tracking.main(["--suites", "fast"])
    assert exit_info.value.code == 2
    assert "unknown suite fast" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        tracking.main(["--families", "spiral"])
    assert "unknown family spiral" in capsys.readouterr().err
