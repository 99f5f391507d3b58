"""``omnibot follow`` through main(argv): report, plot, truth, and clear errors for bad input."""

from __future__ import annotations

import json
from pathlib import Path as FsPath

import pytest

from omnibot.cli import main
from omnibot.control.paths import standard_path, write_path


def test_follow_writes_report_plot_and_truth(tmp_path: FsPath, capsys: pytest.CaptureFixture[str]) -> None:
    path_file = tmp_path / "s.csv"
    write_path(standard_path("s_curve", size=0.4), path_file)
    report, plot, truth = tmp_path / "r.json", tmp_path / "p.png", tmp_path / "t.csv"
    argv = [
        "follow",
        str(path_file),
        "--speed",
        "0.4",
        "--report",
        str(report),
        "--plot",
        str(plot),
        "--truth",
        str(truth),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "omnibot follow: omni4, tracker" in out and "[simulator ground truth]" in out
    data = json.loads(report.read_text())
    for key in ("rms_cross_track_m", "max_cross_track_m", "duration_s", "min_time_s", "final_error_m"):
        assert isinstance(data[key], float)
    assert data["source"] == "simulator ground truth" and data["completed"]
    assert data["rms_cross_track_m"] < 0.015
    assert plot.stat().st_size > 20_000
    assert truth.read_text().startswith("t,x,y,theta\n0.000,0.0")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["follow", "{bad}"], "line 3, column x: 'oops' is not a number"),
        (["follow", "{missing}"], "cannot read"),
        (["follow", "{good}", "--follower", "purepursuit"], "unknown follower 'purepursuit'"),
        (["follow", "{good}", "--estimator", "magic"], "unknown estimator 'magic'"),
        (["follow", "{good}", "--speed", "-1"], "--speed: expected a positive number"),
        (["follow", "{good}", "--robot", "omni5"], "unknown robot 'omni5'"),
        (["follow", "{good}", "--port", "bogus://x"], "omnibot: error:"),
        (
            ["record", "--out", "{out}", "--sample-distance", "0"],
            "--sample-distance: expected a positive number",
        ),
        (["record", "--out", "{out}", "--shape", "circel"], "did you mean 'circle'"),
        (
            ["record", "--out", "{out}", "--teach", "push", "--port", "sim://omni4", "--shape", "zigzag"],
            "unknown path 'zigzag'",
        ),
    ],
)
def test_bad_input_exits_2_without_a_traceback(
    argv: list[str], message: str, tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "bad.csv").write_text("t,x,y,theta\n0,0,0,0\n1,oops,0,0\n")
    write_path(standard_path("line", size=0.2), tmp_path / "good.csv")
    names = {
        "bad": tmp_path / "bad.csv",
        "good": tmp_path / "good.csv",
        "missing": tmp_path / "nope.csv",
        "out": tmp_path / "o.csv",
    }
    assert main([a.format(**names) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and message in err
    assert "Traceback" not in err
