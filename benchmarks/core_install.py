"""The core install as a user gets it: omnibot's wheel with its core dependencies alone (``pip install
omnibot``, no extra) in a fresh venv; its size on disk, its packages and its import times.

``python -m benchmarks.core_install [--extras all] [--repeats N] [--keep DIR]``

The sdist and the wheel are built as a release builds them, ``python -m build`` (the sdist from a copy
of this checkout's sources, caches and all, then the wheel from the sdist; the build backend fetched
by build's isolation), and the wheel is installed at constraints.txt's versions, so the figures are
those of the tested set. ``tests/test_packaging.py`` builds the same venv, one from the sdist too, and
checks what they can do.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONSTRAINTS = ROOT / "constraints.txt"
CORE_IMPORT = "import omnibot.client, omnibot.robot, omnibot.protocol"


def clean_env() -> dict[str, str]:
    """This process's environment without what would make the venv see this checkout (PYTHONPATH)."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP")}


def _run(cmd: list[str | Path]) -> subprocess.CompletedProcess[str]:
    done = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, check=False, env=clean_env())
    if done.returncode != 0:
        raise RuntimeError(
            f"{' '.join(map(str, cmd))} failed ({done.returncode}):\n{done.stdout}{done.stderr}"
        )
    return done


@dataclass(frozen=True)
class Dists:
    """What ``python -m build`` made: the source distribution and the wheel built from it."""

    sdist: Path
    wheel: Path


def build_dists(dest: Path) -> Dists:
    """omnibot's sdist and wheel, built into ``dest`` by ``python -m build`` from a copy of this
    checkout's sources with their caches (``__pycache__``, the simulator's compiled kernels), which
    the sdist must leave out; the build's ``build/`` and ``*.egg-info`` land in the copy, not in the
    checkout (a stale ``*.egg-info`` of an editable install is not copied: setuptools would read its
    file list)."""
    source = dest / "source"
    shutil.copytree(ROOT / "src", source / "src", ignore=shutil.ignore_patterns("*.egg-info"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, source / name)
    _run([sys.executable, "-m", "build", "--outdir", dest, source])
    (sdist,) = dest.glob("omnibot-*.tar.gz")
    (wheel,) = dest.glob("omnibot-*.whl")
    return Dists(sdist, wheel)


def install_venv(dist: Path, dest: Path, extras: str = "") -> Path:
    """A fresh venv in ``dest`` (no pip of its own) with ``dist``, the wheel or the sdist (and
    ``extras``, e.g. ``"all"``), installed at constraints.txt's versions; its python."""
    _run([sys.executable, "-m", "venv", "--without-pip", dest])
    python = dest / "bin" / "python"
    target = f"omnibot[{extras}] @ {dist.as_uri()}" if extras else str(dist)
    _run([sys.executable, "-m", "pip", "--python", python, "install", "--quiet", "-c", CONSTRAINTS, target])
    return python


def site_packages(python: Path) -> Path:
    """The site-packages directory of the venv of ``python``."""
    out = _run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]).stdout
    return Path(out.strip())


def installed(python: Path) -> dict[str, str]:
    """The distributions installed in the venv of ``python``: name -> version."""
    code = "import importlib.metadata as m\nfor d in m.distributions(): print(d.metadata['Name'], d.version)"
    lines = _run([python, "-c", code]).stdout.split("\n")
    return dict(line.split(" ", 1) for line in lines if line)


def size_mb(path: Path) -> float:
    """The bytes of the files under ``path`` (as ``du --apparent-size``), in MB."""
    total = sum(f.stat().st_size for f in path.rglob("*") if f.is_file() and not f.is_symlink())
    return total / 1e6


def wall(cmd: list[str | Path], repeats: int) -> list[float]:
    """The wall times of ``repeats`` runs of ``cmd`` (after one unmeasured run that writes .pyc files)."""
    _run(cmd)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        _run(cmd)
        times.append(time.perf_counter() - start)
    return times


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--extras", default="", help="install omnibot[EXTRAS] instead of the core alone")
    parser.add_argument("--repeats", type=int, default=10, help="timed runs of each command (default 10)")
    parser.add_argument("--keep", type=Path, help="build in DIR and keep it (default: a temporary directory)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="omnibot-core-") as tmp:
        work = args.keep or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        start = time.perf_counter()
        wheel = build_dists(work / "dist").wheel
        python = install_venv(wheel, work / "venv", args.extras)
        took = time.perf_counter() - start
        dists = installed(python)
        lib = site_packages(python)
        print(
            f"omnibot{f'[{args.extras}]' if args.extras else ''}: wheel {wheel.stat().st_size / 1e3:.0f} kB"
        )
        print(f"built and installed in {took:.0f} s")
        print(f"{len(dists)} distributions: {', '.join(sorted(f'{n} {v}' for n, v in dists.items()))}")
        print(f"site-packages: {size_mb(lib):.1f} MB")
        commands: tuple[tuple[str, list[str | Path]], ...] = (
            ("python -c pass", [python, "-c", "pass"]),
            (CORE_IMPORT, [python, "-c", CORE_IMPORT]),
            ("omnibot --help", [python.parent / "omnibot", "--help"]),
            ("omnibot robot list", [python.parent / "omnibot", "robot", "list"]),
        )
        for label, cmd in commands:
            times = wall(cmd, args.repeats)
            print(
                f"{label:60s} median {statistics.median(times) * 1e3:6.0f} ms, best {min(times) * 1e3:6.0f} ms"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
