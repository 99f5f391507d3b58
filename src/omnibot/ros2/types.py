"""ROS 2 message types on DDS, built from rosbags' message definitions (none written by hand).

rmw's conventions: a ROS type ``pkg/msg/Name`` is the final DDS struct ``pkg::msg::dds_::Name_``
with the same members (nested types likewise), serialized as XCDR1 (plain CDR); :func:`dds_type`
builds the cyclonedds :class:`~cyclonedds.idl.IdlStruct` class from rosbags' field definitions,
:func:`to_dds` turns a rosbags message object into an instance of it and :func:`from_dds` back.
"""

from __future__ import annotations

import threading
from functools import cache
from typing import Any

import numpy as np
from rosbags.typesys.msg import get_types_from_msg

from omnibot.logs import typestore

try:
    from cyclonedds.idl import IdlStruct, make_idl_struct
    from cyclonedds.idl import types as idl
except ImportError as exc:  # pragma: no cover - the message says how to get it
    raise ImportError("the ROS 2 bridge needs cyclonedds: pip install 'omnibot[ros2]'") from exc

_BASE: dict[str, Any] = {
    "bool": bool,
    "byte": idl.byte,
    "char": idl.uint8,
    "int8": idl.int8,
    "uint8": idl.uint8,
    "int16": idl.int16,
    "uint16": idl.uint16,
    "int32": idl.int32,
    "uint32": idl.uint32,
    "int64": idl.int64,
    "uint64": idl.uint64,
    "float32": idl.float32,
    "float64": idl.float64,
}


def dds_name(typename: str) -> str:
    """``pkg/msg/Name`` -> ``pkg::msg::dds_::Name_`` (rmw's DDS type name)."""
    pkg, kind, name = typename.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


def ros_name(dds: str) -> str:
    """``pkg::msg::dds_::Name_`` -> ``pkg/msg/Name`` (any other name as it is)."""
    parts = dds.split("::")
    if len(parts) == 4 and parts[2] == "dds_" and parts[3].endswith("_"):
        return f"{parts[0]}/{parts[1]}/{parts[3][:-1]}"
    return dds


def _member(desc: tuple[Any, Any]) -> Any:
    node, detail = desc
    kind = int(node)
    if kind == 1:  # BASE
        name, bound = detail
        if name == "string":
            return idl.bounded_str[bound] if bound else str  # type: ignore[misc]
        return _BASE[name]
    if kind == 2:  # NAME
        return dds_type(detail)
    if kind == 3:  # ARRAY
        inner, size = detail
        return idl.array[_member(inner), size]  # type: ignore[misc]
    if kind == 4:  # SEQUENCE
        inner, bound = detail
        if bound:
            return idl.sequence[_member(inner), bound]  # type: ignore[misc]
        return idl.sequence[_member(inner)]  # type: ignore[misc]
    raise ValueError(f"unknown field kind {node}")


_BUILDING = threading.RLock()
"""One class per type in a process (robots open their nodes in threads; cyclonedds refuses a second
class of a type name it knows)."""


def dds_type(typename: str) -> type[IdlStruct]:
    """The final cyclonedds struct of the ROS 2 message ``typename`` (e.g. ``nav_msgs/msg/Odometry``)."""
    with _BUILDING:
        return _dds_type(typename)


@cache
def _dds_type(typename: str) -> type[IdlStruct]:
    _, fields = typestore().fielddefs[typename]
    members = {name: _member(desc) for name, desc in fields}
    if not members:  # an empty ROS message has one uint8 member on the wire
        members = {"structure_needs_at_least_one_member": idl.uint8}
    cls = make_idl_struct(typename.rsplit("/", 1)[1] + "_", dds_name(typename), members)
    cls.__idl_annotations__["extensibility"] = "final"
    return cls


def _convert(value: Any, desc: tuple[Any, Any], to: bool) -> Any:
    node, detail = desc
    kind = int(node)
    if kind == 1:
        if detail[0] in ("float32", "float64"):
            return float(value)
        if detail[0] == "bool":
            return bool(value)
        if detail[0] == "string":
            return str(value)
        return int(value)
    if kind == 2:
        return to_dds(value, detail) if to else from_dds(value, detail)
    inner = detail[0]
    if int(inner[0]) == 1 and inner[1][0] != "string":  # rosbags keeps these as numpy arrays
        if to:
            return [_convert(v, inner, to) for v in np.asarray(value).tolist()]
        return np.array(value, dtype=_NUMPY.get(inner[1][0], object))
    return [_convert(v, inner, to) for v in value]


_NUMPY = {
    "bool": np.bool_,
    "byte": np.uint8,
    "char": np.uint8,
    "int8": np.int8,
    "uint8": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}


