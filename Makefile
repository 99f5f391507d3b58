# omnibot: `make demo` sets up and runs the main job; `make test` sets up and runs the tests.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: setup demo test lint bench clean browser avr-tools uno-sim arduino-sketch mcap-readers fuzz ros2-interop ros2-kilted

KERNEL_CACHE := $(VENV)/.kernels

setup: $(STAMP) $(KERNEL_CACHE)

# Every extra (all), the tests' tools (dev) and the benchmarks' (bench), at the exact versions of
# constraints.txt; pyproject.toml states the ranges a user's `pip install omnibot[...]` accepts.
$(STAMP): pyproject.toml constraints.txt Makefile
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "omnibot needs Python 3.11 or newer")'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip==25.3
	$(BIN)/python -m pip install --quiet -c constraints.txt -e '.[all,dev,bench]'
	@touch $(STAMP)

# The simulator's kernels compiled into numba's cache (next to their files), again whenever a file of
# src/omnibot/sim/kernels changes (each kernel's cache entry is keyed on all of them, sim/kernels/cache.py:
# a pull that changes one would otherwise leave the next simulator running the kernels as Python, 10-50
# times slower, for the 20 s of CPU they take to compile in the background, omnibot.sim.jit; an
# unchanged cache only loads, in a second).
# The batch API's lanes kernel (Physics.run(exact=False)) too: its tests would compile it otherwise.
$(KERNEL_CACHE): $(STAMP) $(wildcard src/omnibot/sim/kernels/*.py)
	$(BIN)/python -m omnibot.sim.jit
	$(BIN)/python -m omnibot.sim.kernels.lanes
	@touch $@

demo: setup
	$(BIN)/omnibot demo

lint: setup
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks
	$(BIN)/mypy

# Debian's chromium for the dashboard's browser tests (playwright drives /usr/bin/chromium; it never
# downloads a browser). Installed only when missing, with apt-get (as root on CI, else through sudo).
browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  echo "make browser: installing Debian's chromium for the browser tests"; \
	  SUDO=$$([ "$$(id -u)" -eq 0 ] || echo sudo); \
	  $$SUDO apt-get update -qq && \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium; }

# Debian's AVR toolchain and simavr for the Arduino UNO firmware (firmware-avr/) and its emulator
# harness (firmware-avr/unosim/). Installed only when missing, like chromium above.
AVR_PKGS := gcc-avr avr-libc binutils-avr simavr libsimavr-dev libelf-dev pkg-config
avr-tools:
	@command -v avr-gcc >/dev/null 2>&1 && [ -f /usr/include/simavr/sim_avr.h ] || { \
	  echo "make avr-tools: installing Debian's AVR toolchain and simavr"; \
	  SUDO=$$([ "$$(id -u)" -eq 0 ] || echo sudo); \
	  $$SUDO apt-get update -qq && \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $(AVR_PKGS); }

# The emulated UNO: the firmware of both robots (UNO and Mega 2560) and the simavr harness that runs it.
uno-sim: avr-tools
	$(MAKE) -C firmware-avr ROBOT=omni4
	$(MAKE) -C firmware-avr ROBOT=mecanum4
	$(MAKE) -C firmware-avr ROBOT=omni4 BOARD=mega
	$(MAKE) -C firmware-avr ROBOT=mecanum4 BOARD=mega
	$(MAKE) -C firmware-avr/unosim

# The UNO firmware as Arduino sketch folders for the UNO and the Mega 2560 (python -m omnibot.firmware.avrsketch), built with Debian's
# arduino-mk and Arduino core (installed only when missing, like avr-tools) into build/arduino/, with
# the bare build's flash and static RAM limits (firmware-avr's size-of). tests/uno/test_sketch.py does
# the same and runs the images in simavr.
ARDUINO_PKGS := arduino-mk arduino-core-avr
SKETCH_DIR := build/arduino
arduino-sketch: avr-tools
	@[ -f /usr/share/arduino/Arduino.mk ] && [ -d /usr/share/arduino/hardware/arduino/avr/cores/arduino ] || { \
	  echo "make arduino-sketch: installing Debian's arduino-mk and Arduino core"; \
	  SUDO=$$([ "$$(id -u)" -eq 0 ] || echo sudo); \
	  $$SUDO apt-get update -qq && \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $(ARDUINO_PKGS); }
	@for robot in omni4 mecanum4; do \
	  PYTHONPATH=src $(BIN)/python -m omnibot.firmware.avrsketch $$robot $(SKETCH_DIR) && \
	  $(MAKE) -s -C $(SKETCH_DIR)/omnibot_$$robot > $(SKETCH_DIR)/omnibot_$$robot.log 2>&1 || { \
	    tail -20 $(SKETCH_DIR)/omnibot_$$robot.log; echo "make arduino-sketch: arduino-mk failed for $$robot"; exit 1; }; \
	  $(MAKE) -s --no-print-directory -C firmware-avr size-of ROBOT=$$robot \
	    ELF=$(CURDIR)/$(SKETCH_DIR)/omnibot_$$robot/build-uno/omnibot_$$robot.elf || exit 1; \
	  PYTHONPATH=src $(BIN)/python -m omnibot.firmware.avrsketch $$robot $(SKETCH_DIR) --board mega && \
	  $(MAKE) -s -C $(SKETCH_DIR)/omnibot_$${robot}_mega > $(SKETCH_DIR)/omnibot_$${robot}_mega.log 2>&1 || { \
	    tail -20 $(SKETCH_DIR)/omnibot_$${robot}_mega.log; echo "make arduino-sketch: arduino-mk failed for $$robot (mega)"; exit 1; }; \
	  $(MAKE) -s --no-print-directory -C firmware-avr size-of ROBOT=$$robot BOARD=mega \
	    ELF=$(CURDIR)/$(SKETCH_DIR)/omnibot_$${robot}_mega/build-mega-atmega2560/omnibot_$${robot}_mega.elf || exit 1; \
	done

# Foxglove's own MCAP libraries (@mcap/core, @mcap/support, @foxglove/rosmsg2-serialization; versions
# pinned in tests/logs/node/package.json) for the log tests, installed with npm into .cache/ (git-ignored)
# when missing. Without node and npm the tests that need them skip and say why.
MCAP_READERS := .cache/mcap-readers
mcap-readers:
	@command -v npm >/dev/null 2>&1 || { echo "make mcap-readers: no npm; the Foxglove reader tests will skip"; exit 0; }; \
	mkdir -p $(MCAP_READERS); \
	cmp -s tests/logs/node/package.json $(MCAP_READERS)/package.json && [ -d $(MCAP_READERS)/node_modules/@mcap/core ] || { \
	  echo "make mcap-readers: installing Foxglove's MCAP libraries into $(MCAP_READERS)"; \
	  cp tests/logs/node/package.json $(MCAP_READERS)/package.json && \
	  npm install --prefix $(MCAP_READERS) --no-audit --no-fund --silent; }

# Genuine rclpy for the ROS 2 interop tests (tests/ros2/test_rclpy_*.py), never a runtime dependency:
# Jazzy's wheels are the `ros2-test` extra of the project's venv; Kilted's share their names (ros-rclpy,
# ros-rmw, ...), so they get their own venv in .cache/ros2-kilted (pins in
# tests/ros2/kilted/requirements.txt), rebuilt when the pins change. Without them those tests skip.
KILTED := .cache/ros2-kilted
# its wheels are built for CPython 3.11 only
KILTED_PYTHON ?= python3.11
ros2-kilted:
	@cmp -s tests/ros2/kilted/requirements.txt $(KILTED)/requirements.txt || { \
	  echo "make ros2-kilted: installing ROS 2 Kilted's rclpy into $(KILTED)"; \
	  rm -rf $(KILTED) && $(KILTED_PYTHON) -m venv $(KILTED) && \
	  $(KILTED)/bin/python -m pip install --quiet -r tests/ros2/kilted/requirements.txt && \
	  cp tests/ros2/kilted/requirements.txt $(KILTED)/requirements.txt || { rm -rf $(KILTED); \
	  echo "make ros2-kilted: Kilted's rclpy wheels did not install (they exist for CPython 3.11 on x86_64): its interop tests will skip"; }; }

# Jazzy's wheels (the ros2-test extra), once per change of pyproject.toml; where they cannot install
# (another platform) the interop tests skip and say so, as the note printed here does.
ROS2_STAMP := $(VENV)/.ros2-test
ros2-interop: setup ros2-kilted $(ROS2_STAMP)

$(ROS2_STAMP): pyproject.toml constraints.txt
	@$(BIN)/python -m pip install --quiet -c constraints.txt -e '.[ros2-test]' && touch $@ || \
	  echo "make ros2-interop: Jazzy's rclpy wheels did not install (they exist for CPython 3.11 on x86_64): its interop tests will skip"

# The tests on TEST_JOBS workers (pytest-xdist; 4 on two cores: two of them mostly wait on the ROS 2
# tests' wall clock): the workers take whole modules, the costliest first; then the tests marked
# `serial` (they time themselves against the wall clock) run alone, in one process (tests/parallel.py
# says which and why). Both passes run; either failing fails `make test`.
# `make test TEST_JOBS=0` runs the first pass in one process too; to debug a test, run pytest on it:
# `.venv/bin/python -m pytest tests/...` (one process, collection order).
# The tests keep their bytecode whatever PYTHONDONTWRITEBYTECODE says (it is unset for them): without
# it every worker compiled pytest's rewritten test modules anew (collecting the suite, one process:
# 20.1 s of CPU, 8.4 s with them kept) and every omnibot process a test starts compiled omnibot anew.
TEST_JOBS ?= 4
PYTEST := env -u PYTHONDONTWRITEBYTECODE SDL_VIDEODRIVER=dummy MPLBACKEND=Agg $(BIN)/python -m pytest
test: lint browser avr-tools uno-sim arduino-sketch mcap-readers ros2-interop
	@$(PYTEST) -q -n $(TEST_JOBS) -m "not serial"; parallel=$$?; \
	$(PYTEST) -q -m serial $$($(BIN)/python -m tests.parallel); serial=$$?; \
	echo "make test: pytest exited $$parallel (parallel pass) and $$serial (serial pass)"; \
	[ $$parallel -eq 0 ] && [ $$serial -eq 0 ]

bench: setup
	$(BIN)/python -m benchmarks.run_all

# Coverage-guided fuzzing (atheris, the `fuzz` extra) of the controller's text input, checked against
# the host codec, and of the binary decoders: FUZZ_SECONDS per target. Not part of `make test`, which
# runs the same targets on a bounded hypothesis budget (tests/fuzz/). Crashes land in fuzz/crash-*.
FUZZ_SECONDS ?= 600
fuzz: setup
	$(BIN)/python -m pip install --quiet -c constraints.txt -e '.[fuzz]'
	@mkdir -p fuzz
	cd fuzz && PYTHONPATH=.. SDL_VIDEODRIVER=dummy $(BIN)/python -m tests.fuzz.run text --seconds $(FUZZ_SECONDS) --corpus corpus-text
	cd fuzz && PYTHONPATH=.. SDL_VIDEODRIVER=dummy $(BIN)/python -m tests.fuzz.run binary --seconds $(FUZZ_SECONDS) --corpus corpus-binary

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache .mypy_cache .ruff_cache .cache fuzz
