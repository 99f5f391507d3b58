"""A command's recording is handed to its sessions and runtimes, never held by a module: two
runtimes in one process with different recordings record separately, one given none records nowhere."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path

from omnibot.client import robot_session
from omnibot.logs import topics
from omnibot.logs.reader import LogFile
from omnibot.logs.recording import Recording, open_recording
from omnibot.motion import Twist
from omnibot.protocol import codes
from omnibot.runtime import Runtime, ScriptSource


def _held(value: object) -> Iterator[object]:
    """``value`` and, for a container, what it holds (one level deep)."""
    yield value
    if isinstance(value, list | tuple | set | frozenset):
        yield from value
    elif isinstance(value, dict):
        yield from value.values()


def recordings_held_by_modules() -> list[str]:
    """The omnibot modules whose globals hold a recording (directly or in a container)."""
    return sorted(
        f"{name}.{attr}"
        for name, module in list(sys.modules.items())
        if name.startswith("omnibot")
        for attr, value in list(vars(module).items())
        if any(isinstance(v, Recording) for v in _held(value))
    )


def _sources(path: Path) -> set[str]:
    """Who drove, as the log's ``/omnibot/control`` says."""
    return {m.decode().source for m in LogFile.open(path).messages({topics.CONTROL})} - {""}


def test_two_runtimes_with_different_recordings_record_separately(tmp_path: Path) -> None:
    paths = {name: tmp_path / f"{name}.mcap" for name in ("alpha", "beta")}
    with open_recording(paths["alpha"]) as alpha, open_recording(paths["beta"]) as beta:
        assert alpha is not None and beta is not None
        runtimes: list[Runtime] = []
        for seed, (name, rec) in enumerate([("alpha", alpha), ("beta", beta), ("gamma", None)]):
            with robot_session(f"sim://omni4?seed={seed}", "omni4", timeout=0.5, recording=rec) as session:
                client = session.client
                script = ScriptSource(
                    lambda t: Twist(0.1, 0.0, 0.0) if t < 0.2 else ScriptSource.END, name=name
                )
                runtime = Runtime(client, period=0.01, sources=[script], recording=rec)
                runtimes.append(runtime)
                runtime.start()
                client.telemetry(0.01, codes.TEL_MASK)
                try:
                    runtime.run(duration=0.3)
                finally:
                    runtime.close()
        assert recordings_held_by_modules() == []  # handed in, held by no module
        assert alpha.recorder is not None and beta.recorder is not None
        assert alpha.recorder is not beta.recorder
        assert all(runtime.cycles > 10 for runtime in runtimes)
    assert _sources(paths["alpha"]) == {"alpha"}
    assert _sources(paths["beta"]) == {"beta"}  # gamma's runtime, given no recording, is in neither


def test_a_recording_adds_no_source_to_a_runtime(tmp_path: Path) -> None:
    """Foxglove's panel drives only where the command adds it (omnibot.apps.recording)."""
    rec = Recording(tmp_path / "r.mcap")
    with robot_session("sim://omni4", "omni4", timeout=0.5, recording=rec) as session:
        runtime = Runtime(session.client, period=0.01, recording=rec)
        runtime.start()
        try:
            assert rec.panel is None and runtime.sources == {}
            assert any(type(sink).__name__ == "RuntimeRecorder" for sink in runtime.sinks)
        finally:
            runtime.close()
    rec.close()
