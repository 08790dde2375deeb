"""A calibration's file (a1_leg_fk/estimation/correction_file.py), by construction: written and
read back, taken off as it is by the estimator, and refused in one line when it does not match
the robot (other joints, absurd values, not a calibration)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from a1_leg_fk.estimation.contact_estimator import ContactEstimator
from a1_leg_fk.estimation.correction_file import CorrectionFile, read_correction_file
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.urdf import LegFkError

A1 = Quadruped.from_urdf()
TERMS = tuple((round(0.1 * j, 4), round(0.01 * j, 4), round(0.05 * j, 4)) for j in range(12))
"""Per joint: bias [N m], viscous [N m s/rad], Coulomb [N m], all within the bounds."""
A1_KG = 12.458
"""pybullet_data's a1.urdf: the sum of its links' masses [kg] (trunk 4.713, 4 x (hip 0.696,
thigh 1.013, calf 0.166, toe 0.06), five 1 g links), by hand."""


def written(tmp_path: Path, **changes: object) -> Path:
    """A calibration of the A1 (:data:`TERMS`, 1.5 kg of payload) with ``changes`` made to its
    document (``joint__NAME`` replaces one joint's entry)."""
    calibration = CorrectionFile(
        A1.joint_names, TERMS, tuple((100.0, 0.5, 0.1) for _ in TERMS), 1.5, 0.4, "a run", A1_KG
    )
    document = json.loads(calibration.text())
    for key, value in changes.items():
        if key.startswith("joint__"):
            document["joints"][key.removeprefix("joint__")] = value
        else:
            document[key] = value
    path = tmp_path / "calibration.yaml"
    path.write_text(json.dumps(document))
    return path


def test_a_calibration_is_read_back_and_taken_off_as_it_is(tmp_path: Path) -> None:
    path = written(tmp_path)
    calibration = read_correction_file(path, A1.joint_names, A1_KG)
    assert calibration.terms == TERMS and calibration.payload_kg == 1.5
    estimator = ContactEstimator(A1, model_corrections=str(path))
    corrections = estimator.corrections
    assert corrections is not None and corrections.fixed
    bias, viscous, coulomb = TERMS[5]
    rate = 2.0  # rad/s: the smooth sign is tanh(20) = 1 to 1e-17
    expected = 1.0 - (bias - viscous * rate - coulomb)
    assert math.isclose(corrections.correct(5, 1.0, rate), expected, abs_tol=1e-12)
    assert "from a calibration's file" in corrections.line()
    weight = estimator.statics.total_mass_kg + 1.5  # the payload weighs on the filter's scales
    assert math.isclose(estimator.rule.thresholds.touchdown_n / 9.80665, 0.08 * weight)


@pytest.mark.parametrize(
    ("changes", "reason"),
    [
        ({"joint__FR_hip_joint": None}, "not a mapping"),
        ({"joints": {"knee": {}}}, "are not the robot's"),
        ({"joint__FL_lower_joint": {"bias_nm": 50.0}}, "bias_nm 50.0 is absurd"),
        (
            {"joint__FL_lower_joint": {"bias_nm": 0.0, "viscous_nms_per_rad": -0.1}},
            "coulomb_nm is not a number",
        ),
        ({"payload_kg": 1e3}, "payload_kg 1000.0 is absurd"),
        ({"payload_kg": math.nan}, "payload_kg nan is absurd"),
        ({"format": "something else"}, "format is not"),
        ({"urdf_mass_kg": 20.638}, "made for a robot whose URDF weighs 20.638 kg"),
        ({"urdf_mass_kg": "a1"}, "urdf_mass_kg is not a number"),
        ({"leg_inertia_scales": {"FR": 0.9}}, "leg_inertia_scales must give each of FR, FL"),
        (
            {"leg_inertia_scales": {"FR": 0.9, "FL": 3.0, "RR": 1.0, "RL": 1.0}},
            "leg_inertia_scales FL 3.0 is absurd",
        ),
        (
            {"leg_inertia_scales": {"FR": 0.2, "FL": 1.0, "RR": 1.0, "RL": 1.0}},
            "leg_inertia_scales FR 0.2 is absurd",
        ),
    ],
)
def test_a_file_that_does_not_match_the_robot_is_refused(
    tmp_path: Path, changes: dict[str, object], reason: str
) -> None:
    path = written(tmp_path, **changes)
    with pytest.raises(LegFkError, match=reason) as error:
        ContactEstimator(A1, model_corrections=str(path))
    assert "\n" not in str(error.value) and str(path) in str(error.value)


def test_negative_friction_and_an_unreadable_file_are_refused(tmp_path: Path) -> None:
    friction = {"bias_nm": 0.0, "viscous_nms_per_rad": -0.1, "coulomb_nm": 0.2}
    path = written(tmp_path, joint__RR_upper_joint=friction)
    with pytest.raises(LegFkError, match="RR_upper_joint's friction is negative"):
        read_correction_file(path, A1.joint_names, 12.0)
    with pytest.raises(LegFkError, match="cannot be read"):
        read_correction_file(tmp_path / "missing.yaml", A1.joint_names, 12.0)
    (tmp_path / "text.yaml").write_text("bias: [1, 2")
    with pytest.raises(LegFkError, match="cannot be read"):
        read_correction_file(tmp_path / "text.yaml", A1.joint_names, 12.0)


def test_the_legs_inertia_scales_are_read_back_and_applied(tmp_path: Path) -> None:
    """A file's per-leg scales reach the observer as they are (FR 15 % lighter: 0.15 of the
    URDF's torque W taken off, by hand); a file without them (of before the scales) gives 1."""
    scales = {"FR": 0.85, "FL": 1.0, "RR": 1.2, "RL": 0.95}
    path = written(tmp_path, leg_inertia_scales=scales)
    estimator = ContactEstimator(A1, model_corrections=str(path))
    corrections = estimator.corrections
    assert corrections is not None and corrections.scales.scales == list(scales.values())
    residual = corrections.scales.correct(0, (1.0, 2.0, 3.0), (10.0, -20.0, 5.0))
    assert residual == pytest.approx((1.0 - 1.5, 2.0 + 3.0, 3.0 - 0.75), abs=1e-12)
    assert "0.850,1.000,1.200,0.950" in corrections.line()
    without = written(tmp_path)
    document = json.loads(without.read_text())
    del document["leg_inertia_scales"]
    without.write_text(json.dumps(document))
    assert read_correction_file(without, A1.joint_names, A1_KG).inertia_scales == (1.0,) * 4
