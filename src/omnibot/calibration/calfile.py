"""The calibration file: a description's ``calibration:`` section plus what the host needs.

::

    # omnibot calibrate: omni4 on wood, carpet (truth sim)
    calibration:          # the tables for any floor: the one floor's, or the average over the
      k: 162.1            # floors when it is better than none on each (else left out); paste it into
      k_l: {courses_deg: [0.0, 15.0, 30.0, 45.0], curves: [{x: [...], y: [...]}, ...]}
      k_t: {x: [...], y: [...]}    # the robot description, or merge it with `merge_calibration`
      k_r: {x: [...], y: [...]}
      reach: {courses_deg: [0.0, 15.0, 30.0, 45.0], speed: [0.9, 0.81, 0.68, 0.78]}  # m/s (optional)
    surfaces:             # each surface's own calibration, dead bands and wheel slip
      wood: {calibration: {...}, deadband: {course:0: 48, rotation: 40},
             odometry: {slip: {roll: 0.0021, compliance: 0.0},
                        error: {rms: 0.0012, max: 0.0021, runs: 16}}}  # the fit's residual
    gyro: {bias: -0.0032, scale: 1.008}                              # true = scale * (rate - bias)
    odometry: {wheel_radius_scale: 1.038, wheel_base_scale: 0.989}  # for wheel odometry

A ``calibration`` section goes to the controller (CAL commands): the floor's own
(:meth:`CalibrationFile.for_surface`) where the robot stands; ``gyro`` and ``odometry`` are host-side
corrections (:func:`omnibot.calibration.umbmark.corrected_robot`).
"""

from __future__ import annotations

import datetime
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml
from pydantic import ValidationError

from omnibot.calibration.results import CalibrationResult
from omnibot.config_errors import read_yaml
from omnibot.errors import ConfigError
from omnibot.estimation import SlipError, SlipParameters
from omnibot.robot import CalibrationSpec, RobotDescription, calibration_for, load_robot, parse_description

if TYPE_CHECKING:
    from omnibot.navigation import SlipCalibration

log = logging.getLogger(__name__)

TOP_KEYS = ("robot", "calibration", "surfaces", "gyro", "odometry", "info")


@dataclass(frozen=True)
class CalibrationFile:
    """A calibration file as read: the tables for any floor, each floor's own, dead bands, gyro, odometry
    and wheel slip."""

    calibration: CalibrationSpec | None
    """The tables for any floor; None in a file of several floors whose average was worse than none
    on one of them (each floor then has only its own, :attr:`surfaces`)."""
    surfaces: dict[str, CalibrationSpec] = field(default_factory=dict)
    deadbands: dict[str, dict[str, int]] = field(default_factory=dict)
    gyro: dict[str, float] | None = None
    odometry: dict[str, float] | None = None
    robot: str | None = None
    slip: dict[str, SlipParameters] = field(default_factory=dict)
    """Each surface's wheel-slip coefficients for the driven-wheel encoders (host side)."""
    slip_error: dict[str, SlipError] = field(default_factory=dict)
    """Each surface's slip runs' encoder error once its fitted creep is out (files from before
    2026-12-07 have none)."""

    def check_robot(self, robot: str, source: str = "the calibration file") -> None:
        """Refuse a calibration made for another robot (a file that names none is taken as is)."""
        if self.robot is not None and self.robot != robot:
            raise ConfigError(
                f"{source} is a calibration of '{self.robot}', not of '{robot}'", key="--calibration"
            )

    def for_surface(self, surface: str | None) -> CalibrationSpec:
        """A surface's own calibration (None: the file's ``calibration``, the tables for any floor)."""
        if surface is None:
            if self.calibration is None:
                raise ConfigError(
                    f"the calibration file has tables for each floor ({', '.join(self.surfaces)}) and none "
                    "for every floor (their average was worse than none on one): say which floor the "
                    "robot is on",
                    key="surface",
                )
            return self.calibration
        if surface not in self.surfaces:
            raise ConfigError(
                f"no calibration for surface '{surface}'; the file has: {', '.join(self.surfaces) or 'none'}",
                key="surface",
            )
        return self.surfaces[surface]

    def slip_surface(self, surface: str | None) -> str:
        """The floor whose wheel slip applies: ``surface``, or (None) the only one that has it."""
        if surface is None:
            if len(self.slip) == 1:
                return next(iter(self.slip))
            raise ConfigError(
                "the calibration file has wheel slip for "
                + (", ".join(self.slip) if self.slip else "no surface")
                + ": say which floor the robot is on"
            )
        if surface not in self.slip:
            raise ConfigError(
                f"no wheel-slip calibration for surface '{surface}'; the file has: "
                f"{', '.join(self.slip) or 'none'}"
            )
        return surface

    def slip_for(self, surface: str | None) -> SlipParameters:
        """A surface's wheel-slip coefficients; ``None`` picks the only surface that has them."""
        return self.slip[self.slip_surface(surface)]

    def slip_error_for(self, surface: str | None) -> SlipError:
        """A surface's slip-fit residual (:meth:`slip_surface` picks it); a ConfigError when the file
        has the fit without it (written before the residual was kept)."""
        name = self.slip_surface(surface)
        if name not in self.slip_error:
            raise ConfigError(
                f"surfaces.{name}.odometry has wheel slip but no 'error' (the slip runs' residual, which "
                "omnibot calibrate writes since 2026-12-07): calibrate the floor again"
            )
        return self.slip_error[name]


