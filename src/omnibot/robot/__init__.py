"""Robot descriptions: the YAML model, presets, kinematics and the physical specs they hold."""
