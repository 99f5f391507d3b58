"""The floor's creep coefficients and the wheel geometry the creep model reads them through, in plain
Python: the core install's firmware config takes its ``slip`` and ``creep_*`` keys from here without
numpy; :class:`~omnibot.estimation.slip.SlipModel` (numpy) takes the same rows as arrays.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

from omnibot.errors import ConfigError
from omnibot.robot import rows

if TYPE_CHECKING:
    from omnibot.robot import RobotDescription

KEYS = ("roll", "combined", "compliance", "scale", "ramp")
"""A calibration file's ``odometry.slip`` keys (files from before the combined drag lack
``combined``, files from before 2026-12-07 ``ramp``: each is then 0, the model those files were
fitted with)."""


@dataclass(frozen=True)
class SlipParameters:
    """A floor's creep coefficients, ``roll`` (m/s per roller drag), ``compliance`` (s),
    ``combined`` (m/s per m/s of combined-drag roller speed) and ``ramp`` (s^3/m: the drag's extra
    creep per (m/s^2)^2 of acceleration), and the encoders' distance ``scale`` (true distance per
    encoder distance once the creep is out: a tyre whose rolling radius differs from the
    description's)."""

    roll: float = 0.0
    compliance: float = 0.0
    scale: float = 1.0
    combined: float = 0.0
    ramp: float = 0.0

    def __post_init__(self) -> None:
        for name in KEYS:
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ConfigError(f"slip {name} must be a finite number, got {value}", key=name)
        if not 0.5 < self.scale < 2.0:
            raise ConfigError(f"slip scale must be between 0.5 and 2, got {self.scale}", key="scale")

    @classmethod
    def from_mapping(cls, data: object, where: str = "slip") -> SlipParameters:
        """From ``{roll: ..., combined: ..., compliance: ..., scale: ...}`` (a calibration file's
        ``odometry.slip``; a missing key keeps its default, so files with the older three keys load)."""
        if not isinstance(data, dict):
            raise ConfigError(f"{where}: expected a mapping with {', '.join(KEYS)}")
        unknown = sorted(set(data) - set(KEYS))
        if unknown:
            raise ConfigError(f"{where}: unknown key(s) {unknown}; expected {', '.join(KEYS)}")
        values = {}
        for key in KEYS:
            raw = data.get(key, getattr(cls, key))
            try:
                values[key] = float(raw)
            except (TypeError, ValueError):
                raise ConfigError(f"{where}.{key}: {raw!r} is not a number") from None
        try:
            return cls(**values)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None

    def as_dict(self) -> dict[str, float]:
        """The coefficients as a mapping, rounded for a calibration file (``odometry.slip``)."""
        return {
            "roll": round(self.roll, 6),
            "combined": round(self.combined, 6),
            "compliance": round(self.compliance, 6),
            "scale": round(self.scale, 5),
            "ramp": round(self.ramp, 7),
        }


@dataclass(frozen=True)
class SlipError:
    """How well a floor's slip fit corrects the driven-wheel encoders: over its straight runs, each
    run's |encoder - true displacement| / true distance with the fitted creep taken out (a fraction
    of the distance; in-sample, so a lower bound on a route's), as root mean square and maximum.
    A calibration file's ``surfaces.<floor>.odometry.error``."""

    rms: float
    max: float
    runs: int

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rms) and 0.0 < self.rms < 1.0):
            raise ConfigError(f"rms must be a fraction in (0, 1), got {self.rms}", key="rms")
        if not (math.isfinite(self.max) and self.rms <= self.max < 1.0):
            raise ConfigError(f"max must be a fraction in [rms, 1), got {self.max}", key="max")
        if self.runs < 1:
            raise ConfigError(f"runs must be at least 1, got {self.runs}", key="runs")

    @classmethod
    def of(cls, errors: Sequence[float]) -> SlipError:
        """From the runs' relative errors (``SlipCalibration.errors(corrected=True)``), rounded for a
        calibration file."""
        rms = math.sqrt(math.fsum(e * e for e in errors) / len(errors))
        return cls(round(rms, 6), round(max(errors), 6), len(errors))

    @classmethod
    def from_mapping(cls, data: object, where: str = "error") -> SlipError:
        """From ``{rms: ..., max: ..., runs: ...}``, every key required; a ConfigError naming
        ``where`` and the key otherwise."""
        keys = ("rms", "max", "runs")
        if not isinstance(data, dict) or sorted(data) != sorted(keys):
            raise ConfigError(f"{where}: expected a mapping with exactly {', '.join(keys)}, got {data!r}")
        rms, top, runs = data["rms"], data["max"], data["runs"]
        if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in (rms, top)) or not (
            isinstance(runs, int) and not isinstance(runs, bool)
        ):
            raise ConfigError(f"{where}: rms and max must be numbers and runs a count, got {data!r}")
        try:
            return cls(float(rms), float(top), runs)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None

    def as_dict(self) -> dict[str, float | int]:
        """The mapping a calibration file holds."""
        return {"rms": self.rms, "max": self.max, "runs": self.runs}


class CreepRows(NamedTuple):
    """A robot's creep geometry (:class:`~omnibot.estimation.slip.SlipModel`'s), one row per wheel."""

    rim_per_rad: tuple[float, ...]
    """m of rim travel along the traction direction per rad of wheel turn, r cos(gamma)."""
    roll: tuple[rows.Row, ...]
    """The roller's rolling speed over the body twist: with the body and, on mecanum wheels, with
    the wheel's own turn (the firmware's ``creep_roll``)."""
    rim: tuple[rows.Row, ...]
    """The rim speed r omega over the body twist, rolling without slip (``creep_rim``)."""
    share: rows.Matrix
    """(m, 3): the least-norm traction forces of the wheels that give the body a unit wrench, the
    pseudo-inverse of the traction rows' transpose."""
    mix: rows.Matrix
    """(m, m): wheel k's over-turn (rad/s) per m/s of roller row j's creep term (``creep_mix``)."""


def creep_rows(robot: RobotDescription) -> CreepRows:
    """The creep geometry of a robot's wheels (its traction and roller rows, :mod:`omnibot.robot.rows`)."""
    traction, roller = rows.robot_contact_rows(robot)
    wheels = robot.wheels
    rim_per_rad = tuple(w.radius * math.cos(w.gamma) for w in wheels)
    along = [w.radius * math.sin(w.gamma) / k for w, k in zip(wheels, rim_per_rad, strict=True)]
    roll = tuple(
        _row(n + a * t for n, t in zip(rn, rt, strict=True))
        for rn, rt, a in zip(roller, traction, along, strict=True)
    )
    rim = tuple(_row(t / math.cos(w.gamma) for t in rt) for rt, w in zip(traction, wheels, strict=True))
    share = rows.transpose(rows.pseudo_inverse(traction))
    mix = tuple(
        tuple(sum(a * b for a, b in zip(force, rn, strict=True)) / k for rn in roller)
        for force, k in zip(share, rim_per_rad, strict=True)
    )
    return CreepRows(rim_per_rad, roll, rim, share, mix)


def _row(values: Iterable[float]) -> rows.Row:
    a, b, c = values
    return (a, b, c)
