"""ament_python packaging of a1_leg_fk (the layout of ros2/demos' demo_nodes_py).

The version is read from package.xml, so that file alone decides it.
"""

import os
from glob import glob
from xml.etree import ElementTree

from setuptools import find_packages, setup

package_name = "a1_leg_fk"
here = os.path.dirname(os.path.abspath(__file__))
version = (
    ElementTree.parse(os.path.join(here, "package.xml")).getroot().findtext("version").strip()
)

setup(
    name=package_name,
    version=version,
    packages=find_packages(exclude=["test", "test.*"]),
    # PEP 561: users' type checkers read the package's annotations.
    package_data={package_name: ["py.typed"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/config", sorted(glob("config/*.yaml"))),
        ("share/" + package_name + "/config/robots", sorted(glob("config/robots/*.yaml"))),
        ("share/" + package_name + "/launch", sorted(glob("launch/*.launch.py"))),
        ("share/" + package_name + "/rviz", sorted(glob("rviz/*.rviz"))),
    ],
    # Only setuptools: rclpy and the message packages come from the ROS install (apt, rosdep) or
    # from requirements.txt (PyPI wheels); an apt Jazzy install has no pip metadata for them.
    install_requires=["setuptools"],
    extras_require={
        "test": ["pytest", "hypothesis"],
        # a1-leg-fk view: the Rerun SDK (its viewer inside the wheel, about 170 MB)
        "view": ["rerun-sdk==0.41.0"],
    },
    zip_safe=True,
    maintainer="a1_leg_fk maintainers",
    maintainer_email="maintainer@example.com",
    description="Forward kinematics of a quadruped's feet from a URDF, as a ROS 2 node.",
    license="Apache-2.0",
    python_requires=">=3.10",
    entry_points={
        "console_scripts": [
            "foot_fk_node = a1_leg_fk.ros.executables:foot_fk_node",
            "foot_ik_node = a1_leg_fk.ros.executables:foot_ik_node",
            "joint_state_demo = a1_leg_fk.ros.executables:joint_state_demo",
            "leg_odometry_node = a1_leg_fk.ros.executables:leg_odometry_node",
            "a1-leg-fk = a1_leg_fk.cli:main",
        ],
    },
)