def describe_spec(spec: CalibrationSpec) -> dict[str, Any]:
    """A calibration section as plain data (the YAML layout of a description's ``calibration:``)."""
    out: dict[str, Any] = {"k": spec.k}
    if spec.fold_axes_deg is not None:
        out["fold_axes_deg"] = list(spec.fold_axes_deg)
    if spec.k_l is not None:
        out["k_l"] = {
            "courses_deg": list(spec.k_l.courses_deg),
            "curves": [{"x": [int(x) for x in c.x], "y": list(c.y)} for c in spec.k_l.curves],
        }
    for name in ("k_t", "k_r"):
        t = getattr(spec, name)
        if t is not None:
            out[name] = {"x": [int(x) for x in t.x], "y": list(t.y)}
    if spec.motors is not None:
        out["motors"] = {
            "offset": list(spec.motors.offset),
            "gain": [{"x": [int(x) for x in g.x], "y": list(g.y)} for g in spec.motors.gain],
        }
        if spec.motors.speed is not None:
            out["motors"]["speed"] = list(spec.motors.speed)
    if spec.rollers is not None:
        out["rollers"] = {"cos": list(spec.rollers.cos), "sin": list(spec.rollers.sin)}
        if spec.rollers.coast is not None:
            out["rollers"]["coast"] = {"x": list(spec.rollers.coast.x), "y": list(spec.rollers.coast.y)}
    if spec.reach is not None:
        out["reach"] = {"courses_deg": list(spec.reach.courses_deg), "speed": list(spec.reach.speed)}
    return out


def document(result: CalibrationResult, truth: str = "", warning: str = "") -> dict[str, Any]:
    """The YAML document of a calibration result (plain data); ``warning`` marks one that its own
    check found worse than none (``omnibot calibrate --force``)."""
    doc: dict[str, Any] = {"robot": result.robot.name}
    if (chosen := result.chosen) is not None:
        doc["calibration"] = describe_spec(chosen)
    doc["surfaces"] = {
        s.surface: {
            "calibration": describe_spec(s.spec),
            "deadband": dict(s.fit.deadbands),
            **({"odometry": _slip_odometry(s.slip)} if s.slip is not None else {}),
        }
        for s in result.sessions
    }
    if (gyro := result.gyro) is not None:
        doc["gyro"] = {
            "bias": round(gyro.bias, 6),
            **({"scale": round(gyro.scale, 5)} if gyro.scale is not None else {}),
        }
    if (odo := result.odometry) is not None:
        doc["odometry"] = _odometry(odo.as_dict())
    doc["info"] = {
        "surfaces": [s.surface for s in result.sessions],
        "truth": truth or (result.sessions[0].truth if result.sessions else ""),
        "written": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        **({"average": _average_note(result)} if result.average is not None else {}),
        **({"warning": warning} if warning else {}),
    }
    return doc


