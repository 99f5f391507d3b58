"""The UNO firmware as an Arduino sketch folder: its files, its build with Debian's arduino-mk (flash
and static RAM within the limits of docs/uno.md, nothing of the Arduino core linked in) and the
Arduino-built image in simavr, answering as the bare build does."""

from __future__ import annotations

import re
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from omnibot.errors import ConfigError
from omnibot.firmware import avrsketch
from omnibot.protocol import codes
from omnibot.uno.emulator import FIRMWARE_DIR, UnoEmulator, missing_tools

from .conftest import BUILD_IDS, BUILDS, Port
from .test_emulator import AFTER_IDLE, SCRIPT, reference, split_powers

ROBOTS = ("omni4", "mecanum4")
FLASH_LIMIT = 32256  # 32 KB less optiboot's 512 bytes
RAM_LIMIT = 1536  # 75 % of the 2,048 bytes of SRAM for static data (docs/uno.md)
# per board: flash and SRAM in all, the limits (the bootloader's room off; 75 % of the SRAM for static
# data) and the vectors the firmware owns (its UART's two, its clock timer's capture, compare B and
# overflow) and timer 0's overflow (the core's millis(): not linked)
SIZES = {"uno": (32768, 2048, FLASH_LIMIT, RAM_LIMIT), "mega": (262144, 8192, 253952, 6144)}
VECTORS = {"uno": ((18, 19, 10, 12, 13), 16), "mega": ((25, 26, 46, 48, 50), 23)}
CORE_PATH = Path("/usr/share/arduino/hardware/arduino/avr/cores/arduino")
# what the Arduino core would bring if any of it were linked: its main() calls these
CORE_SYMBOLS = {"init", "initVariant", "setup", "loop", "millis", "micros", "delay", "serialEventRun"}
MADE = Path(__file__).resolve().parents[2] / "build" / "arduino"
"""Where ``make arduino-sketch`` writes and builds the sketch folders (the Makefile's SKETCH_DIR)."""


def arduino_mk_missing() -> str | None:
    """Why the sketch cannot be built with arduino-mk here, or None."""
    needed = {"arduino-mk": Path(avrsketch.ARDUINO_MK), "arduino-core-avr": CORE_PATH}
    absent = [pkg for pkg, path in needed.items() if not path.exists()]
    if absent:
        return f"missing Debian's {' and '.join(absent)}: `make arduino-sketch` installs them"
    return missing_tools()


def test_sketch_folder_holds_the_ino_the_header_and_every_source() -> None:
    files = avrsketch.sketch_files("omni4")
    ino = files["omnibot_omni4.ino"]
    # comments only: no setup() or loop(), the firmware's main() runs
    assert all(line.startswith("//") for line in ino.splitlines()), ino
    assert files[avrsketch.HEADER] == (FIRMWARE_DIR / "generated" / "omni4.h").read_text()
    sources = {p.name: p.read_text() for p in (FIRMWARE_DIR / "src").iterdir() if p.suffix in (".cpp", ".h")}
    assert "main.cpp" in sources and "hal.cpp" in sources
    assert set(files) == set(sources) | {"omnibot_omni4.ino", avrsketch.HEADER, "Makefile"}
    for name, text in sources.items():
        if name.endswith(".cpp"):  # the bare build's -include, and the source's own line numbers
            assert files[name] == f'#include "{avrsketch.HEADER}"\n#line 1 "{name}"\n' + text
        else:
            assert files[name] == text
    makefile = files["Makefile"]
    assert "BOARD_TAG    = uno" in makefile and "TARGET       = omnibot_omni4" in makefile
    assert "ARDUINO_LIBS =\n" in makefile and makefile.endswith(f"include {avrsketch.ARDUINO_MK}\n")


def test_unknown_robot_names_the_known_ones() -> None:
    with pytest.raises(ConfigError, match=r"no UNO firmware for robot 'omni3': .*mecanum4, omni4"):
        avrsketch.sketch_files("omni3")


