"""The fields of a message type, for checking field paths of mode sources.

A field's kind is ("base", type), ("msg", "pkg/msg/Name") or ("array", kind).
Types come from rosbags' ROS 2 Jazzy store (no ROS needed: the web side checks
with it), then from the interface packages installed into FTT's environment
(the robot team's own, built at setup), or from a recording's own definitions.
"""

import importlib
import importlib.util
import re
from functools import lru_cache
from pathlib import Path

from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.base import Nodetype

_BOUND = re.compile(r"(,\s*\d+)?>$")
_PACKAGE = re.compile(r"[a-z][a-z0-9_]*")
_KINDS = ("msg", "srv", "action")


@lru_cache(maxsize=1)
def _jazzy():
    return get_typestore(Stores.ROS2_JAZZY)


def _rosbags_kind(desc) -> tuple:
    nodetype, details = desc
    if nodetype == Nodetype.BASE:
        return ("base", details[0])
    if nodetype == Nodetype.NAME:
        return ("msg", details)
    return ("array", _rosbags_kind(details[0]))


def typestore_fields(typestore, typename: str) -> dict:
    """{field: kind} of ``typename`` in a rosbags typestore; KeyError if absent."""
    _, fields = typestore.fielddefs[typename]
    return {name: _rosbags_kind(desc) for name, desc in fields}


def _rosidl_kind(text: str) -> tuple:
    """A kind from rclpy's get_fields_and_field_types() spelling."""
    if text.startswith("sequence<"):
        return ("array", _rosidl_kind(_BOUND.sub("", text[len("sequence<") :])))
    if text.endswith("]"):
        return ("array", _rosidl_kind(text[: text.index("[")]))
    if "/" in text:
        pkg, name = text.split("/")
        return ("msg", f"{pkg}/msg/{name}")
    return ("base", text.split("<")[0])


def installed_fields(typename: str) -> dict:
    """{field: kind} of an installed message type; KeyError when there is none."""
    try:
        return typestore_fields(_jazzy(), typename)
    except KeyError:
        pass
    try:
        fields = message_class(typename).get_fields_and_field_types()
    except (ImportError, AttributeError):
        raise KeyError(typename) from None
    return {field: _rosidl_kind(text) for field, text in fields.items()}


def message_class(typename: str):
    """The rclpy class of 'pkg/msg/Type', imported only from an interface package:
    a type named in a parameter, a bag or the ROS graph never runs another module.
    ImportError when there is none."""
    parts = typename.split("/")
    if len(parts) != 3 or parts[1] not in _KINDS or not is_interface_package(parts[0]):
        raise ImportError(f"no interface package provides {typename}")
    pkg, kind, name = parts
    return getattr(importlib.import_module(f"{pkg}.{kind}"), name)


def is_interface_package(pkg: str) -> bool:
    """Is ``pkg`` an installed ROS interface package (rosidl made its type support
    library beside it)?  Found without importing anything, so a name an operator
    types never runs a module."""
    if not _PACKAGE.fullmatch(pkg):
        return False
    try:
        spec = importlib.util.find_spec(pkg)
    except (ImportError, ValueError):
        return False
    folders = (spec.submodule_search_locations or []) if spec else []
    return any(
        next(Path(folder).glob(f"{pkg}_s__rosidl_typesupport_c*"), None) for folder in folders
    )


def recorded_fields(typestore):
    """fields_of for a recording: its own type definitions, then the installed ones."""

    def fields_of(typename: str) -> dict:
        try:
            return typestore_fields(typestore, typename)
        except KeyError:
            return installed_fields(typename)

    return fields_of


def folder_types(folder) -> dict:
    """{"pkg/msg/Name": definition} of a ROS 2 package or a folder of .msg files
    (the package is the folder's name), for rosbags' ``register``."""
    from pathlib import Path

    from rosbags.typesys import get_types_from_msg

    folder = Path(folder)
    msg_dir = folder / "msg" if (folder / "msg").is_dir() else folder
    package = msg_dir.parent.name if msg_dir.name == "msg" else msg_dir.name
    types: dict = {}
    for path in sorted(msg_dir.glob("*.msg")):
        types.update(get_types_from_msg(path.read_text(), f"{package}/msg/{path.stem}"))
    return types
