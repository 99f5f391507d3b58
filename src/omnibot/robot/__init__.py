"""Robot descriptions: the YAML model, presets, kinematics and the physical specs they hold."""

__all__ = ["battery", "courses", "description", "kinematics", "summary", "urdf"]