def dds_fields(message: Any, typename: str) -> dict[str, Any]:
    """The members of the DDS sample of a rosbags message object of ``typename``."""
    _, fields = typestore().fielddefs[typename]
    if not fields:
        return {"structure_needs_at_least_one_member": 0}
    return {name: _convert(getattr(message, name), desc, True) for name, desc in fields}


def to_dds(message: Any, typename: str) -> IdlStruct:
    """The DDS sample of a rosbags message object of ``typename``."""
    return dds_type(typename)(**dds_fields(message, typename))


SERVICE_TYPES = {
    "std_srvs/srv/Trigger_Request": "",
    "std_srvs/srv/Trigger_Response": "bool success  # indicate successful run of triggered service\n"
    "string message  # informational, e.g. for error messages\n",
}
"""Service request and response types (rosbags' store has messages only): std_srvs' definitions."""

NAVIGATE = "nav2_msgs/action/NavigateToPose"
ACTION_TYPES = {
    "action_msgs/srv/CancelGoal_Request": "action_msgs/GoalInfo goal_info\n",
    "action_msgs/srv/CancelGoal_Response": "int8 ERROR_NONE=0\nint8 ERROR_REJECTED=1\nint8 ERROR_UNKNOWN_GOAL_ID=2\n"
    "int8 ERROR_GOAL_TERMINATED=3\nint8 return_code\naction_msgs/GoalInfo[] goals_canceling\n",
    f"{NAVIGATE}_Goal": "geometry_msgs/PoseStamped pose\nstring behavior_tree\n",
    f"{NAVIGATE}_Result": "uint16 NONE=0\nuint16 error_code\nstring error_msg\n",
    f"{NAVIGATE}_Feedback": "geometry_msgs/PoseStamped current_pose\nbuiltin_interfaces/Duration navigation_time\n"
    "builtin_interfaces/Duration estimated_time_remaining\nint16 number_of_recoveries\nfloat32 distance_remaining\n",
    f"{NAVIGATE}_SendGoal_Request": f"unique_identifier_msgs/UUID goal_id\n{NAVIGATE}_Goal goal\n",
    f"{NAVIGATE}_SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp\n",
    f"{NAVIGATE}_GetResult_Request": "unique_identifier_msgs/UUID goal_id\n",
    f"{NAVIGATE}_GetResult_Response": f"int8 status\n{NAVIGATE}_Result result\n",
    f"{NAVIGATE}_FeedbackMessage": f"unique_identifier_msgs/UUID goal_id\n{NAVIGATE}_Feedback feedback\n",
}
"""Nav2's NavigateToPose action as ROS 2 Jazzy defines it (nav2_msgs/action/NavigateToPose.action: the
goal, result and feedback; Kilted's result adds error code constants, not fields), the parts rosidl
makes of an action (``_SendGoal``, ``_GetResult`` services, ``_FeedbackMessage``) and action_msgs'
CancelGoal service, in dependency order."""


def register_service_types() -> None:
    """Put :data:`SERVICE_TYPES` and :data:`ACTION_TYPES` in the type store (once); rosbags gives an empty
    request the one ``uint8`` member rosidl gives it, so the RIHS01 hashes are ROS 2's."""
    store = typestore()
    for name, text in (SERVICE_TYPES | ACTION_TYPES).items():
        if name not in store.fielddefs:
            # rosbags names what it parses pkg/msg/Name; the definition is registered under the srv name
            ((_, definition),) = get_types_from_msg(text, "omnibot_srv/msg/Parsed").items()
            store.register({name: definition})


def request_type(typename: str) -> type[IdlStruct]:
    """:func:`_request_type`, one class per type in a process."""
    with _BUILDING:
        return _request_type(typename)


@cache
def _request_type(typename: str) -> type[IdlStruct]:
    """rmw_cyclonedds' wire type of a service request or reply of ``typename``
    (``pkg/srv/Name_Request`` or ``_Response``): the final struct ``pkg::srv::dds_::Name_Request_`` whose
    members are the request header (``guid``: the client's request writer's instance handle, ``seq``:
    the client's sequence number; rmw_cyclonedds' ``cdds_request_header_t``) and then the message's."""
    register_service_types()
    _, fields = typestore().fielddefs[typename]
    members: dict[str, Any] = {"guid": idl.uint64, "seq": idl.int64}
    members.update({name: _member(desc) for name, desc in fields})
    cls = make_idl_struct(typename.rsplit("/", 1)[1] + "_", dds_name(typename), members)
    cls.__idl_annotations__["extensibility"] = "final"
    return cls


def from_dds(sample: Any, typename: str) -> Any:
    """The rosbags message object of a DDS sample of ``typename``."""
    _, fields = typestore().fielddefs[typename]
    values = {name: _convert(getattr(sample, name), desc, False) for name, desc in fields}
    return typestore().types[typename](**values)
