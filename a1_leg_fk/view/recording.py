"""One recorded run as a Rerun recording (``.rrd``): the robot (:mod:`.robot`), the feet, paths
and time series (:mod:`.columns`) and the summary as a text document; written under a temporary
name and renamed when complete, so a failed or interrupted run leaves no partial ``.rrd``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import rerun as rr

from a1_leg_fk.kinematics.robot_config import load_robot
from a1_leg_fk.model.urdf import LegFkError, default_urdf_path, read_urdf_text
from a1_leg_fk.recording.odometry import OdometryTrack
from a1_leg_fk.recording.outputs import OutputTarget
from a1_leg_fk.recording.trajectories import FootTrajectories
from a1_leg_fk.view import columns
from a1_leg_fk.view.robot import log_description, send_base_columns, send_joint_columns

APPLICATION_ID = "a1_leg_fk"
SUMMARY = "summary"
"""The entity of the summary ``bag``/``odom`` print (a text document)."""
URDF_COPY = "robot.urdf"


def write_view(
    target: OutputTarget,
    feet: FootTrajectories,
    track: OdometryTrack | None,
    robot: tuple[str | None, Sequence[str], Sequence[str]],
    summary: Sequence[str],
) -> str:
    """Write the recording to ``target`` (committed only when complete); return a note ("" or
    what is missing, e.g. meshes). ``robot``: the ``--urdf`` path (None: the model the recording
    was read with), ``--foot-links`` and ``--joint-aliases``. :class:`LegFkError` when the
    description cannot be loaded.
    """
    target.prepare()
    try:
        note = _write(target, feet, track, robot, summary)
        (target.folder / URDF_COPY).unlink(missing_ok=True)
        target.commit()
    except BaseException:
        target.discard()
        raise
    return note


def _write(
    target: OutputTarget,
    feet: FootTrajectories,
    track: OdometryTrack | None,
    robot: tuple[str | None, Sequence[str], Sequence[str]],
    summary: Sequence[str],
) -> str:
    urdf, foot_links, joint_aliases = robot
    quadruped = load_robot(feet.urdf_xml, "", foot_links, joint_aliases).quadruped
    recording = rr.RecordingStream(APPLICATION_ID, send_properties=False)
    recording.save(str(target.temporary))
    try:
        tree, note = log_description(recording, _urdf_path(target, feet, urdf), quadruped.model)
        if feet.angles is not None:
            send_joint_columns(
                recording,
                tree,
                quadruped.model,
                quadruped.joint_names,
                feet.stamps_ns,
                feet.angles,
            )
        if track is not None:
            send_base_columns(
                recording,
                quadruped.base_frame,
                track.stamps_ns,
                track.positions,
                track.orientations,
            )
            columns.send_paths(recording, feet, track)
            columns.send_odometry_plots(recording, track)
        columns.send_feet(recording, feet)
        columns.send_feet_plots(recording, feet, quadruped.joint_names)
        text = "\n".join([*summary, *([f"view:      {note}"] if note else [])])
        recording.log(SUMMARY, rr.TextDocument(text), static=True)
        recording.flush()
    finally:
        recording.disconnect()
    return note


def _urdf_path(target: OutputTarget, feet: FootTrajectories, urdf: str | None) -> Path:
    """The description's file for Rerun's loader: ``--urdf``'s (its relative meshes resolve),
    the embedded A1's, else the recorded description copied into the output's hidden folder.
    """
    if urdf:
        return Path(urdf)
    if feet.urdf_xml == read_urdf_text(None)[0]:
        return default_urdf_path()
    if not feet.urdf_xml:
        raise LegFkError("no robot description to draw")
    copy = target.folder / URDF_COPY
    copy.write_text(feet.urdf_xml)
    return copy