def _average_note(result: CalibrationResult) -> str:
    """What became of the average over the floors."""
    if result.average_better is False:
        return "not kept: worse than no calibration on a floor (each floor has its own tables)"
    if result.average_better is None:
        return "kept as calibration, unchecked"
    return "kept as calibration: better than none on every floor"


def _slip_odometry(slip: SlipCalibration) -> dict[str, Any]:
    """A floor's ``odometry``: the slip fit and, when it had runs, their residual error."""
    errors = slip.errors(corrected=True)
    return {"slip": slip.params.as_dict(), **({"error": SlipError.of(errors).as_dict()} if errors else {})}


def _odometry(values: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in values.items() if not k.endswith("_runs")}


def dumps(doc: dict[str, Any]) -> str:
    """YAML with the knot lists on one line each (the presets' layout)."""
    warning = doc.get("info", {}).get("warning")
    head = (
        (f"# {warning}\n" if warning else "")
        + f"# omnibot calibrate: {doc.get('robot', '?')} on {', '.join(doc.get('info', {}).get('surfaces', []))}\n"
        "# A `calibration` section goes to the controller (CAL) and into a robot description: the floor's\n"
        "# own (`surfaces.<floor>`) where the robot stands; `gyro` and `odometry` are host-side\n"
        "# corrections. See docs/calibration.md.\n"
    )
    return head + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=200)


def write_calibration(
    path: str | Path, result: CalibrationResult, truth: str = "", warning: str = ""
) -> Path:
    """Write ``result`` as a calibration file at ``path`` (directories made); the path written, ConfigError
    when it cannot be written."""
    path = Path(path)
    try:
        if path.parent != Path():
            path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(dumps(document(result, truth, warning)), encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot write {path}: {exc.strerror}", key="--calibration") from None
    return path


def _spec(data: Any, where: str) -> CalibrationSpec:
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: expected a mapping with k, k_l, k_t, k_r")
    try:
        return CalibrationSpec.model_validate(data)
    except ValidationError as exc:
        problems = []
        for item in exc.errors():
            loc = ".".join(str(p) for p in item["loc"])
            msg = (
                "unknown key"
                if item["type"] == "extra_forbidden"
                else item["msg"].removeprefix("Value error, ")
            )
            problems.append(f"{where}.{loc}: {msg}")
        raise ConfigError("invalid calibration:\n  " + "\n  ".join(problems)) from None


def parse_calibration(data: Any, source: str = "") -> CalibrationFile:
    """Validate a parsed calibration document (or a bare ``calibration`` section)."""
    if not isinstance(data, dict):
        raise ConfigError(f"a calibration file must be a mapping {source}".strip())
    if "calibration" not in data and "k" in data:
        data = {"calibration": data}
    unknown = [k for k in data if k not in TOP_KEYS]
    if unknown:
        raise ConfigError(f"{source}: unknown key(s) {unknown}; expected {', '.join(TOP_KEYS)}".lstrip(": "))
    if "calibration" not in data and not data.get("surfaces"):
        raise ConfigError(f"{source}: no 'calibration' section".lstrip(": "))
    surfaces, deadbands, slips, slip_errors = {}, {}, {}, {}
    for name, entry in (data.get("surfaces") or {}).items():
        if not isinstance(entry, dict) or "calibration" not in entry:
            raise ConfigError(f"surfaces.{name}: expected a mapping with 'calibration'")
        extra = [k for k in entry if k not in ("calibration", "deadband", "odometry")]
        if extra:
            raise ConfigError(
                f"surfaces.{name}: unknown key(s) {extra}; expected calibration, deadband, odometry"
            )
        surfaces[str(name)] = _spec(entry["calibration"], f"surfaces.{name}.calibration")
        deadbands[str(name)] = {str(k): int(v) for k, v in (entry.get("deadband") or {}).items()}
        odometry = entry.get("odometry") or {}
        if not isinstance(odometry, dict) or sorted(set(odometry) - {"slip", "error"}):
            raise ConfigError(f"surfaces.{name}.odometry: expected a mapping with 'slip' (and its 'error')")
        if "slip" in odometry:
            slips[str(name)] = SlipParameters.from_mapping(odometry["slip"], f"surfaces.{name}.odometry.slip")
        if "error" in odometry:
            slip_errors[str(name)] = SlipError.from_mapping(
                odometry["error"], f"surfaces.{name}.odometry.error"
            )
    return CalibrationFile(
        calibration=_spec(data["calibration"], "calibration") if "calibration" in data else None,
        surfaces=surfaces,
        deadbands=deadbands,
        gyro=data.get("gyro"),
        odometry=data.get("odometry"),
        robot=data.get("robot"),
        slip=slips,
        slip_error=slip_errors,
    )


def load_calibration(path: str | Path) -> CalibrationFile:
    """Read and check the calibration file at ``path``; ConfigError naming what is wrong."""
    return parse_calibration(read_yaml(path, "calibration file"), str(path))


def floor_calibration(
    path: str | Path, robot: str | RobotDescription, surface: str | None
) -> tuple[CalibrationSpec | None, SlipParameters]:
    """(the floor's calibration tables, its wheel-slip coefficients) from the file at ``path`` for the
    floor ``surface`` (None: the only floor with wheel slip in the file); the file must be
    ``robot``'s (a description: the tables on its course axes, :func:`spec_for_robot`). A ConfigError
    names ``--calibration`` or ``--surface``."""
    cal = load_calibration(path)
    cal.check_robot(robot if isinstance(robot, str) else robot.name, str(path))
    try:
        slip = cal.slip_for(surface)
        tables = cal.for_surface(surface)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}", key="--surface") from None
    if not isinstance(robot, str):
        tables = spec_for_robot(tables, robot, str(path))
    return tables, slip


