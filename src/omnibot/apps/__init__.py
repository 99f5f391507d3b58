"""The composition roots: ``omnibot`` subcommands that wire libraries and front ends into a runtime.

Nothing imports this package (``tests/test_imports.py`` holds it to that). Today it holds the newest
commands; the others still live beside the libraries they drive (``runtime/command.py``,
``navigation/commands.py`` ...) and move here as the command line is reorganised.

* :mod:`omnibot.apps.mapping` - ``omnibot map``: drive the robot (a path, a pad or the keyboard)
  while the SLAM maps the room; the map, the trajectories and, on the simulator, their scores.
"""
