"""The composition roots: the ``omnibot`` subcommands that parse their options and wire libraries and
front ends into a runtime (:mod:`omnibot.cli` dispatches to them by name).

Nothing but the command line (:mod:`omnibot.cli`) imports this package from outside it
(``tests/test_imports.py`` holds it to that): the libraries below (teleop, web, navigation, calibration, logs, ros2 ...) export sources, sinks and
functions, and never parse a command line.

* :mod:`omnibot.apps.run` - ``omnibot run``: several front ends on one runtime;
* :mod:`omnibot.apps.teleop` - ``omnibot teleop``: a pad or the keyboard, with a deadman
  (:mod:`omnibot.apps.teleop_loop`: the pad driving a runtime);
* :mod:`omnibot.apps.dashboard` - ``omnibot dashboard``: the web page;
* :mod:`omnibot.apps.record` and :mod:`omnibot.apps.follow` - ``omnibot record`` and ``omnibot follow``:
  teach and repeat a path (:mod:`omnibot.apps.teach`: the robot both drive);
* :mod:`omnibot.apps.calibrate` - ``omnibot calibrate``: power, gyro and odometry calibration (its
  options: :mod:`omnibot.apps.calibrate_options`; the robots it drives: :mod:`omnibot.apps.calibrate_robots`);
* :mod:`omnibot.apps.log` - ``omnibot log``: inspect, plot, export and replay a recording (its options;
  the subcommands in :mod:`omnibot.apps.log_views`, :mod:`omnibot.apps.log_replay`, :mod:`omnibot.apps.log_score`);
* :mod:`omnibot.apps.mapping` - ``omnibot map``: drive the robot (a path, a pad or the keyboard)
  while the SLAM maps the room; the map, the trajectories and, on the simulator, their scores;
* :mod:`omnibot.apps.goto` - ``omnibot goto``: localise on a saved map, plan and go;
* :mod:`omnibot.apps.ros2` - ``omnibot ros2``: robots on ROS 2, and the bridge's options of
  ``omnibot run --ros2`` and ``omnibot map --ros2``;
* :mod:`omnibot.apps.send` and :mod:`omnibot.apps.console` - ``omnibot send`` and ``omnibot console``:
  the protocol by hand (:mod:`omnibot.apps.formats`: how they print replies and events);
* :mod:`omnibot.apps.robot` - ``omnibot robot`` and ``omnibot kinematics``: the robot's description;
* :mod:`omnibot.apps.sim` - ``omnibot sim --pty``: the simulated robot on a pseudo-terminal;
* :mod:`omnibot.apps.demo` - ``omnibot demo`` and ``omnibot tour``: seed 000's and seed 003's demos;
* :mod:`omnibot.apps.subcommands` - the subcommands declared by name and summary, filled in when
  chosen (what keeps ``omnibot --help`` light);
* :mod:`omnibot.apps.recording` - the ``--log`` / ``--foxglove`` recording :func:`omnibot.cli.main`
  opens for a command, which the command hands to its sessions and runtimes.
"""

__all__ = ["demo", "recording", "robot", "sim", "subcommands"]
