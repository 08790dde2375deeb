"""Where ``foot_fk_node``'s time per JointState goes, stage by stage, beside the raw floor's
callback, in one process (no DDS: the publishers have no reader).

Run: ``.venv/bin/python bench/node_stages.py`` (about 30 s). The node (``FootFkNode``, its
defaults: dynamic forces, the contact filter) and the floor's callback (``throughput_roles.py
baseline``: the stamp read from the bytes, the same pre-serialized messages published) are fed
the benchmark generator's 250 serialized JointStates (12 joints, positions and velocities; with
efforts too in the second half), one after the other, stamps 1 ms apart. Per message, median of
interleaved runs:

- ``decode``: the JointState's fields from its bytes (``JointStateDecoder``, ``doubles``);
- ``track``: ``FootTracker.update`` (the JointState rules and the four feet's FK);
- ``forces + contacts``: ``ForcePass.message`` (the efforts by name, the momentum observer, the
  contact filter);
- ``publish``: the node's outputs (``FootOutput.feet`` and ``.forces``: 9 messages, 13 with
  efforts);
- ``callback``: the whole subscription callback (the guarded read, then ``_on_joint_state``);
  ``floor``: the floor's whole callback
  (``throughput_roles.floor_callback``, publishing with ``Publisher.publish``), and the same
  publishing as the node does (``raw_publish``: without rclpy's per-call wrapper).

The callback's excess over the floor is the node's own work; over DDS each microsecond of it
costs more (the process wakes with cold caches at 1 kHz): ``bench/node_cost.py`` measures that.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

from common import machine, median_seconds_per_call, shared

DOMAIN, DOMAIN_LOCK = shared.claim_domain_id()  # held until the process ends
os.environ["ROS_DOMAIN_ID"] = str(DOMAIN)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"

import rclpy  # noqa: E402 (after the domain)
from rclpy.node import Node  # noqa: E402
from rclpy.serialization import serialize_message  # noqa: E402
from throughput_roles import _poses, floor_callback  # noqa: E402

from a1_leg_fk.ros.foot_fk_node import FootFkNode  # noqa: E402
from a1_leg_fk.tracking import leg_feet  # noqa: E402
from a1_leg_fk.wire.joint_state import doubles  # noqa: E402

MESSAGES = 250


def serialized_stream(efforts: bool) -> list[bytes]:
    """The generator's messages, serialized, stamped 1 ms apart from 1000 s."""
    stream = []
    for index, msg in enumerate(_poses(efforts)):
        msg.header.stamp.sec, msg.header.stamp.nanosec = 1000, index * 1_000_000
        stream.append(serialize_message(msg))
    return stream


def cycling(call: Callable[[bytes], object], stream: list[bytes]) -> Callable[[], None]:
    """``call`` on the stream's next message at each call."""
    position = [0]

    def next_message() -> None:
        call(stream[position[0] % MESSAGES])
        position[0] += 1

    return next_message


def stages(node: FootFkNode, stream: list[bytes]) -> dict[str, Callable[[], object]]:
    """The node's stages, each on its own (its inputs prepared once from the stream)."""
    decoder, tracker, forces, output = (
        node._decoder,
        node._tracker,
        node._forces,
        node._output,
    )
    assert forces is not None  # publish_forces is on by default
    fields = decoder.fields(stream[0])
    names = decoder.names
    order = fields.order
    positions, velocities = doubles(fields.positions, order), doubles(fields.velocities, order)
    efforts = doubles(fields.efforts, order) if fields.efforts else ()
    feet = tracker.update(names, positions, velocities, efforts)
    joints = (
        tracker.angles,
        tracker.rates,
        forces.message_efforts(names, efforts) if efforts else None,
    )
    legs = leg_feet(feet)
    clock = [0]

    def decode() -> None:
        found = decoder.fields(stream[0])
        doubles(found.positions, order), doubles(found.velocities, order)
        if found.efforts:
            doubles(found.efforts, order)

    def forces_and_contacts() -> None:
        clock[0] += 1_000_000
        forces.message(clock[0], joints, legs, node._imu)

    result = forces.message(clock[0], joints, legs, node._imu)
    assert efforts or all(math.isnan(f) for f, _, _ in result.forces), "no forces without efforts"

    def publish() -> None:
        output.feet(feet, 1000, 0, True)
        output.forces(result.forces, result.normals, result.probabilities, 1000, 0)

    return {
        "decode": decode,
        "track": lambda: tracker.update(names, positions, velocities, efforts),
        "forces + contacts": forces_and_contacts,
        "publish": publish,
    }


def main() -> None:
    print(machine())
    rclpy.init()
    nodes = [FootFkNode() for _ in range(4)]  # each timed function its own state
    floor_node = Node("bench_floor_callback")
    try:
        for efforts, (node, staged) in zip((False, True), (nodes[:2], nodes[2:]), strict=True):
            stream = serialized_stream(efforts)
            prefix = "efforts/" if efforts else "plain/"
            floors = {
                name: floor_callback(floor_node, [efforts], raw, f"{prefix}{name}/")
                for name, raw in (("floor", False), ("floor_raw", True))
            }
            timed: dict[str, Callable[[], object]] = {
                "callback": cycling(node._inputs.callbacks["joint_states"], stream),
                **stages(staged, stream),
                "floor": cycling(floors["floor"], stream),
                "floor, published raw": cycling(floors["floor_raw"], stream),
            }
            runs = median_seconds_per_call(timed)
            what = "with efforts" if efforts else "without efforts"
            print(f"\n  one JointState {what:<16} {'us':>8}")
            for name, seconds in runs.items():
                print(f"  {name:<31} {seconds * 1e6:8.1f}")
            for floor in ("floor", "floor, published raw"):
                excess = runs["callback"] - runs[floor]
                print(
                    f"  the node's own work beside the {floor}: {excess * 1e6:.1f} us per "
                    f"message ({runs['callback'] / runs[floor]:.2f}x its callback)"
                )
    finally:
        for each in [*nodes, floor_node]:
            each.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
