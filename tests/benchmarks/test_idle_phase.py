"""The idle-phase benchmark: its sweep on a calibration file (lockstep, a few MOVEs) and its table."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from benchmarks import idle_phase
from omnibot.calibration import load_calibration

CAL = Path(__file__).resolve().parents[1] / "data" / "omni4_carpet_calibration_before_idle_phase.yaml"


def test_the_idle_wheels_angle_moves_an_axis_move_and_the_term_takes_it_out() -> None:
    spec = load_calibration(CAL).for_surface("carpet")
    results = idle_phase.sweep("nominal", "carpet", spec, [0.0], [0.3], [0.0, 0.5], seed=1)
    off, on = results[(0.0, 0.3, False)], results[(0.0, 0.3, True)]
    # without the term: least resistant position further than half a pitch on (measured +45.4 / +26.0 %:
    # this file's tables were fitted on the carpet of 4x wood's roller drag, so both run too far here)
    assert off[0] - off[1] > 0.15 and off[1] > 0.15
    # this file's term (before the MOVEs measured the drag) takes out about a third of it (12.4 % left)
    assert 0.5 * (off[0] - off[1]) < on[0] - on[1] < 0.8 * (off[0] - off[1])


def test_table_rows_give_each_phase_the_spread_and_the_mean() -> None:
    results = {(90.0, 0.5, True): [0.01, -0.02], (90.0, 0.5, False): [0.2, math.nan]}
    lines = idle_phase.table(results, [0.0, 4.0], 8, "turn")
    assert "fraction of a wheel turn" in lines[0]
    assert lines[2] == "| course, m/s, term | 0 | 0.5 | spread | mean |"
    assert lines[4] == "| 90, 0.5, on | +1.0 | -2.0 | 3.0 | -0.5 |"
    assert lines[5] == "| 90, 0.5, off | +20.0 | +nan | 0.0 | +20.0 |"


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--speeds", "fast"], "comma-separated numbers"),
        (["--steps", "1"], "at least 2"),
        (["--speeds", "0.3,-1"], "positive"),
        (["--surface", "wood", "--calibration", str(CAL.with_name("missing.yaml"))], "missing.yaml"),
    ],
)
def test_bad_arguments_are_refused_in_one_line(
    args: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        idle_phase.main(["--calibration", str(CAL), *args])
    assert exc.value.code == 2
    assert says in capsys.readouterr().err.strip().splitlines()[-1]
