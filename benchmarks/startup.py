"""Start-up: CPU time of ``omnibot --help``, ``omnibot robot list`` and the first HELLO reply of the
simulated robot, with an empty numba cache and with a filled one.

Run: ``python -m benchmarks.startup [--src DIR ...] [--repeats N]``. Each ``--src`` is an omnibot
source tree (``src/`` of a checkout; default this one's); giving two (``git archive`` of an older
commit unpacked beside) measures before and after side by side in one run. Every case is a fresh
interpreter; the figure is the process's CPU time (user + system), best of ``--repeats``, because
wall time on the shared machine moves with its load (wall time is printed too):

* ``--help``, ``robot list``: the whole process (``getrusage`` of the child);
* ``sim --pty`` first HELLO: ``omnibot sim --pty`` started, its pty opened as soon as it prints the
  path, ``HELLO`` written; the CPU its process has used when the reply arrives (``/proc/PID/stat``);
* ``send HELLO`` (``sim://omni4`` in-process, lockstep): the whole ``omnibot send HELLO`` process,
  whose first reply is its HELLO (it exits right after: an upper bound of the first reply's CPU).

"cold" points ``NUMBA_CACHE_DIR`` at an empty directory (every kernel a run needs is compiled);
"warm" at the directory the cold run filled. A tree whose cold start compiles in a process of its
own (``omnibot.sim.jit``) answers before that process ends: its CPU is reported on a row of its own
("compiling meanwhile", waited for before the warm run), as it is not the first reply's.

``--kernels`` instead prints where a cold start's time goes: each kernel of
:data:`omnibot.sim.kernels.KERNELS` compiled in turn (in that order: the helpers a kernel shares
with one before it are compiled already) in a fresh interpreter with an empty cache, CPU s each.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import select
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TICK = os.sysconf("SC_CLK_TCK")


def _env(src: Path, cache: str | None) -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=str(src), MPLBACKEND="Agg", SDL_VIDEODRIVER="dummy")
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    return env


def command_cpu(src: Path, argv: list[str], cache: str | None = None) -> tuple[float, float]:
    """(CPU s, wall s) of ``omnibot ARGV`` run to its end."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "omnibot", *argv],
        env=_env(src, cache),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        check=True,
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def _process_cpu(pid: int) -> float:
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:
        stat = f.read()
    fields = stat[stat.rfind(")") + 2 :].split()
    return sum(int(v) for v in fields[11:15]) / TICK  # utime stime cutime cstime


def pty_hello_cpu(src: Path, cache: str | None) -> tuple[float, float]:
    """(CPU s, wall s) of ``omnibot sim --pty`` from its start to its first HELLO reply."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "omnibot", "sim", "--pty"],
        env=_env(src, cache),
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert proc.stdout is not None
        path = proc.stdout.readline().strip()
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        try:
            os.write(fd, b"HELLO;\r\n")
            seen = b""
            while b"HELLO," not in seen:
                ready, _, _ = select.select([fd], [], [], 60.0)
                if not ready:
                    raise RuntimeError(f"no HELLO reply from {path}: {seen!r}")
                seen += os.read(fd, 1024)
            wall = time.perf_counter() - t0
            cpu = _process_cpu(proc.pid)
        finally:
            os.close(fd)
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=30)
        if proc.stdout is not None:
            proc.stdout.close()
    return cpu, wall


def _compilers(cache: str) -> list[int]:
    """Processes compiling the kernels into ``cache`` in the background (``python -m omnibot.sim.jit``)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            if b"omnibot.sim.jit" not in Path(f"/proc/{entry}/cmdline").read_bytes().split(b"\0"):
                continue
            environ = Path(f"/proc/{entry}/environ").read_bytes().split(b"\0")
        except OSError:  # gone, or not ours to read
            continue
        if f"NUMBA_CACHE_DIR={cache}".encode() in environ:
            found.append(int(entry))
    return found


