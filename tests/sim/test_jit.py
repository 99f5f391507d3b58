"""Which kernels the simulator runs: the compiled ones from numba's cache, or on a cold start their
twins while a process of its own compiles them, then the compiled ones, with the same numbers."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from numba.extending import is_jitted

from omnibot.robot import load_robot
from omnibot.sim import jit, kernels
from omnibot.sim.simulator import Simulator


def test_with_the_kernels_cached_the_simulator_calls_the_compiled_ones() -> None:
    jit.active.choose()
    assert jit.active.wait()
    assert jit.active.kind == jit.COMPILED
    assert all(getattr(jit.active, name) is getattr(kernels, name) for name in jit.CALLED)


def test_a_kernel_that_does_not_exist_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no kernel 'robot_stpe'"):
        jit.active.robot_stpe  # noqa: B018


def _cold(monkeypatch: pytest.MonkeyPatch, compiling: tuple[int, str] | OSError) -> jit.ActiveKernels:
    """A fresh choice that finds the cache empty, with what its compiling process does stubbed."""

    def compile_in_own_process() -> tuple[int, str]:
        if isinstance(compiling, OSError):
            raise compiling
        return compiling

    monkeypatch.setattr(jit, "load_cached", lambda: False)
    monkeypatch.setattr(jit, "_compile_in_own_process", compile_in_own_process)
    return jit.ActiveKernels()


@pytest.mark.parametrize(
    ("compiling", "said"),
    [
        ((1, "MemoryError"), "(exit status 1: MemoryError)"),
        (OSError("no python"), "(not started: no python)"),
    ],
)
def test_when_the_compiling_process_fails_the_kernels_compile_in_the_process(
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
    compiling: tuple[int, str] | OSError,
    said: str,
) -> None:
    active = _cold(monkeypatch, compiling)
    assert active.choose() == jit.PYTHON  # (the switch may follow at once: the test's cache is warm)
    assert active.wait(600)
    assert active.kind == jit.COMPILED and active.robot_step is kernels.robot_step
    assert said in caplog.text and "compiling them here" in caplog.text


def test_kernels_that_do_not_compile_leave_the_twins_running_and_wait_says_why(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    active = _cold(monkeypatch, (0, ""))
    broken = RuntimeError("LLVM ERROR")

    def fail() -> None:
        raise broken

    monkeypatch.setattr(jit, "_load_simulator_kernels", fail)
    active.choose()
    with pytest.raises(RuntimeError, match="LLVM ERROR"):
        active.wait(600)
    assert active.kind == jit.PYTHON and not is_jitted(active.robot_step)


_COLD_START = """
import json, time
from omnibot.robot import load_robot
from omnibot.sim import jit
from omnibot.sim.simulator import Simulator

t0 = time.process_time()
kind = jit.active.choose()
choice_cpu = time.process_time() - t0
sim = Simulator(load_robot("omni4"), world="room", seed=5, start_pose=(1.5, 3.4, 0.3))
sim.set_pwm([150, -40, -150, 40])
on_twins = 0
while on_twins < {twin_steps} and not jit.active.wait(0):
    sim.step()
    on_twins += 1
compiled = jit.active.wait()
for _ in range({compiled_steps}):
    sim.step()
print(json.dumps({{"kind": kind, "choice_cpu": choice_cpu, "on_twins": on_twins, "compiled": compiled,
                  "state": [*sim.pose_array.tolist(), *sim._twist_row.tolist(), *sim.wheel_speeds],
                  "collisions": len(sim.collisions)}}))
"""


# one whole compile of the kernels: about 20 s of CPU, several times that in wall time when loaded
@pytest.mark.timeout(900)
def test_a_cold_start_runs_the_twins_then_what_its_own_process_compiled(tmp_path: Path) -> None:
    """With an empty cache the simulator starts at once on the twins (nothing compiled in the
    process), a process of its own fills the cache with every kernel, and the simulator switches to
    the compiled kernels: the run ends where a run on compiled kernels alone does, bit for bit."""
    cache = tmp_path / "numba"
    twin_steps, compiled_steps = 1500, 500
    script = _COLD_START.format(twin_steps=twin_steps, compiled_steps=compiled_steps)
    out = subprocess.run(
        [sys.executable, "-c", script],
        env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
        capture_output=True,
        text=True,
        timeout=850,
        check=False,
    )
    assert out.returncode == 0 and out.stderr == "", out.stderr
    cold = json.loads(out.stdout)
    assert cold["kind"] == jit.PYTHON and cold["compiled"]
    assert cold["choice_cpu"] < 3.0  # looking in the cache; compiling robot_step alone takes 9 s
    assert cold["on_twins"] > 0 and cold["collisions"] > 0  # into the cabinet, on the twins
    cached = {p.name.split("-")[0] for p in cache.rglob("*.nbi")}
    own_file = {name: getattr(kernels, name).py_func.__module__.rsplit(".", 1)[-1] for name in jit.CALLED}
    assert {f"{own_file[name]}.{name}" for name in jit.CALLED} <= cached  # numba names them file.kernel

    sim = Simulator(load_robot("omni4"), world="room", seed=5, start_pose=(1.5, 3.4, 0.3))
    sim.set_pwm([150, -40, -150, 40])
    for _ in range(cold["on_twins"] + compiled_steps):
        sim.step()
    assert jit.active.kind == jit.COMPILED
    state = [*sim.pose_array.tolist(), *sim._twist_row.tolist(), *sim.wheel_speeds]
    assert state == cold["state"] and len(sim.collisions) == cold["collisions"]
