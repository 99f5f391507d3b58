"""Robot descriptions: presets load, bad files give errors that name the key and suggest the fix."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from omnibot.errors import ConfigError
from omnibot.robot.description import (
    PRESET_DIR,
    load_description,
    load_robot,
    parse_description,
    preset_names,
)


def preset_data(name: str) -> dict[str, Any]:
    data = yaml.safe_load((PRESET_DIR / f"{name}.yaml").read_text())
    assert isinstance(data, dict)
    return data


def test_presets_are_the_three_seed_robots() -> None:
    assert preset_names() == ["mecanum4", "omni3", "omni4"]


def test_omni4_keeps_seed000_numbers() -> None:
    r = load_robot("omni4")
    assert r.n_wheels == 4 and r.mass <= 2.0
    assert [w.name for w in r.wheels] == ["m1", "m2", "m3", "m4"]
    for w in r.wheels:
        assert math.hypot(*w.position) == pytest.approx(0.096)
        assert w.radius == pytest.approx(0.025)
        assert w.motor.pwm_max == 255
    assert r.battery.voltage == pytest.approx(7.4)
    assert (r.limits.speed_min, r.limits.speed_max) == (0.30, 1.00)
    assert len(r.sonars) == 1


def test_omni3_keeps_seed002_numbers() -> None:
    r = load_robot("omni3")
    assert r.n_wheels == 3 and r.mass == pytest.approx(30)
    assert all(w.radius == pytest.approx(0.0762) for w in r.wheels)  # 6 inch diameter
    assert r.battery.voltage == pytest.approx(22.5)
    assert r.limits.speed_max == pytest.approx(5.0)
    assert {t.name for t in r.encoders.tracking} == {"vertical", "horizontal"}
    assert r.gyro is not None and r.gyro.model == "MPU6050"


def test_mecanum4_is_seed003_alpha_beta_gamma_mirrored_into_omnibot_s_frame() -> None:
    r = load_robot("mecanum4")
    seed = {"alpha": [35.77, 144.23, 215.77, 324.23], "beta": [144.23, 35.77, -35.77, -144.23]}
    for w, a, b in zip(r.wheels, seed["alpha"], seed["beta"], strict=True):
        assert w.alpha_deg is not None and w.beta_deg is not None
        assert math.remainder(w.alpha_deg - (90 - a), 360) == pytest.approx(0, abs=1e-9)
        assert math.remainder(w.beta_deg - (180 - b), 360) == pytest.approx(0, abs=1e-9)
    assert [w.gamma_deg for w in r.wheels] == [-45, 45, -45, 45]
    assert all(pytest.approx(0.0937) == w.L and w.radius == pytest.approx(0.0325) for w in r.wheels)


def test_polar_form_converts_to_cartesian() -> None:
    w = load_robot("mecanum4").wheels[0]
    assert w.position[0] == pytest.approx(0.0937 * math.cos(math.radians(54.23)))
    assert w.position[1] == pytest.approx(0.0937 * math.sin(math.radians(54.23)))
    assert math.degrees(w.drive_angle) == pytest.approx(54.23 + 35.77 - 90)


def test_wheel_motor_overrides_merge_with_the_default() -> None:
    data = preset_data("omni4")
    default = data["motor"]["resistance"]
    data["wheels"][1]["motor"] = {"resistance": default * 1.1}
    r = parse_description(data)
    assert r.wheels[1].motor.resistance == default * 1.1
    assert r.wheels[1].motor.gear_ratio == r.wheels[0].motor.gear_ratio
    assert r.wheels[0].motor.resistance == default


def error_for(data: dict[str, Any]) -> str:
    with pytest.raises(ConfigError) as info:
        parse_description(data, "test.yaml")
    return str(info.value)


def test_misspelt_key_is_named_with_a_suggestion() -> None:
    data = preset_data("omni4")
    data["wheels"][1]["radus"] = data["wheels"][1].pop("radius")
    msg = error_for(data)
    assert "wheels[1].radus: unknown key; did you mean 'radius'?" in msg
    assert "wheels[1].radius: required key is missing" in msg


def test_misspelt_top_level_and_nested_keys() -> None:
    data = preset_data("omni3")
    data["mas"] = data.pop("mass")
    data["limits"]["speed_mx"] = data["limits"].pop("speed_max")
    msg = error_for(data)
    assert "mas: unknown key; did you mean 'mass'?" in msg
    assert "limits.speed_mx: unknown key; did you mean 'speed_max'?" in msg


def test_bad_values_are_named() -> None:
    data = preset_data("omni4")
    data["mass"] = -1
    data["wheels"][0]["radius"] = "big"
    msg = error_for(data)
    assert "mass: Input should be greater than 0 (got -1)" in msg
    assert "wheels[0].radius:" in msg and "'big'" in msg


def test_roller_drag_section_is_checked() -> None:
    data = preset_data("omni4")
    data["calibration"]["rollers"] = {"cos": [-5.0, -4.0, -5.0, -4.0], "sin": [0.0, 0.0, 0.0, 0.0]}
    robot = parse_description(data, "test")
    assert robot.calibration is not None and robot.calibration.rollers is not None
    assert robot.calibration.rollers.cos[1] == -4.0 and robot.calibration.rollers.coast is None
    data["calibration"]["rollers"] = {"cos": [-5.0, -4.0], "sin": [0.0]}
    assert "cos and sin need one entry per wheel" in error_for(data)
    data["calibration"]["rollers"] = {
        "cos": [1.0],
        "sin": [0.0],
        "coast": {"x": [-0.1, 0.5], "y": [0.0, -0.2]},
    }
    assert "coast: speeds must be >= 0" in error_for(data)


def test_mixed_wheel_forms_and_degenerate_rollers_are_rejected() -> None:
    data = preset_data("omni4")
    data["wheels"][0]["alpha_deg"] = 10
    assert "either x/y/drive_angle_deg or alpha_deg/beta_deg/L" in error_for(data)
    data = preset_data("omni4")
    data["wheels"][2]["gamma_deg"] = 90
    assert "wheels[2]: gamma_deg of +-90" in error_for(data)


def test_encoder_on_unknown_wheel_suggests_a_name() -> None:
    data = preset_data("omni4")
    data["encoders"]["motors"][0]["wheel"] = "m5"
    assert "did you mean 'm1'?" in error_for(data) or "did you mean" in error_for(data)


def test_not_a_mapping(tmp_path: Path) -> None:
    f = tmp_path / "r.yaml"
    f.write_text("- just\n- a list\n")
    with pytest.raises(ConfigError, match="must be a mapping"):
        load_description(f)
    f.write_text("name: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_description(f)
    with pytest.raises(ConfigError, match="cannot read"):
        load_description(tmp_path / "missing.yaml")


def test_a_key_given_twice_is_refused_naming_its_place_and_lines(tmp_path: Path) -> None:
    """A preset edited by hand: a wheel's radius given again, the mass given again at the end."""
    text = (PRESET_DIR / "omni4.yaml").read_text()
    lines = text.splitlines()
    wheel = next(i for i, line in enumerate(lines) if line.startswith("  - {name: m2,"))
    lines.insert(wheel + 2, "     radius: 0.03}")
    lines[wheel + 1] = lines[wheel + 1].removesuffix("}") + ","
    f = tmp_path / "mine.yaml"
    f.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as info:
        load_robot(str(f))
    assert str(info.value) == (
        f"invalid robot description {f}: wheels[1].radius: duplicate key on line {wheel + 3} "
        f"(first on line {wheel + 1})"
    )
    mass = lines.index("mass: 1.6") + 1
    f.write_text(text + "mass: 16\n")
    with pytest.raises(ConfigError) as info:
        load_robot(str(f))
    last = len(text.splitlines()) + 1
    assert str(info.value).endswith(f": mass: duplicate key on line {last} (first on line {mass})")


