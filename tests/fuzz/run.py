"""Coverage-guided fuzzing with atheris (the ``fuzz`` extra): ``python -m tests.fuzz.run TARGET``.

TARGET is ``text`` (the controller's text input, firmware vs host codec) or ``binary`` (the binary
decoders); ``--seconds`` bounds the run (libFuzzer's -max_total_time); ``--corpus DIR`` keeps the
inputs that found new coverage between runs. A failing input is written as ``crash-*`` in the
current directory and the run exits non-zero. ``make fuzz`` runs both targets.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m tests.fuzz.run", description=__doc__.splitlines()[0])
    ap.add_argument("target", choices=["text", "binary"])
    ap.add_argument("--seconds", type=int, default=60, help="time budget (default 60)")
    ap.add_argument("--corpus", help="corpus directory (created if missing)")
    args = ap.parse_args(argv)
    if args.seconds <= 0:
        ap.error("--seconds must be > 0")
    try:
        import atheris
    except ImportError:
        sys.exit("atheris is missing: install the fuzz extra (pip install -e '.[fuzz]'), or run make fuzz")
    with atheris.instrument_imports(include=["omnibot", "tests.fuzz"]):
        from tests.fuzz import targets
    target: Callable[[bytes], None] = targets.text_input if args.target == "text" else targets.binary_input
    libfuzzer = [sys.argv[0], f"-max_total_time={args.seconds}", "-max_len=300", "-print_final_stats=1"]
    if args.corpus:
        import os

        os.makedirs(args.corpus, exist_ok=True)
        libfuzzer.append(args.corpus)
    atheris.Setup(libfuzzer, target)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
