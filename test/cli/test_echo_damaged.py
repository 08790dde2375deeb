"""Issue 38: ``a1-leg-fk echo`` fed damaged PointStamped messages on foot_positions/<leg> (cut
short, a length of gigabytes, bit flips, another type's bytes) between good ones: it keeps
running, its table keeps its columns (a bit flip can make a coordinate 1e200), and Ctrl-C ends it
with exit 0 and no traceback. Its subscriptions are typed, not raw: the middleware drops a
message it cannot deserialize before rclpy sees it, so nothing can raise (docs/troubleshooting.md).
"""

from __future__ import annotations

import random
import re

import pytest
from fuzzed_nodes import target_topic
from geometry_msgs.msg import PointStamped
from node_fuzz import ABSURD_LENGTH, BIT_FLIPS, OTHER_TYPE, TRUNCATED, damaged, point_bytes
from rclpy.qos import QoSProfile
from shared import LEGS, cli_command

from a1_leg_fk.cli.echo import millimetres

DAMAGED = 400
ROW = re.compile(r"^(FR|FL|RR|RL) {2}(.{9})(.{9})(.{9}) +([-\d.]+|-   no message yet)$")


def test_an_absurd_coordinate_keeps_its_column() -> None:
    assert millimetres(0.1234) == "    123.4" and millimetres(-0.3) == "   -300.0"
    for absurd in (2.46e200, -1e300, float("inf"), float("nan"), 999.9999):
        assert len(millimetres(absurd)) == 9, millimetres(absurd)


@pytest.mark.slow
def test_echo_survives_damaged_foot_messages(processes, ros) -> None:
    process = processes.start([*cli_command(), "echo", "--interval", "0.5"])
    publishers = {
        leg: ros.node.create_publisher(
            PointStamped, f"foot_positions/{leg}", QoSProfile(depth=100)
        )
        for leg in LEGS
    }
    topic, rng = target_topic("FR"), random.Random(38)  # a PointStamped topic of the harness

    def good() -> None:
        for publisher in publishers.values():
            publisher.publish(
                point_bytes(ros.node.get_clock().now().nanoseconds, (0.1, 0.2, -0.3))
            )

    def table_shown() -> bool:
        good()
        return "-300.0" in processes.output(process)

    assert ros.spin_until(table_shown, 20.0), processes.output(process)
    kinds = (TRUNCATED, ABSURD_LENGTH, BIT_FLIPS, OTHER_TYPE)
    for count in range(DAMAGED):
        raw = damaged(rng.choice(kinds), topic, ros.node.get_clock().now().nanoseconds, rng)
        publishers[LEGS[count % 4]].publish(raw)
        ros.executor.spin_once(timeout_sec=0.002)
        if count % 25 == 0:
            good()
    ros.spin_for(1.0)
    good()
    ros.spin_for(1.0)
    output = processes.output(process)
    assert process.poll() is None, output[-3000:]
    rows = [line for line in output.splitlines() if line[:2] in LEGS]
    assert rows and all(ROW.match(line) for line in rows), [r for r in rows if not ROW.match(r)]
    assert (
        rows[-4:]
        == [  # the last table: the good messages after the damage (rates cut off)
            line for line in rows[-4:] if line[4:31] == "    100.0    200.0   -300.0"
        ]
    ), rows[-4:]
    assert processes.interrupt(process, timeout_s=10.0) == 0, output[-3000:]
    assert "Traceback" not in processes.output(process), processes.output(process)[-3000:]
