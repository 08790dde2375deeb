"""The node fuzz's damage whose outcome is known by construction (test/node_fuzz.py: ``KNOWN``),
checked offline against the nodes' own readers of each topic: every message cut short or given a
length field of gigabytes cannot be read, also once padded with zeros to a multiple of 4 bytes as
Fast DDS delivers it; every message with bytes appended or absurd values can (a LowState of
either Unitree layout, a fixed size: cut short or absurd values, :attr:`InputTopic.kinds`).
The live fuzz's exact counts (test/ros/test_input_fuzz.py) rest on this.
"""

from __future__ import annotations

import random

import pytest
from fuzzed_nodes import fuzzed_nodes, lowstate_topic
from node_fuzz import KNOWN, InputTopic, damaged
from pybullet_reference import A1_URDF

from a1_leg_fk.wire.unitree_types import GO_LOW_STATE, LEGGED_LOW_STATE

PER_KIND = 200
TOPICS = {
    each.topic: each for node in fuzzed_nodes(A1_URDF.read_text()).values() for each in node.inputs
} | {msgtype: lowstate_topic(msgtype) for msgtype in (GO_LOW_STATE, LEGGED_LOW_STATE)}


def readable(topic: InputTopic, raw: bytes) -> bool:
    try:
        topic.read(raw)
    except Exception:  # noqa: BLE001 (whatever the node's reader raises: unreadable)
        return False
    return True


@pytest.mark.parametrize("name", sorted(TOPICS))
def test_known_damage_is_read_as_constructed(name: str) -> None:
    topic, rng = TOPICS[name], random.Random(38)
    wrong = []
    for kind in (kind for kind in KNOWN if kind in topic.kinds):
        for _ in range(PER_KIND):
            raw = damaged(kind, topic, 1_700_000_000_123_456_789, rng)
            as_delivered = raw + bytes(-len(raw) % 4)
            if readable(topic, as_delivered) == (kind in topic.unreadable):
                wrong.append(f"{kind}: {len(raw)} bytes {raw[:24].hex()}...")
    assert not wrong, (len(wrong), wrong[:5])


def test_an_unpadded_cut_is_what_the_rule_avoids() -> None:
    """Cut 1 to 3 bytes short, a PointStamped is read once padded (why TRUNCATED loses 4)."""
    topic = TOPICS["foot_targets/FR"]
    good = topic.good(1_700_000_000_123_456_789)
    assert not readable(topic, good[:-4])
    assert all(readable(topic, good[:-cut] + bytes(cut)) for cut in (1, 2, 3))
