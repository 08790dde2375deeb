"""Exporter-written robot descriptions (Unitree Go2 and B2 style) with zero configuration: feet
against PyBullet, the verify twin on descriptions whose meshes cannot be found, and the node.

The reference loads the same robot written with primitives instead of meshes
(``exported_quadruped(..., meshes=False)``), straight into PyBullet: it never goes through the
package's own mesh handling.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet
import pytest
from exported_urdf import FEET, QUIRKS, exported_quadruped, reference_robot
from node_harness import NodeClient, distance, node_command, parse_tokens
from pybullet_reference import assert_twin_agrees
from shared import LEGS, UNITREE_NAMES

from a1_leg_fk.kinematics.robot_config import load_robot
from a1_leg_fk.verify import PyBulletFeet

TOLERANCE_M = 1e-7


def in_limit_configurations(
    limits: tuple[np.ndarray, np.ndarray], count: int, seed: int
) -> np.ndarray:
    return np.random.default_rng(seed).uniform(*limits, size=(count, len(UNITREE_NAMES)))


@pytest.mark.parametrize("robot", ["go2", "b2"])
def test_feet_match_pybullet_with_no_configuration(tmp_path: Path, robot: str) -> None:
    config = load_robot(exported_quadruped(robot, **QUIRKS[robot]))
    quadruped = config.quadruped
    assert list(quadruped.joint_names) == UNITREE_NAMES
    assert [leg.chain.foot_link for leg in quadruped.legs] == FEET
    with reference_robot(tmp_path, robot) as reference:
        configurations = in_limit_configurations(reference.limits(UNITREE_NAMES), 500, seed=14)
        worst = max(
            float(np.abs(quadruped.fk(q) - reference.feet(UNITREE_NAMES, FEET, q)).max())
            for q in configurations
        )
    assert worst <= TOLERANCE_M, f"{robot}: max error {worst:.3e} m"


def test_go2_like_standing_foot_by_hand() -> None:
    """FR at hip 0, thigh 0.8, calf -1.5: hip (0.1934, -0.0465, 0), thigh 0.0955 further right,
    then two 0.213 m segments pitched by 0.8 and 0.8 - 1.5 rad about y."""
    foot = load_robot(exported_quadruped("go2")).quadruped.fk([0.0, 0.8, -1.5] * 4)[0]
    expected = (
        0.1934 - 0.213 * np.sin(0.8) - 0.213 * np.sin(0.8 - 1.5),
        -0.0465 - 0.0955,
        -0.213 * np.cos(0.8) - 0.213 * np.cos(0.8 - 1.5),
    )
    np.testing.assert_allclose(foot, expected, rtol=0.0, atol=1e-15)


def test_pybullet_itself_refuses_a_description_whose_meshes_are_missing(tmp_path: Path) -> None:
    """Why verify_fk needs a kinematic twin: loadURDF refuses the whole file over one missing
    mesh."""
    path = tmp_path / "go2_meshes.urdf"
    path.write_text(
        exported_quadruped("go2", mesh_folder="package://no_such_description/meshes"),
        encoding="utf-8",
    )
    client = pybullet.connect(pybullet.DIRECT)
    try:
        with pytest.raises(pybullet.error):
            pybullet.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
    finally:
        pybullet.disconnect(client)


@pytest.mark.parametrize("robot", ["go2", "b2"])
@pytest.mark.parametrize(
    "mesh_folder",
    ["package://no_such_description/meshes", "meshes/not/here", "/no/such/folder"],
    ids=["package-uri", "relative-path", "absolute-path"],
)
def test_the_verify_twin_loads_descriptions_whose_meshes_cannot_be_found(
    tmp_path, robot, mesh_folder
) -> None:
    config = load_robot(exported_quadruped(robot, mesh_folder=mesh_folder, **QUIRKS[robot]))
    assert f'filename="{mesh_folder}/calf.dae"' in config.urdf_xml
    twin = PyBulletFeet(config.quadruped, config.urdf_xml)
    try:
        with reference_robot(tmp_path, robot) as reference:
            configurations = in_limit_configurations(reference.limits(UNITREE_NAMES), 50, seed=3)
            assert_twin_agrees(twin, reference, UNITREE_NAMES, FEET, configurations, TOLERANCE_M)
    finally:
        twin.close()


# --- through the node, over DDS -----------------------------------------------------------


def params_file(tmp_path: Path, xml: str) -> Path:
    """A parameters file with the description as a YAML block scalar (what `-p` cannot carry:
    the exporter header's `Commit Version: 1.6.0` is not valid YAML on the command line)."""
    indented = "\n".join("      " + line for line in xml.splitlines())
    path = tmp_path / "description.yaml"
    path.write_text(
        f"a1_leg_fk:\n  ros__parameters:\n    robot_description: |\n{indented}\n", encoding="utf-8"
    )
    return path


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["go2", "b2"])
def test_the_node_publishes_pybullet_feet_and_verifies_with_no_configuration(
    processes, ros, tmp_path, robot
):
    xml = exported_quadruped(robot, **QUIRKS[robot])
    if robot == "b2":  # the CRLF file as urdf_file, the Go2 one as robot_description
        urdf = tmp_path / "b2_like.urdf"
        urdf.write_bytes(xml.encode("utf-8"))
        process = processes.start(node_command("-p", f"urdf_file:={urdf}"))
    else:
        process = processes.start(node_command("--params-file", str(params_file(tmp_path, xml))))
    client = NodeClient(ros)
    angles = [0.1, 0.7, -1.4, -0.1, 0.9, -1.2, 0.2, 0.6, -1.6, -0.2, 0.8, -1.1]

    def sent_and_all_arrived() -> bool:
        client.send(client.joint_state(UNITREE_NAMES, angles))
        return all(client.positions[leg] for leg in LEGS)  # one topic per foot

    assert client.probe.spin_until(sent_and_all_arrived, 30.0), processes.output(process)
    with reference_robot(tmp_path, robot) as reference:
        expected = reference.feet(UNITREE_NAMES, FEET, angles)
    root = QUIRKS[robot].get("root", "base")
    for slot, leg in enumerate(LEGS):
        message = client.positions[leg][-1]
        assert message.header.frame_id == root
        assert distance(message.point, expected[slot]) <= TOLERANCE_M
    response = client.verify()
    assert response.success, response.message
    assert float(parse_tokens(response.message)["max_error_m"]) <= TOLERANCE_M


@pytest.mark.slow
def test_an_exported_description_on_the_command_line_is_refused_with_a_hint(processes) -> None:
    """rcl parses `-p name:=value` as YAML before the node runs; the exporter header is not
    YAML."""
    process = processes.start(
        node_command("-p", f"robot_description:={exported_quadruped('go2')}")
    )
    assert process.wait(30) == 2
    output = processes.output(process)
    assert "foot_fk_node: cannot start:" in output and "Traceback" not in output
    assert "not valid YAML: give it in a --params-file" in output
    assert "Commit Version" not in output  # the URDF is not echoed back whole
