"""One recorded run as a Rerun recording (``.rrd``): the robot, the feet and the odometry's rows
(:class:`~a1_leg_fk.view.scene.Scene`), the paths, gait and filter of the odometry
(:mod:`.columns`) and the summary as a text document; written under a temporary name and renamed
when complete, so a failed or interrupted run leaves no partial ``.rrd``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import rerun as rr

from a1_leg_fk.kinematics.robot_config import load_robot
from a1_leg_fk.model.urdf import LegFkError, default_urdf_path, read_urdf_text
from a1_leg_fk.recording.odometry import OdometryTrack
from a1_leg_fk.recording.odometry_truth import truth_body_velocities
from a1_leg_fk.recording.outputs import OutputTarget
from a1_leg_fk.recording.trajectories import FootTrajectories
from a1_leg_fk.view import columns
from a1_leg_fk.view.columns import BaseRows, FeetRows
from a1_leg_fk.view.scene import APPLICATION_ID, Scene

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
    urdf, foot_links, joint_aliases = robot
    quadruped = load_robot(feet.urdf_xml, "", foot_links, joint_aliases).quadruped
    target.prepare()
    recording = rr.RecordingStream(APPLICATION_ID, send_properties=False)
    try:
        recording.save(str(target.temporary))
        scene = Scene(recording, _urdf_path(target, feet, urdf), quadruped)
        if track is None:
            scene.send(FeetRows.of(feet), None)
        else:
            _send_with_odometry(scene, FeetRows.of(feet), track)
        scene.log_summary(summary)
        recording.flush()
        recording.disconnect()
        (target.folder / URDF_COPY).unlink(missing_ok=True)
        target.commit()
    except BaseException:
        recording.disconnect()
        target.discard()
        raise
    return scene.note


def _send_with_odometry(scene: Scene, rows: FeetRows, track: OdometryTrack) -> None:
    """The rows with the odometry's, the truth's velocity and path (``--truth``), the feet's
    trails, the odometry's gait diagram and its filter's NIS and gate counts.
    """
    base, truth, recording = BaseRows.of(track), track.truth, scene.recording
    stamps = base.stamps_ns
    scene.send(rows, base, truth_body_velocities(truth, stamps) if truth is not None else None)
    columns.send_paths(recording, rows, base, truth.at(stamps)[0] if truth is not None else None)
    columns.send_gait(recording, stamps, track.stance)
    columns.send_filter(recording, stamps, track.filter_history)


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
