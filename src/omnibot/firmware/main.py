"""Board entry point (copied to the board's root as main.py, next to robot_config.py).

Builds the MachineHAL from the pin map in ``robot_config.CONFIG`` and polls the controller forever.
"""

from omnibot.firmware.controller import Controller
from omnibot.firmware.hal import MachineHAL


def run() -> None:
    """Build the board's HAL and controller from ``robot_config`` and poll the controller forever."""
    config = __import__("robot_config").CONFIG
    hal = MachineHAL(config["pins"], config["baud"], config["pwm_max"])
    controller = Controller(hal, config)
    poll = controller.poll
    while True:
        poll()


if __name__ == "__main__":
    run()