def test_unknown_preset_suggests() -> None:
    with pytest.raises(ConfigError, match="did you mean 'mecanum4'"):
        load_robot("mecanum")


def test_description_file_round_trip(tmp_path: Path) -> None:
    f = tmp_path / "mine.yaml"
    f.write_text(yaml.safe_dump(preset_data("omni3")))
    assert load_robot(str(f)) == load_robot("omni3")


@pytest.mark.parametrize(
    ("where", "text"),
    [
        ("limits.speed_max", "limits:\n  speed_max: .inf"),
        ("wheels[0].x", None),
        ("motor.current_limit", "motor:\n  current_limit: .inf"),
        ("battery.voltage", "battery:\n  voltage: .nan"),
        ("calibration.k_t.y", None),
    ],
)
def test_numbers_that_are_not_finite_are_refused_naming_the_key(where: str, text: str | None) -> None:
    data = preset_data("omni4")
    if where == "wheels[0].x":
        data["wheels"][0]["x"] = -math.inf
        key = "wheels[0].x"
    elif where == "calibration.k_t.y":
        data["calibration"] = {"k": 100.0, "k_t": {"x": [0.0, 1.0], "y": [1.0, math.nan]}}
        key = "calibration.k_t.y[1]"
    else:
        assert text is not None
        section, rest = text.split(":\n  ")
        name, value = rest.split(": ")
        data[section] = {**data[section], name: yaml.safe_load(value)}
        key = f"{section}.{name}" if section != "motor" else f"wheels[0].motor.{name}"
    with pytest.raises(ConfigError, match="Input should be a finite number") as info:
        parse_description(data, "x.yaml")
    assert key in str(info.value)


