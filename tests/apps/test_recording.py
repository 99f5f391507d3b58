"""The command's recording: ``--foxglove`` puts Foxglove's Teleop panel on every runtime the command
records, ``--log`` alone adds no source; ``main`` hands the recording to the command."""

from __future__ import annotations

import argparse
from pathlib import Path

from omnibot.apps.recording import CommandRecording, command_recording
from omnibot.cliargs import recording_of
from omnibot.client import robot_session
from omnibot.logs import Recording
from omnibot.logs.recording import FoxgloveBind
from omnibot.runtime import Runtime


def _sources_of_a_recorded_runtime(rec: CommandRecording) -> list[str]:
    with robot_session("sim://omni4", "omni4", timeout=0.5, recording=rec) as session:
        runtime = Runtime(session.client, period=0.01, recording=rec)
        runtime.start()
        runtime.start()  # once per runtime, however often it starts
        runtime.close()
    return sorted(runtime.sources)


def test_the_panel_drives_the_runtimes_of_a_command_that_serves_foxglove(tmp_path: Path) -> None:
    rec = Recording(tmp_path / "f.mcap", foxglove=FoxgloveBind("127.0.0.1", 0))
    try:
        assert _sources_of_a_recorded_runtime(CommandRecording(rec, panel_drives=True)) == ["foxglove"]
    finally:
        rec.close()


def test_a_log_alone_adds_no_source(tmp_path: Path) -> None:
    rec = Recording(tmp_path / "l.mcap")
    try:
        assert _sources_of_a_recorded_runtime(CommandRecording(rec, panel_drives=False)) == []
        assert rec.recorder is not None and (tmp_path / "l.mcap").exists()
    finally:
        rec.close()


def test_the_recording_the_options_ask_for(tmp_path: Path) -> None:
    none = argparse.Namespace(log=None, foxglove=None, foxglove_token=None)
    with command_recording(none) as rec:
        assert rec is None
    asked = argparse.Namespace(log=str(tmp_path / "a.mcap"), foxglove="127.0.0.1:0", foxglove_token=None)
    with command_recording(asked) as rec:
        assert rec is not None and rec.panel_drives and rec.recorder is None  # made with the first client
        asked.recording = rec
        assert recording_of(asked) is rec
    with command_recording(argparse.Namespace(log=str(tmp_path / "b.mcap"))) as rec:
        assert rec is not None and not rec.panel_drives
    assert recording_of(argparse.Namespace()) is None  # a command called without main records nothing


def test_main_hands_the_recording_to_the_command(tmp_path: Path) -> None:
    from omnibot import cli

    log = tmp_path / "send.mcap"
    assert cli.main(["send", "STATUS", "--log", str(log)]) == 0
    assert log.stat().st_size > 0  # send opened its session with the recording: the file was made
    assert cli.main(["send", "STATUS"]) == 0
