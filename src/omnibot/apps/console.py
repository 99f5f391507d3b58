"""``omnibot console``: the protocol by hand, an interactive terminal over any link URL.

Lines typed are sent as they are; replies and decoded events are printed as they come (``<- RANGE
sonar 1: 42 cm``: :mod:`omnibot.apps.formats`), also while the prompt waits.
Lines starting with ``:`` are console commands (``:help``). With a terminal, input is read with
readline (history in ``~/.omnibot_history``) in a helper thread while the main thread keeps the
link pumped; on ``sim://`` the main thread also advances simulated time with the wall clock, so
the simulated robot lives in real time while you type. With piped input there is no helper
thread: lines are handled one after the other, and simulated time advances only while waiting
for replies and with ``:wait``. However the console ends (``:quit``, end of input, Ctrl-C, the link
dropping) the robot gets STOP and the controller its MODE from the start back
(:func:`omnibot.client.session.guarded`).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import queue
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TextIO

from omnibot.apps.formats import commas, format_event, format_reply
from omnibot.cliargs import add_robot_options, positive
from omnibot.client import Event, RobotClient, Telemetry
from omnibot.errors import ControllerError, LinkError, LinkTimeout, ProtocolError

DEFAULT_PORT = "sim://omni4"
HISTORY = Path("~/.omnibot_history")
PROMPT = "> "
QUIT = (":quit", ":q", ":exit")

HELP = """\
Type protocol commands (several per line with ';'), e.g. MOVE,20,40,0,0  STATUS  STOP
Console commands:
  :help              this text
  :quit              leave (also :q, :exit, Ctrl-D)
  :tel on|off        show or hide TEL lines (shown by default)
  :wait SECONDS      let time pass, showing events
  :idle [SECONDS]    wait for IDLE (default 30 s)
  :status            STATUS in SI units
  :binary / :text    switch the protocol (replies and events look the same)"""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """``omnibot console``'s options."""
    add_robot_options(p)
    p.add_argument("--timeout", type=float, default=2.0, help="seconds to wait for each reply (default 2)")


def run(args: argparse.Namespace) -> int:
    """``omnibot console``, its timeout checked first."""
    positive(args.timeout, "--timeout")
    return run_console(args)


class Console:
    """The interactive console's state: the client, where to print, whether TEL is shown."""

    def __init__(self, client: RobotClient, out: TextIO, echo: bool) -> None:
        self.client = client
        self.out = out
        self.echo = echo
        self.show_tel = True
        self.prompting = False
        """True while the input thread shows the prompt: events are printed above it."""
        self.lost = False
        """The link failed and no command went through since (the console exits 1)."""
        client.add_listener(self._event)

    def say(self, line: str) -> None:
        """Print one line of the console's own output (flushed at once)."""
        print(line, file=self.out, flush=True)

    def _event(self, event: Event) -> None:
        if not self.show_tel and isinstance(event, Telemetry):
            return
        if self.prompting and self.out.isatty():  # above the prompt, then show it again as typed
            self.out.write(f"\r\x1b[K{format_event(event)}\n{PROMPT}{_typed()}")
            self.out.flush()
        else:
            self.say(format_event(event))

    def handle(self, line: str) -> bool:
        """Handle one input line; False to quit."""
        line = line.strip()
        if not line:
            self.client.pump(0)
            return True
        if self.echo:
            self.say(f"-> {line}")
        try:
            if line.startswith(":"):
                return self._meta(line)
            self._send(line)
            self.lost = False
        except LinkTimeout as exc:
            self.say(f"!! {exc}")
        except LinkError as exc:
            self.lost = True
            self.say(f"!! link error: {exc}")
        except (ProtocolError, ValueError) as exc:
            self.say(f"!! {exc}")
        return True

    def _send(self, line: str) -> None:
        for p in self.client.submit_text(line):
            with contextlib.suppress(ControllerError):
                p.result()
            if p.reply is not None:
                self.say(format_reply(p.reply))

    def _meta(self, line: str) -> bool:
        word, *rest = line.split()
        word = word.lower()
        client = self.client
        if word in QUIT:
            return False
        if word == ":help":
            self.say(HELP)
        elif word == ":tel" and rest and rest[0].lower() in ("on", "off"):
            self.show_tel = rest[0].lower() == "on"
        elif word == ":wait" and len(rest) == 1:
            client.sleep(_seconds(rest[0]))
        elif word == ":idle" and len(rest) <= 1:
            client.wait_idle(_seconds(rest[0]) if rest else 30.0)
            self.say("idle")
        elif word == ":status" and not rest:
            s = client.status()
            m = s.move
            self.say(
                f"{s.state_name}, {s.queued}/{s.capacity} queued, mode {s.mode}, powers {commas(s.powers)}; "
                f"move {m.distance:g} m at {m.speed:g} m/s, course {math.degrees(m.course):g} deg, "
                f"curvature {m.curvature:g} 1/m"
            )
        elif word == ":binary" and not rest:
            h = client.use_binary()
            self.say(f"binary protocol, version {h.version}")
        elif word == ":text" and not rest:
            client.use_text()
            self.say("text protocol")
        else:
            self.say(f"?? unknown console command {line!r}; :help lists them")
        return True