def compiling_meanwhile(src: Path, cache: str) -> float | None:
    """CPU s of the process a cold start left compiling into ``cache``, waited for until it ends (its
    last reading); None when there is none (a tree that compiles before it answers)."""
    deadline = time.monotonic() + (5.0 if (src / "omnibot" / "sim" / "jit.py").exists() else 0.0)
    pids = _compilers(cache)
    while not pids and time.monotonic() < deadline:
        time.sleep(0.05)
        pids = _compilers(cache)
    if not pids:
        return None
    total = 0.0
    for pid in pids:
        last = 0.0
        while True:
            try:
                last = _process_cpu(pid)
                state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
            except OSError:  # ended and reaped
                break
            if state == "Z":
                break
            time.sleep(0.1)
        total += last
    return total


def best(runs: list[tuple[float, float]]) -> str:
    cpu = min(c for c, _ in runs)
    wall = min(w for _, w in runs)
    return f"{cpu:6.2f} s CPU ({wall:5.2f} s wall)"


def measure(src: Path, repeats: int) -> dict[str, str]:
    out = {
        "omnibot --help": best([command_cpu(src, ["--help"]) for _ in range(repeats)]),
        "omnibot robot list": best([command_cpu(src, ["robot", "list"]) for _ in range(repeats)]),
    }
    cases: dict[str, Callable[[str], tuple[float, float]]] = {
        "sim --pty: first HELLO": lambda cache: pty_hello_cpu(src, cache),
        "send HELLO (sim://)": lambda cache: command_cpu(src, ["send", "HELLO"], cache),
    }
    for case, run in cases.items():
        runs = [cold_then_warm(src, run) for _ in range(repeats)]
        out[f"{case}, cold cache"] = best([cold for cold, _, _ in runs])
        out[f"{case}: compiling meanwhile"] = _cpu([m for _, m, _ in runs if m is not None])
        out[f"{case}, warm cache"] = best([warm for _, _, warm in runs])
    return out


def cold_then_warm(
    src: Path, run: Callable[[str], tuple[float, float]]
) -> tuple[tuple[float, float], float | None, tuple[float, float]]:
    """``run(cache)`` on an empty cache, the CPU of any compiling it left behind (waited for), then
    ``run`` again on the cache so filled."""
    with tempfile.TemporaryDirectory(prefix="numba-cache-") as cache:
        cold = run(cache)
        meanwhile = compiling_meanwhile(src, cache)
        return cold, meanwhile, run(cache)


def _cpu(runs: list[float]) -> str:
    return f"{min(runs):6.2f} s CPU" if runs else "none"


_KERNEL_TIMES = """
import json, time
from omnibot.sim import kernels
times = []
for kernel, call in kernels.warm_up_calls():
    t0 = time.process_time()
    call()
    times.append((kernel.__name__, time.process_time() - t0))
print(json.dumps(times))
"""


def kernel_compile_cpu(src: Path) -> list[tuple[str, float]]:
    """(kernel, CPU s) of compiling each kernel in turn with an empty cache, in a fresh interpreter."""
    with tempfile.TemporaryDirectory(prefix="numba-cache-") as cache:
        out = subprocess.run(
            [sys.executable, "-c", _KERNEL_TIMES],
            env=_env(src, cache),
            capture_output=True,
            text=True,
            check=True,
        )
    return [(str(name), float(t)) for name, t in json.loads(out.stdout.splitlines()[-1])]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--src",
        action="append",
        type=Path,
        help="an omnibot source tree (repeat it to compare; default ./src)",
    )
    parser.add_argument(
        "--repeats", type=int, default=3, help="fresh processes per case, best taken (default 3)"
    )
    parser.add_argument("--kernels", action="store_true", help="CPU s to compile each kernel, cold")
    args = parser.parse_args(argv)
    sources = args.src or [ROOT / "src"]
    if args.kernels:
        for src in sources:
            times = kernel_compile_cpu(src.resolve())
            print(
                f"{src}: "
                + ", ".join(f"{name} {t:.2f}" for name, t in times)
                + f"; total {sum(t for _, t in times):.2f} s"
            )
        return 0
    results = {str(src): measure(src.resolve(), args.repeats) for src in sources}
    for case in next(iter(results.values())):
        print(f"{case:36s} " + " | ".join(r[case] for r in results.values()))
    print("columns: " + " | ".join(results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