def spec_for_robot(spec: CalibrationSpec, robot: RobotDescription, source: str = "") -> CalibrationSpec:
    """A calibration section with its K_l and reach courses on ``robot``'s course axes: as it is when
    made on them, moved there exactly when made on others (a mecanum file written before the fold
    marker: its courses count from the diagonals), else a ConfigError naming ``source``."""
    try:
        moved = calibration_for(spec, robot.wheels)
    except ValueError as exc:
        raise ConfigError(f"{source or 'the calibration'}: {exc}", key="--calibration") from None
    if moved.k_l != spec.k_l:
        log.info(
            "%s: K_l courses %s moved onto %s's course axes (%s)",
            source or "calibration",
            list(spec.k_l.courses_deg) if spec.k_l else [],
            robot.name,
            list(moved.k_l.courses_deg) if moved.k_l else [],
        )
    return moved


def apply_calibration(robot: RobotDescription, spec: CalibrationSpec) -> RobotDescription:
    """The description with its ``calibration`` section replaced."""
    data = robot.model_dump(exclude_none=True)
    data["calibration"] = spec.model_dump(exclude_none=True)
    return parse_description(data, f"{robot.name} (calibrated)")


def merge_calibration(robot: str | Path, calibration: str | Path, surface: str | None = None) -> str:
    """A description file (or preset) with its ``calibration:`` section replaced by the file's, as
    YAML text (comments of the description are not kept)."""
    desc = load_robot(robot)
    cal = load_calibration(calibration)
    cal.check_robot(desc.name, str(calibration))
    spec = cal.for_surface(surface)
    merged = apply_calibration(desc, spec_for_robot(spec, desc, str(calibration)))
    data = merged.model_dump(exclude_none=True, mode="json")
    data["calibration"] = describe_spec(merged.calibration or spec)
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=200)
