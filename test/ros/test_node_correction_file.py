"""``model_corrections_file`` on both nodes over real DDS: a calibration's file that matches the
robot is applied as it is (its terms in /diagnostics); one that does not (other joints, an absurd
value, another robot's mass, unreadable, or ``file`` without one) is refused in ONE log line
naming the file and the reason, and the node keeps running on the nominal model
(``model_corrections: off`` and the refusal in /diagnostics, its joint states still answered).

The files are written here by hand (the format ``a1-leg-fk calibrate`` documents), not by the
package's writer; every case runs as its own node process (renamed ``-r __node:=CASE``) at once.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from node_harness import STANDING, joint_state_message, node_command
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState
from shared import PYBULLET_NAMES, odometry_node_command

CALF_TERMS = (-0.5, 0.12, 0.3)
"""The good file's calves: bias [N m], viscous [N m s/rad], Coulomb [N m]; the rest 0."""


def calibration(
    joints: list[str], bias: float = 0.0, urdf_mass_kg: float = 12.458
) -> dict[str, object]:
    """A calibration's document for ``joints`` (every calf :data:`CALF_TERMS`; ``bias`` [N m]
    on the first joint), made with a URDF of ``urdf_mass_kg`` [kg] (pybullet_data's A1's, the
    sum of its links' masses by hand)."""
    entries = {}
    for index, name in enumerate(joints):
        terms = CALF_TERMS if index % 3 == 2 else (bias if index == 0 else 0.0, 0.0, 0.0)
        entries[name] = {
            "bias_nm": terms[0],
            "viscous_nms_per_rad": terms[1],
            "coulomb_nm": terms[2],
            "swing_samples": 1000,
            "residual_rms_nm": 0.3,
            "fitted_rms_nm": 0.05,
        }
    return {
        "format": "a1_leg_fk model corrections 1",
        "source": "written by hand",
        "urdf_mass_kg": urdf_mass_kg,
        "payload_kg": 0.0,
        "standing_s": 0.5,
        "joints": entries,
    }


def cases(folder: Path) -> dict[str, tuple[str, str]]:
    """Per case (node name): the file's path ('' none) and what its refusal names ('' applied)."""
    files = {
        "good": calibration(PYBULLET_NAMES),
        "other_joints": calibration([name.replace("_joint", "") for name in PYBULLET_NAMES]),
        "absurd": calibration(PYBULLET_NAMES, bias=1000.0),
        "aliengo": calibration(PYBULLET_NAMES, urdf_mass_kg=20.638),  # its joints: the A1's
    }
    out = {}
    for name, document in files.items():
        path = folder / f"{name}.yaml"
        path.write_text(json.dumps(document))
        out[name] = (str(path), "")
    out["other_joints"] = (out["other_joints"][0], "are not the robot's")
    out["absurd"] = (out["absurd"][0], "is absurd")
    out["aliengo"] = (out["aliengo"][0], "made for a robot whose URDF weighs 20.638 kg")
    out["unreadable"] = (str(folder / "missing.yaml"), "cannot be read")
    out["no_file"] = ("", "without a model_corrections_file")
    return out


@pytest.mark.slow
@pytest.mark.parametrize(
    ("executable", "command", "suffix"),
    [
        ("foot_fk_node", node_command, "foot kinematics"),
        ("leg_odometry_node", odometry_node_command, "leg odometry"),
    ],
)
def test_a_calibration_file_is_applied_or_refused_in_one_line(
    ros, processes, tmp_path, executable, command, suffix
) -> None:
    started = {}
    for case, (path, _) in cases(tmp_path).items():
        arguments = ["-r", f"__node:={case}", "-p", "model_corrections:=file"]
        if path:
            arguments += ["-p", f"model_corrections_file:={path}"]
        started[case] = processes.start(command(*arguments))
    latest: dict[str, dict[str, str]] = {}

    def on_diagnostics(message: DiagnosticArray) -> None:
        for status in message.status:
            case, _, name = status.name.partition(": ")
            if name == suffix:
                latest[case] = {kv.key: kv.value for kv in status.values}

    ros.node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 10)
    publisher = ros.node.create_publisher(JointState, "joint_states", QoSProfile(depth=10))
    received = "messages_received" if executable == "foot_fk_node" else "joint_states_received"

    sent = [0.0]

    def all_answered() -> bool:
        if time.monotonic() - sent[0] > 0.2:  # a joint state with efforts, 5 a second
            stamp_ns = time.time_ns()
            message = joint_state_message(PYBULLET_NAMES, STANDING, [0.0] * 12, stamp_ns=stamp_ns)
            message.effort = [0.0] * 12
            publisher.publish(message)
            sent[0] = time.monotonic()
        return all(int(latest.get(case, {}).get(received, "0")) > 0 for case in started)

    outputs = lambda: "\n".join(f"{c}: {processes.output(p)}" for c, p in started.items())  # noqa: E731
    assert ros.spin_until(all_answered, 60.0), (latest, outputs())
    for case, (path, refusal) in cases(tmp_path).items():  # the pybullet_data A1's joints
        process, values = started[case], latest[case]
        output = processes.output(process)
        assert process.poll() is None, output
        refused = [line for line in output.splitlines() if "refused" in line]
        if not refusal:
            assert values["model_corrections"] == "file", values
            assert "model_corrections_refused" not in values, values
            for leg in ("FR", "FL", "RR", "RL"):
                assert values[f"model_corrections_{leg}"] == (
                    "+0.00,0.00,0.00/+0.00,0.00,0.00/-0.50,0.12,0.30"
                ), values
            assert refused == [], output
        else:
            assert values["model_corrections"] == "off", values
            assert refusal in values["model_corrections_refused"], values
            assert len(refused) == 1, output
            assert refusal in refused[0] and "nominal model" in refused[0], refused
            assert path in refused[0] or not path, refused
        assert "Traceback" not in output
        assert processes.interrupt(process) == 0, output
