"""The robot in a Rerun recording: its description (Rerun's own URDF loader: meshes where they
resolve, the collision shapes), a line from each link's origin to each child joint, the links'
axes, and the transforms that pose it: the fixed joints once, the movable joints' rotations and
the base's pose in odom as columns over the recording's timeline.

Frames are Rerun's named frames: each link's name (as in the URDF), and ``tf#/odom``, the
implicit frame of the entity :data:`ODOM`, which the odom-frame things (trails, paths) share.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np
import rerun as rr

from a1_leg_fk.estimation.so3 import quaternion_of
from a1_leg_fk.kinematics.leg_stages import rpy_matrix
from a1_leg_fk.model.urdf import Joint, LegFkError, RobotModel

ROBOT = "robot"
"""The entity under which the description is logged."""
ODOM = "odom"
"""The entity of the odometry frame; its things live in its implicit frame :data:`ODOM_FRAME`."""
ODOM_FRAME = "tf#/odom"
JOINTS = f"{ROBOT}/joints"
"""Each joint's transform (parent link -> child link) at ``JOINTS/<joint>``."""
BASE_POSE = f"{ROBOT}/base_pose"
"""The root link's pose in odom (parent :data:`ODOM_FRAME`)."""
SKELETON = f"{ROBOT}/skeleton"
AXIS_LENGTH_M = 0.04
LINE_RADIUS_M = 0.006


def log_description(
    recording: rr.RecordingStream, urdf_path: Path, model: RobotModel
) -> tuple[Any, str]:
    """Log the description statically (without its joints' transforms, which
    :func:`send_joint_columns` sends) and the skeleton; return Rerun's URDF tree and a note
    ("" when every mesh resolves). :class:`LegFkError` when Rerun cannot load the URDF.
    """
    try:
        tree = rr.urdf.UrdfTree.from_file_path(urdf_path, entity_path_prefix=ROBOT)
        recording.send_chunks(tree.stream(include_joint_transforms=False))
    except Exception as error:  # noqa: BLE001 (the bindings raise plain Rust errors)
        raise LegFkError(f"{urdf_path}: Rerun cannot load this URDF: {error}") from None
    _log_skeleton(recording, model)
    missing = missing_meshes(urdf_path)
    note = (
        f"meshes not found ({len(missing)}, e.g. {missing[0]}): links drawn as their collision "
        "shapes, frames and lines"
        if missing
        else ""
    )
    return tree, note


def _log_skeleton(recording: rr.RecordingStream, model: RobotModel) -> None:
    """Per joint, a line in its parent link's frame from the origin to the joint; per link, its
    axes.
    """
    for name, joint in model.joints.items():
        recording.log(
            f"{SKELETON}/{name}",
            rr.LineStrips3D([[(0.0, 0.0, 0.0), joint.origin_xyz]], radii=LINE_RADIUS_M),
            rr.CoordinateFrame(joint.parent),
            static=True,
        )
    for link in model.links:
        recording.log(
            f"{SKELETON}/axes/{link}",
            rr.TransformAxes3D(AXIS_LENGTH_M),
            rr.CoordinateFrame(link),
            static=True,
        )


def log_fixed_transforms(
    recording: rr.RecordingStream, tree: Any, model: RobotModel, movable: Sequence[str], root: str
) -> None:
    """What stays put (static): the transform of every joint not in ``movable`` (Rerun's, at
    its zero); of each joint in ``movable`` its frames and translation (its rotation per row:
    :func:`send_joint_columns`); and the root link's parent, odom (its pose:
    :func:`send_base_columns`).
    """
    for name, joint in model.joints.items():
        if name in movable:
            transform = rr.Transform3D(
                translation=joint.origin_xyz, parent_frame=joint.parent, child_frame=joint.child
            )
        else:
            transform = tree.get_joint_by_name(name).compute_transform(0.0)
        recording.log(f"{JOINTS}/{name}", transform, static=True)
    recording.log(
        BASE_POSE, rr.Transform3D(parent_frame=ODOM_FRAME, child_frame=root), static=True
    )


