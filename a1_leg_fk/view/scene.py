"""The entities a recorded run and a live stream share: :class:`Scene` logs the robot's
description and what stays put once, then sends rows of the feet and the odometry, a whole
recording at once (:mod:`.recording`) or a few at a time (:mod:`.live`), through the same
column functions (:mod:`.robot`, :mod:`.columns`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import rerun as rr

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.view import columns
from a1_leg_fk.view.columns import BaseRows, FeetRows
from a1_leg_fk.view.robot import (
    log_description,
    log_fixed_transforms,
    send_base_columns,
    send_joint_columns,
)

APPLICATION_ID = "a1_leg_fk"
SUMMARY = "summary"
"""The entity of the summary (a text document)."""


class Scene:
    """One robot in one Rerun stream: built, it has logged the description (Rerun's URDF loader
    on ``urdf_path``, the skeleton), the fixed joints and the static styles; ``note`` says what
    the description lacks ("" or the meshes not found). :class:`~a1_leg_fk.model.urdf.
    LegFkError` when Rerun cannot load the URDF.
    """

    def __init__(
        self, recording: rr.RecordingStream, urdf_path: Path, quadruped: Quadruped
    ) -> None:
        self.recording = recording
        self.joints = quadruped.joint_names
        self.model = quadruped.model
        self.tree, self.note = log_description(recording, urdf_path, quadruped.model)
        log_fixed_transforms(
            recording, self.tree, quadruped.model, self.joints, quadruped.base_frame
        )
        columns.log_styles(recording, quadruped.base_frame)

    def send(
        self, feet: FeetRows, base: BaseRows | None, truth_velocity: np.ndarray | None = None
    ) -> None:
        """Rows of the feet (``feet.angles``' columns in the order of ``joints``) and of the
        odometry (None: none), with the true velocity (N, 3) [m/s] in the base frame at
        ``base``'s rows, if known.
        """
        recording = self.recording
        if feet.angles is not None:
            send_joint_columns(recording, self.model, self.joints, feet.stamps_ns, feet.angles)
        columns.send_feet(recording, feet)
        columns.send_feet_plots(recording, feet, self.joints)
        if base is not None:
            send_base_columns(recording, base.stamps_ns, base.positions, base.orientations)
            columns.send_velocity(recording, base, truth_velocity)

    def log_summary(self, lines: Sequence[str]) -> None:
        """``lines`` (and the note) as the text document :data:`SUMMARY`."""
        text = "\n".join([*lines, *([f"view:      {self.note}"] if self.note else [])])
        self.recording.log(SUMMARY, rr.TextDocument(text), static=True)
