"""``omnibot send``: the protocol by hand, one shot, over any link URL.

It sends the commands given on the command line, prints every reply and the events seen until the
replies are in (with ``--wait-idle`` until IDLE), and exits 0 if every reply was OK, 1 if any was an
ERROR (or the link failed), 2 for bad input. A motion it was asked to send keeps running when it ends
normally; on an error or an interrupt the robot gets STOP. Either way the controller is left in the
text protocol.
"""

from __future__ import annotations

import argparse
import sys
from typing import TextIO

from omnibot.apps.formats import format_event, format_reply
from omnibot.cliargs import add_robot_options, positive
from omnibot.client import Event
from omnibot.errors import ControllerError


def run(args: argparse.Namespace) -> int:
    """``omnibot send``, its timeouts checked first."""
    positive(args.timeout, "--timeout")
    positive(args.idle_timeout, "--idle-timeout")
    return run_send(args)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """``omnibot send``'s options (anywhere among its commands: ``intermixed``)."""
    p.add_argument(
        "commands", nargs="+", metavar="COMMANDS", help="protocol text, e.g. 'MOVE,2,40,0,0;STATUS'"
    )
    add_robot_options(p)
    p.add_argument("--timeout", type=float, default=2.0, help="seconds to wait for each reply (default 2)")
    p.add_argument("--wait-idle", action="store_true", help="after the replies, wait for IDLE")
    p.add_argument("--idle-timeout", type=float, default=60.0, help="seconds --wait-idle waits (default 60)")
    p.add_argument("--binary", action="store_true", help="speak the binary protocol (MODE bit 2)")
    p.set_defaults(intermixed="commands")


def run_send(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """``omnibot send``: exit status 0 all OK, 1 an ERROR reply or link trouble, 2 bad input."""
    from omnibot.cliargs import check_sim_options, recording_of, sim_url
    from omnibot.client import robot_session

    out = out or sys.stdout
    for line in args.commands:
        if not line.isascii():
            print(f"omnibot: error: commands are ASCII only: {line!r}", file=sys.stderr)
            return 2
    if not "".join(args.commands).replace(";", "").strip():  # `send "$EMPTY"`: nothing was sent, no OK
        print("omnibot: error: no command to send (the arguments are empty)", file=sys.stderr)
        return 2
    check_sim_options(args)
    status = 0
    with robot_session(
        sim_url(args),
        args.robot,
        stop="on_error",
        restore="protocol",
        timeout=args.timeout,
        reconnect=None,
        recording=recording_of(args),
    ) as session:
        client = session.client

        def show(event: Event) -> None:
            print(format_event(event), file=out, flush=True)

        client.add_listener(show)
        if args.binary:
            client.use_binary()
        for line in args.commands:
            pendings = client.submit_text(line)
            for p in pendings:
                print(f"-> {p.line}", file=out, flush=True)
            for p in pendings:
                try:
                    p.result()
                except ControllerError:
                    status = 1
                if p.reply is not None:
                    print(format_reply(p.reply), file=out, flush=True)
        if args.wait_idle:
            client.wait_idle(args.idle_timeout)
        client.pump(0)
    return status