def test_no_current_limit_means_none_and_round_trips() -> None:
    data = preset_data("omni4")
    del data["motor"]["current_limit"]
    robot = parse_description(data)
    assert robot.wheels[0].motor.current_limit is None
    assert parse_description(robot.model_dump(exclude_none=True)) == robot  # as calibration re-validates


# --------------------------------------------------------------------------- the laser scanner


def test_every_preset_carries_an_rplidar_above_its_body() -> None:
    for name in ("omni4", "omni3", "mecanum4"):
        robot = load_robot(name)
        sc = robot.scanner
        assert sc is not None and sc.model == "rplidar-a1" and sc.frame == "laser"
        assert sc.z > robot.body_top and (sc.x, sc.y) == (0.0, 0.0)
        assert (sc.range_min, sc.range_max, sc.rays, sc.rate_hz) == (0.15, 12.0, 360, 10.0)
        assert sc.spin == "clockwise" and sc.angle_increment == pytest.approx(-math.pi / 180)
        assert sc.motion_distortion and sc.resolution == 0.00025


def test_a_scanner_section_is_optional_and_its_defaults_are_the_datasheets() -> None:
    data = preset_data("omni4")
    del data["scanner"]
    assert parse_description(data).scanner is None
    data["scanner"] = {"z": 0.3}
    sc = parse_description(data).scanner
    assert sc is not None and (sc.rate_hz, sc.sample_rate_hz, sc.noise_fraction) == (5.5, 8000.0, 0.01)


def test_scanner_errors_name_the_key_and_say_what_to_do() -> None:
    data = preset_data("omni4")
    data["scanner"]["rang_max"] = data["scanner"].pop("z")
    msg = error_for(data)
    assert "scanner.rang_max: unknown key; did you mean 'range_max'?" in msg
    assert "scanner.z: required key is missing" in msg
    data = preset_data("omni4")
    data["scanner"]["z"] = 0.1
    assert "scanner.z: the scan plane at 0.1 m would cut the robot's own body" in error_for(data)
    data = preset_data("omni4")
    data["scanner"].update(rays=1000, rate_hz=10)
    assert "1000 rays at 10 Hz need 10000 samples/s; the rplidar-a1 measures at most 8000" in error_for(data)
    data = preset_data("omni4")
    data["scanner"].update(range_min=3.0, range_max=2.0)
    assert "range_min (3.0 m) must be below range_max (2.0 m)" in error_for(data)
    data = preset_data("omni4")
    data["scanner"]["spin"] = "cw"
    assert "scanner.spin:" in error_for(data)
    data = preset_data("omni4")
    data["scanner"]["frame"] = "imu_link"
    assert "scanner.frame 'imu_link' is already a link of the robot" in error_for(data)


def test_robot_show_lists_the_scanner() -> None:
    from omnibot.robot.summary import describe

    text = describe(load_robot("omni3"))
    assert "scanner   rplidar-a1 'laser' at (0, 0, 0.37 m) facing 0 deg, 360 rays at 10 Hz clockwise" in text


def test_robot_show_gives_each_drive_angle_within_a_half_turn() -> None:
    """Seed 003's angles put mecanum4's right front drive at alpha + beta - 90 = 360 degrees: shown as
    0 beside its three 0-degree siblings (and omni4's wheel at the back as 180, not -180)."""
    from omnibot.robot.summary import describe

    rows = {line.split()[0]: line.split()[3] for line in describe(load_robot("mecanum4")).splitlines()[6:10]}
    assert rows == {"left_front": "0.00", "right_front": "0.00", "right_back": "0.00", "left_back": "0.00"}
    assert "m4            0.0000   0.0960       180.00" in describe(load_robot("omni4"))
