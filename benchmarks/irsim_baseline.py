"""IR-SIM 2.12 baseline: steps per second of one kinematic omni robot, headless.

IR-SIM integrates an ideal omni robot kinematically (position += velocity * dt), so this is the
floor of what a Python robot simulator costs per step; omnibot's step does wheel dynamics, motors,
friction and sensors on top.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import time
from pathlib import Path

WORLD = """
world:
  height: 10
  width: 10
  step_time: 0.001
  sample_time: 0.001
robot:
  - kinematics: {name: 'omni'}
    shape: {name: 'circle', radius: 0.1}
    state: [1, 1, 0]
    goal: [9, 9, 0]
    vel_max: [1, 1]
"""


def irsim_steps_per_second(steps: int = 5000, repeats: int = 3) -> float | None:
    """Best-of-repeats steps/s of IR-SIM, or None if IR-SIM is not installed (``make setup`` installs it)."""
    os.environ.setdefault("MPLBACKEND", "Agg")  # IR-SIM otherwise tries (and reports) GUI backends
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            import irsim  # it reports the GUI backends it cannot load
        import numpy as np
    except ImportError:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        world = Path(tmp) / "omni.yaml"
        world.write_text(WORLD)
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            env = irsim.make(str(world), headless=True, log_level="ERROR", seed=0)  # it reports GUI backends
        action = np.array([[0.5], [0.2]])
        for _ in range(200):
            env.step(action)
        best = 0.0
        for _ in range(repeats):
            t0 = time.perf_counter()
            for _ in range(steps):
                env.step(action)
            best = max(best, steps / (time.perf_counter() - t0))
        env.end(0)
    return best