def _seconds(word: str) -> float:
    try:
        value = float(word)
    except ValueError:
        raise ValueError(f"expected seconds, got {word!r}") from None
    if not 0 <= value < math.inf:
        raise ValueError(f"expected seconds >= 0, got {word!r}")
    return value


def run_console(
    args: argparse.Namespace,
    stdin: TextIO | None = None,
    out: TextIO | None = None,
    interactive: bool | None = None,
    input_fn: Callable[[str], str] = input,
) -> int:
    """``omnibot console``; ``interactive`` defaults to whether ``stdin`` is a terminal."""
    from omnibot.cliargs import check_sim_options, recording_of, sim_url
    from omnibot.client import robot_session

    stdin = stdin or sys.stdin
    out = out or sys.stdout
    if interactive is None:
        interactive = stdin.isatty()
    check_sim_options(args)
    with robot_session(
        sim_url(args), getattr(args, "robot", None), timeout=args.timeout, recording=recording_of(args)
    ) as session:
        client = session.client
        console = Console(client, out, echo=not interactive)
        if interactive:
            console.say(f"omnibot console on {client.link.url}; :help for help, :quit to leave")
            _interactive(console, input_fn)
        else:
            for line in stdin:
                if not console.handle(line):
                    break
                client.pump(0)
        try:
            client.drain()
            client.pump(0)
        except LinkError as exc:
            console.lost = console.lost or not isinstance(exc, LinkTimeout)
            console.say(f"!! {exc}")
    if console.lost:
        print("omnibot: error: the link to the controller failed", file=sys.stderr)
        return 1
    return 0


def _interactive(console: Console, input_fn: Callable[[str], str]) -> None:
    """Read lines in a helper thread (readline, history); pump the link in this one."""
    history = _load_history()
    lines: queue.Queue[str | None] = queue.Queue()
    ready = threading.Event()
    ready.set()

    def reader() -> None:
        try:
            while True:
                ready.wait()
                ready.clear()
                console.prompting = True
                line = input_fn(PROMPT)
                console.prompting = False
                lines.put(line)
                if line.strip().lower() in QUIT:
                    return
        except (EOFError, KeyboardInterrupt):
            pass
        finally:
            lines.put(None)

    thread = threading.Thread(target=reader, name="omnibot-console-input", daemon=True)
    thread.start()
    client = console.client
    clock = client.clock
    wall0, clock0 = time.monotonic(), clock.now()
    try:
        while True:
            try:
                line = lines.get(timeout=0.05)
            except queue.Empty:
                line = ""
            else:
                if line is None:
                    break
                if not console.handle(line):
                    break
                ready.set()
                wall0, clock0 = time.monotonic(), clock.now()
            ahead = clock0 + (time.monotonic() - wall0) - clock.now()
            if ahead > 0.001:  # simulated time: keep up with the wall clock while waiting for input
                client.sleep(ahead)
            else:
                client.pump(0)
    finally:
        ready.set()
        thread.join(timeout=0.5)
        _save_history(history)


def _typed() -> str:
    """What the user has typed at the prompt so far (readline's buffer)."""
    try:
        import readline
    except ImportError:  # pragma: no cover
        return ""
    return readline.get_line_buffer()


def _load_history() -> Path | None:
    try:
        import readline
    except ImportError:  # pragma: no cover - no readline on this platform
        return None
    path = Path(os.path.expanduser(str(HISTORY)))
    with contextlib.suppress(OSError):
        readline.read_history_file(path)
    readline.set_history_length(1000)
    return path


def _save_history(path: Path | None) -> None:
    if path is None:
        return
    import readline

    with contextlib.suppress(OSError):
        readline.write_history_file(path)