def test_cli_writes_the_folder_and_replaces_only_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert avrsketch.main(["mecanum4", str(tmp_path)]) == 0
    folder = tmp_path / "omnibot_mecanum4"
    assert capsys.readouterr().out.strip() == str(folder / "omnibot_mecanum4.ino")
    (folder / "stale.cpp").write_text("x")
    assert avrsketch.main(["mecanum4", str(tmp_path)]) == 0  # written again, the stale file gone
    assert not (folder / "stale.cpp").exists() and (folder / "motion.cpp").exists()
    other = tmp_path / "elsewhere"
    (other / "omnibot_omni4").mkdir(parents=True)
    (other / "omnibot_omni4" / "omnibot_omni4.ino").write_text("void setup() {}\n")
    assert avrsketch.main(["omni4", str(other)]) == 2
    assert "not a sketch folder this command wrote" in capsys.readouterr().err
    assert (other / "omnibot_omni4" / "omnibot_omni4.ino").read_text() == "void setup() {}\n"
    assert avrsketch.main(["omni3", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: no UNO firmware for robot 'omni3'") and err.count("\n") == 1


def test_the_megas_sketch_has_its_header_board_and_name(tmp_path: Path) -> None:
    files = avrsketch.sketch_files("omni4", "mega")
    assert files[avrsketch.HEADER] == (FIRMWARE_DIR / "generated" / "mega" / "omni4.h").read_text()
    assert "BOARD_TAG    = mega\nBOARD_SUB    = atmega2560\n" in files["Makefile"]
    assert "Arduino Mega 2560 (arduino:avr:mega:cpu=atmega2560)" in files["omnibot_omni4_mega.ino"]
    assert avrsketch.main(["omni4", str(tmp_path), "--board", "mega"]) == 0
    assert (tmp_path / "omnibot_omni4_mega" / "omnibot_omni4_mega.ino").exists()
    with pytest.raises(ConfigError, match=r"no Mega 2560 firmware for robot 'omni3'"):
        avrsketch.sketch_files("omni3", "mega")


def made_by_make(robot: str, board: str) -> Path | None:
    """The image ``make arduino-sketch`` (a step of ``make test``) built into :data:`MADE` from this very
    sketch, or None: its folder holds the files :func:`avrsketch.sketch_files` gives now and nothing
    else, and its ELF and HEX are newer than each of them (make's own test, so an image left by a
    failed build of other sources is never taken). Such an image is what the fixture would build again."""
    files = avrsketch.sketch_files(robot, board)
    name = avrsketch.sketch_name(robot, board)
    folder, objdir = MADE / name, avrsketch.build_dir(board)
    images = [folder / objdir / f"{name}{suffix}" for suffix in (".elf", ".hex")]
    if not all(image.is_file() for image in images) or not folder.is_dir():
        return None
    if {p.name for p in folder.iterdir() if p.name != objdir} != set(files):
        return None
    built = min(image.stat().st_mtime for image in images)
    for file_name, text in files.items():
        path = folder / file_name
        if path.stat().st_mtime >= built or path.read_text(encoding="utf-8") != text:
            return None
    return images[0]


@pytest.fixture(scope="module", params=BUILDS, ids=BUILD_IDS)
def arduino_build(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[tuple[str, str, Path]]:
    """(robot, board, the ELF arduino-mk built from the robot's sketch folder for the board): the one
    ``make test`` built before pytest started where it is that build (:func:`made_by_make`), else built
    here (four builds, about 10 s of CPU)."""
    reason = arduino_mk_missing()
    if reason:
        pytest.skip(f"Arduino sketch build: {reason}")
    robot, board = request.param
    made = made_by_make(robot, board)
    if made is not None:
        yield robot, board, made
        return
    folder = avrsketch.write_sketch(robot, tmp_path_factory.mktemp("sketch"), board)
    proc = subprocess.run(
        ["nice", "make", "-s", "-C", str(folder)], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]
    out = folder / avrsketch.build_dir(board)
    name = avrsketch.sketch_name(robot, board)
    elf = out / f"{name}.elf"
    assert elf.exists() and (out / f"{name}.hex").exists()
    yield robot, board, elf
    shutil.rmtree(folder, ignore_errors=True)


def test_arduino_build_fits_flash_and_static_ram(arduino_build: tuple[str, str, Path]) -> None:
    robot, board, elf = arduino_build
    flash_size, ram_size, flash_limit, ram_limit = SIZES[board]
    proc = subprocess.run(
        [
            "make",
            "-s",
            "--no-print-directory",
            "-C",
            str(FIRMWARE_DIR),
            "size-of",
            f"ROBOT={robot}",
            f"BOARD={board}",
            f"ELF={elf}",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    report = proc.stdout.strip()
    assert proc.returncode == 0, report + proc.stderr
    m = re.search(rf"flash (\d+) of {flash_size} .* static RAM (\d+) of {ram_size}", report)
    assert m, report
    flash, static = int(m.group(1)), int(m.group(2))
    assert flash <= flash_limit and static <= ram_limit, report


def test_arduino_build_links_nothing_of_the_arduino_core(arduino_build: tuple[str, str, Path]) -> None:
    _, board, elf = arduino_build
    nm = subprocess.run(["avr-nm", str(elf)], capture_output=True, text=True, check=True).stdout
    symbols = {line.split()[-1]: line.split()[-2] for line in nm.splitlines() if len(line.split()) >= 2}
    assert not CORE_SYMBOLS & set(symbols), CORE_SYMBOLS & set(symbols)
    assert not [s for s in symbols if "HardwareSerial" in s or s == "Serial"]
    assert symbols["main"] == "T"
    ours, timer0_ovf = VECTORS[board]
    assert symbols[f"__vector_{timer0_ovf}"] == "W"  # TIMER0_OVF: the core's millis() tick is not there
    for vector in ours:  # the UART's and the clock timer's: the firmware's
        assert symbols[f"__vector_{vector}"] == "T", vector


def test_arduino_build_answers_as_the_bare_build(arduino_build: tuple[str, str, Path]) -> None:
    """The image arduino-mk built, in simavr: the HELLO at reset and the whole script of
    test_emulator.py (every command, error and odd input) answered as by the MicroPython firmware."""
    robot, board, elf = arduino_build
    _, ram_size, _, ram_limit = SIZES[board]
    emu = UnoEmulator(robot, range_cm=100, elf=elf, board=board)
    port = Port(emu.path)
    try:
        assert port.lines(1) == [f"HELLO,{codes.PROTOCOL_VERSION},{robot},4"]
        assert port.ask("HELLO") == [f"HELLO,{codes.PROTOCOL_VERSION},{robot},4"]
        for text, replies in zip(SCRIPT, reference(robot), strict=True):
            got = port.ask(text, len(replies), skip=AFTER_IDLE)
            for g, e in zip(got, replies, strict=True):
                g_text, g_powers = split_powers(g)
                e_text, e_powers = split_powers(e)
                assert g_text == e_text, (text, g, e)
                assert all(abs(a - b) <= 1 for a, b in zip(g_powers, e_powers, strict=True)), (g, e)
    finally:
        port.close()
        emu.close()
    # the lowest byte the stack wrote (the harness's --heap: an LTO image's main() keeps painted locals)
    assert emu.stack_bytes is not None and 64 < emu.stack_bytes < ram_size - ram_limit, emu.stack_bytes


def test_without_arduino_mk_the_reason_names_the_packages_and_the_make_target(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(avrsketch, "ARDUINO_MK", str(tmp_path / "Arduino.mk"))
    reason = arduino_mk_missing()
    assert reason is not None and "arduino-mk" in reason and "make arduino-sketch" in reason


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_ides_builder_builds_the_sketch_within_the_limits(robot: str, tmp_path: Path) -> None:
    """arduino-builder, the Arduino IDE 1.8's builder (Debian's `arduino` package, which arduino-mk
    depends on): the .ino through its preprocessor, the sketch's .cpp files, the core archive."""
    reason = arduino_mk_missing()
    if reason or shutil.which("arduino-builder") is None:
        pytest.skip(f"Arduino IDE builder: {reason or 'no arduino-builder (Debian: arduino)'}")
    folder = avrsketch.write_sketch(robot, tmp_path)
    build = tmp_path / "build"
    build.mkdir()
    hardware = "/usr/share/arduino/hardware"
    argv = ["nice", "arduino-builder", "-compile", "-hardware", hardware, "-tools", f"{hardware}/tools"]
    # Debian's core and avr-gcc 5.4 need DECIMAL_DIG (the sketch's Makefile says why)
    argv += ["-fqbn", "arduino:avr:uno", "-build-path", str(build)]
    argv += [
        "-prefs=compiler.cpp.extra_flags=-DDECIMAL_DIG=__DECIMAL_DIG__",
        str(folder / f"omnibot_{robot}.ino"),
    ]
    proc = subprocess.run(argv, capture_output=True, text=True, check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-3000:]
    flash = re.search(r"Sketch uses (\d+) bytes .* Maximum is (\d+) bytes", out)
    ram = re.search(r"Global variables use (\d+) bytes .* Maximum is 2048 bytes", out)
    assert flash and ram, out[-2000:]
    assert int(flash.group(2)) == FLASH_LIMIT  # the UNO's upload.maximum_size: optiboot's 512 B off
    assert int(flash.group(1)) <= FLASH_LIMIT and int(ram.group(1)) <= RAM_LIMIT, (
        flash.group(0),
        ram.group(0),
    )
    elf = build / f"omnibot_{robot}.ino.elf"
    emu = UnoEmulator(robot, elf=elf)
    port = Port(emu.path)
    try:
        assert port.lines(1) == [f"HELLO,{codes.PROTOCOL_VERSION},{robot},4"]
        assert port.ask("MOVE,30000,40,0,0;STOP", 2, skip=("IDLE",)) == ["OK", "OK"]
    finally:
        port.close()
        emu.close()
