"""``omnibot dashboard``: serves until its time is up; bad input exits 2 with one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from omnibot.cli import main


def test_serves_and_stops(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["dashboard", "--http-port", "0", "--duration", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "omnibot dashboard for sim://omni4?seed=1&world=room: http://127.0.0.1:" in out
    assert "token" not in out


def test_token_from_the_environment(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("OMNIBOT_DASHBOARD_TOKEN", "from-the-env")
    assert main(["dashboard", "--http-port", "0", "--duration", "0.2"]) == 0
    assert "/?token=from-the-env" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--http-port", "70000"], "--http-port: expected a port 0..65535, got 70000"),
        (["--token", "short"], "--token: an access token needs at least 8 characters"),
        (["--host", "no.such.host.invalid"], "--host: cannot resolve 'no.such.host.invalid'"),
        (["--duration", "-1"], "--duration: expected a positive number of seconds"),
        (["--port", "bogus://x"], "bogus"),
        (["--world", "moon"], "moon"),
        (["--path", "missing.csv"], "--path: cannot read path missing.csv"),
        (["--repeat-speed", "0"], "--repeat-speed: expected a positive speed in m/s, got 0"),
        (["--robot", "omni5"], "unknown robot 'omni5'"),
    ],
)
def test_bad_arguments_exit_2(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["dashboard", "--http-port", "0", "--duration", "0.1", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and message in err
    assert "Traceback" not in err


def test_path_and_config_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "path.csv"
    path.write_text("x,y\n1,1\n3,1\n3,3\n")
    config = tmp_path / "pad.yaml"
    config.write_text("speed_max: 0.3\n")
    assert (
        main(
            [
                "dashboard",
                "--http-port",
                "0",
                "--duration",
                "0.1",
                "--path",
                str(path),
                "--config",
                str(config),
            ]
        )
        == 0
    )
    config.write_text("spede_max: 0.3\n")
    assert main(["dashboard", "--http-port", "0", "--config", str(config)]) == 2
    assert "spede_max: unknown key; did you mean 'speed_max'?" in capsys.readouterr().err
