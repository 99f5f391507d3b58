"""Paths: the :class:`Path` type, CSV files, teaching, geometry, standard paths and speed profiles."""

from omnibot.control.paths.files import PathFileError, format_path, parse_path, read_path, write_path
from omnibot.control.paths.generator import closed_curve_path, figure_eight_path, smooth_random_path
from omnibot.control.paths.geometry import curvature, douglas_peucker, heading_rate, resample
from omnibot.control.paths.limits import MotionLimits
from omnibot.control.paths.path import Path, Projection
from omnibot.control.paths.profile import Reference, SpeedProfile, time_optimal_profile
from omnibot.control.paths.standard import random_path, standard_names, standard_path
from omnibot.control.paths.teach import PathRecorder

__all__ = [
    "MotionLimits",
    "Path",
    "PathFileError",
    "PathRecorder",
    "Projection",
    "Reference",
    "SpeedProfile",
    "closed_curve_path",
    "curvature",
    "douglas_peucker",
    "figure_eight_path",
    "files",
    "format_path",
    "geometry",
    "heading_rate",
    "limits",
    "parse_path",
    "path",
    "profile",
    "random_path",
    "read_path",
    "resample",
    "smooth_random_path",
    "standard",
    "standard_names",
    "standard_path",
    "teach",
    "time_optimal_profile",
    "write_path",
]
