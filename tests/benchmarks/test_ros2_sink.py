"""The ROS 2 sink's cost benchmark runs (in its private network namespace) and measures both cases."""

from __future__ import annotations

import re

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from benchmarks import ros2_sink


def test_quick_run_measures_with_and_without_a_namespace(capfd: pytest.CaptureFixture[str]) -> None:
    assert ros2_sink.main(["--cycles", "50", "--backend", "dds"]) == 0
    out = capfd.readouterr().out
    if "skipped" in out:
        pytest.skip(out.strip())
    costs = re.findall(r"dds, (namespace robot1 \(frames prefixed\)|no namespace): the sink (\d+) us", out)
    assert [where for where, _ in costs] == ["namespace robot1 (frames prefixed)", "no namespace"], out
    assert all(int(us) > 0 for _, us in costs), out
