"""Which message types a bag is read with: one rule, here.

- The bag's own message definitions, when it records them: every ROS 1 bag, rosbag2 from Iron on.
  Old ROS 1 bags define their header as ``roslib/Header`` (before ``std_msgs/Header`` existed);
  it is read as ``std_msgs/Header``: the same three fields, so the same wire layout and MD5.
- A rosbag2 bag that records no definition at all (Foxy, Galactic, Humble: metadata version
  <= 5) is read with rosbags' bundled typestore of the ROS 2 distro the bag names: its
  ``metadata.yaml``'s ``ros_distro`` (metadata version 8 on), else the ``schema`` table of its
  sqlite3 file (rosbag2 0.15.4 on, January 2023 in Humble); else of :data:`DEFAULT_DISTRO`.
  The standard types read here (JointState, Odometry, Pose*, TFMessage, Imu, String) are the same
  from Foxy to Jazzy. Unitree's (``unitree_go``) are no distro's: the package's own definitions
  (:mod:`a1_leg_fk.wire.unitree_types`) are added to those bundled types.

A type that the chosen types cannot define is named by :func:`require_types`. No ROS install:
``rosbags`` is imported when a bag is opened.
"""

from __future__ import annotations

import contextlib
import functools
import sqlite3
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.reads import BoundedPath, one_line
from a1_leg_fk.wire.unitree_types import DEFINITIONS

if TYPE_CHECKING:  # rosbags is imported when a bag is opened
    from rosbags.highlevel import AnyReader
    from rosbags.typesys.store import Typestore

DEFAULT_DISTRO = "humble"
"""The ROS 2 distro whose bundled types read a bag that records neither definitions nor its
distro: the most used ROS 2 release whose rosbag2 stored no definitions."""
OLD_HEADER, HEADER = "roslib/Header", "std_msgs/Header"


class CannotOpen(Exception):
    """rosbags cannot open the file (not a bag, or damaged where it starts or is indexed)."""


def open_reader(path: Path) -> tuple[AnyReader, str]:
    """An open ``AnyReader`` of ``path`` (a ROS 1 ``.bag``, a rosbag2 directory, ``.mcap`` or
    ``.db3`` file) with the types of the rule above, and a line saying which types those are.
    Its files are read through :class:`~a1_leg_fk.recording.reads.BoundedPath`. Raises
    :class:`CannotOpen` with what rosbags raised for a file it cannot open.
    """
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    try:
        # an empty default lets a bag without definitions open; its types are chosen below
        reader = AnyReader([BoundedPath(path)], default_typestore=get_typestore(Stores.EMPTY))
        if not reader.is2:
            reader.readers = [_ros1_reader_class()(bag) for bag in reader.paths]
        reader.open()
    except Exception as error:  # rosbags raises many kinds for what it cannot open
        raise CannotOpen(one_line(error)) from error
    try:
        return reader, _choose_types(reader, path)
    except BaseException:
        reader.close()
        raise


def _choose_types(reader: AnyReader, path: Path) -> str:
    """Give ``reader`` the bundled types if the bag defines none; the summary's line on them."""
    from rosbags.interfaces import MessageDefinitionFormat
    from rosbags.typesys import Stores, get_typestore

    if not reader.is2:
        renamed = any(getattr(bag, "renamed_old_header", False) for bag in reader.readers)
        return "recorded in the bag" + (f" ({OLD_HEADER} read as {HEADER})" if renamed else "")
    if any(c.msgdef.format != MessageDefinitionFormat.NONE for c in reader.connections):
        return "recorded in the bag"  # rosbags defines the types from the definitions there are
    distro, source = recorded_distro(reader, path)
    chosen = distro if distro in _bundled_distros() else DEFAULT_DISTRO
    reader.typestore = with_unitree_types(get_typestore(Stores(f"ros2_{chosen}")))
    default = f"{chosen.capitalize()} is the default"
    if distro is None:
        why = f"no ROS distro recorded: {default}"
    elif chosen == distro:
        why = f"ROS distro '{distro}' from {source}"
    else:
        why = f"ROS distro '{distro}' from {source} has no bundled types: {default}"
    return (
        f"rosbags' bundled ROS 2 {chosen.capitalize()} types and the package's Unitree "
        f"definitions (the bag has no message definitions, as rosbag2 wrote before Iron; {why})"
    )


def with_unitree_types(typestore: Typestore) -> Typestore:
    """``typestore`` with Unitree's message types added (written from their published field
    lists: :data:`~a1_leg_fk.wire.unitree_types.DEFINITIONS`).
    """
    from rosbags.typesys import get_types_from_msg

    types = {}
    for msgtype, text in DEFINITIONS.items():
        types.update(get_types_from_msg(text, msgtype))
    typestore.register(types)
    return typestore


def recorded_distro(reader: AnyReader, path: Path) -> tuple[str | None, str]:
    """The ROS distro a rosbag2 bag says it was recorded with, and where it says so: its
    metadata (``metadata.yaml`` version >= 8), else its sqlite3 file's ``schema`` table; else
    ``(None, "")``.
    """
    distro = getattr(reader.readers[0], "ros_distro", None)  # rosbag2's reader has it
    if distro:
        return str(distro), "metadata.yaml"
    files = sorted(path.glob("*.db3")) if path.is_dir() else [path]
    for db3 in files:
        if db3.suffix == ".db3":
            distro = _sqlite_distro(db3)
            if distro:
                return distro, db3.name
    return None, ""


def _sqlite_distro(db3: Path) -> str | None:
    """``ros_distro`` of a rosbag2 sqlite3 file's ``schema`` table, or None (no such table)."""
    try:
        with contextlib.closing(
            sqlite3.connect(db3.resolve().as_uri() + "?immutable=1", uri=True)
        ) as connection:
            row = connection.execute("SELECT ros_distro FROM schema").fetchone()
    except sqlite3.Error:
        return None
    distro = str(row[0]).strip().lower() if row else ""
    return distro or None


@functools.cache
def _bundled_distros() -> frozenset[str]:
    """The ROS 2 distros rosbags bundles types of (``humble``, ``jazzy``, ...)."""
    from rosbags.typesys import Stores

    return frozenset(
        store.value.removeprefix("ros2_") for store in Stores if store.value.startswith("ros2_")
    )


@functools.cache
def _ros1_reader_class() -> type:
    """A ROS 1 reader (rosbags') reading ``roslib/Header`` definitions as ``std_msgs/Header``."""
    from rosbags.rosbag1 import Reader

    class Ros1Reader(Reader):
        renamed_old_header = False

        def read_connection(self) -> Any:
            connection = super().read_connection()
            text = connection.msgdef.data
            if OLD_HEADER not in text:
                return connection
            self.renamed_old_header = True
            definition = connection.msgdef._replace(data=text.replace(OLD_HEADER, HEADER))
            return connection._replace(msgdef=definition)

    return Ros1Reader


def require_types(reader: AnyReader, path: Path, wanted: Mapping[str, str], types: str) -> None:
    """:class:`LegFkError` naming the first of ``wanted`` (message type -> what needs it, e.g.
    ``"--base-pose /odom"``) that ``reader``'s types cannot define; ``types`` is the line of
    :func:`open_reader` saying which types those are.
    """
    for msgtype, what in wanted.items():
        if msgtype not in reader.typestore.fielddefs:
            raise LegFkError(
                f"{path}: {what} is {msgtype}, which is not among the types the bag is read "
                f"with: {types}"
            )