def send_joint_columns(
    recording: rr.RecordingStream,
    model: RobotModel,
    movable: Sequence[str],
    time: np.ndarray,
    angles: np.ndarray,
) -> None:
    """The rotations of ``movable``'s joints (the columns of ``angles`` (N, len(movable))
    [rad]) at the rows of ``time`` (N,) [ns] where each angle is known: one quaternion per row,
    the frames and translation being static (:func:`log_fixed_transforms`).
    """
    for slot, name in enumerate(movable):
        known = np.isfinite(angles[:, slot])
        send_known(
            recording,
            f"{JOINTS}/{name}",
            time,
            known,
            lambda: rr.Transform3D.columns(
                quaternion=joint_quaternions(model.joints[name], angles[known, slot])  # noqa: B023
            ),
        )


def joint_quaternions(joint: Joint, angles: np.ndarray) -> np.ndarray:
    """(N, 4) x, y, z, w: the child link's rotation in the parent's frame at ``angles`` (N,)
    [rad] of a revolute or continuous ``joint``: its origin's rpy, then the turn about its axis
    (q0 * q_axis).
    """
    x, y, z, w = quaternion_of(rpy_matrix(joint.origin_rpy).tolist())
    origin, axis = np.array([x, y, z]), np.asarray(joint.axis, float)
    sine, cosine = np.sin(angles / 2)[:, None], np.cos(angles / 2)[:, None]
    vector = w * sine * axis + cosine * origin + sine * np.cross(origin, axis)
    scalar = w * cosine - sine * float(origin @ axis)
    return np.hstack([vector, scalar])


def send_base_columns(
    recording: rr.RecordingStream,
    time: np.ndarray,
    positions: np.ndarray,
    orientations: np.ndarray,
) -> None:
    """The root link's pose in odom at ``time`` (N,) [ns]: ``positions`` (N, 3) [m],
    ``orientations`` (N, 4) x, y, z, w; rows with NaN are left out.
    """
    known = np.isfinite(positions).all(axis=1) & np.isfinite(orientations).all(axis=1)
    send_known(
        recording,
        BASE_POSE,
        time,
        known,
        lambda: rr.Transform3D.columns(
            translation=positions[known], quaternion=orientations[known]
        ),
    )


def send_known(
    recording: rr.RecordingStream,
    entity: str,
    time: np.ndarray,
    known: np.ndarray,
    columns: Callable[[], Any],
) -> None:
    """``columns()`` (the ``known`` rows' values) to ``entity`` at those rows of ``time`` (N,)
    [ns]; nothing when no row is known.
    """
    if known.any():
        recording.send_columns(entity, indexes=[time_column(time[known])], columns=columns())


def time_column(stamps_ns: np.ndarray) -> rr.TimeColumn:
    """The recording's timeline ``stamp``: the messages' stamps [ns]."""
    return rr.TimeColumn("stamp", timestamp=np.asarray(stamps_ns, np.int64).view("datetime64[ns]"))


def missing_meshes(urdf_path: Path) -> list[str]:
    """The mesh file names of the URDF at ``urdf_path`` that resolve to no file: ``package://``
    under ``AMENT_PREFIX_PATH``'s ``share/`` or ``ROS_PACKAGE_PATH``, ``file://`` and relative
    names against the URDF's folder.
    """
    root = ElementTree.parse(urdf_path).getroot()  # already read safely by the model's loader
    names = [mesh.get("filename", "") for mesh in root.iter("mesh")]
    return [name for name in dict.fromkeys(names) if not _resolves(name, urdf_path.parent)]


def _resolves(name: str, folder: Path) -> bool:
    if name.startswith("package://"):
        package, _, rest = name[len("package://") :].partition("/")
        roots = [Path(p) / "share" for p in _paths("AMENT_PREFIX_PATH")]
        roots += [Path(p) for p in _paths("ROS_PACKAGE_PATH")]
        candidates = [root / package / rest for root in roots]
        candidates += [
            Path(p) / rest for p in _paths("ROS_PACKAGE_PATH") if Path(p).name == package
        ]
        return any(candidate.is_file() for candidate in candidates)
    path = Path(name.removeprefix("file://"))
    return (path if path.is_absolute() else folder / path).is_file()


def _paths(variable: str) -> list[str]:
    return [part for part in os.environ.get(variable, "").split(os.pathsep) if part]
