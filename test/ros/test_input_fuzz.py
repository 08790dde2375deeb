"""Issue 38: every input topic of every node survives damaged messages, as a real process over
real DDS (the harness: test/node_fuzz.py; the long run: ``make fuzz``, bench/fuzz_nodes.py).

Per node, one process; per input topic, messages damaged in ways whose outcome is known by
construction (cut short, a length field of gigabytes: unreadable; bytes appended, well-formed
absurd values: readable), each batch followed by good input the node must answer; then the node's
``rejected_<topic>_malformed`` in /diagnostics must count the unreadable messages sent (no more;
at least 85 %: best-effort inputs lose a few of a burst on a loaded machine). Then bit
flips and another type's bytes (outcome not known beforehand): the counts grow by at most what
was sent. Nothing non-finite is published, and SIGINT ends the node with exit 0 and no traceback.
"""

from __future__ import annotations

import pytest
from fuzzed_nodes import fuzzed_nodes
from node_fuzz import KNOWN, UNKNOWN, NodeFuzz
from pybullet_reference import A1_URDF

pytestmark = pytest.mark.slow

PER_TOPIC = {"known": 150, "unknown": 60}
"""Damaged messages per input topic in CI (robot_description: a fifth, paced)."""
NODES = fuzzed_nodes(A1_URDF.read_text())


def count_for(topic: str, kind: str) -> int:
    share = 5 if topic == "robot_description" else 1
    return PER_TOPIC[kind] // share


@pytest.mark.parametrize("name", list(NODES))
def test_damaged_messages_on_every_input(name: str, processes, ros) -> None:
    spec = NODES[name]
    process = processes.start(spec.command)
    fuzz = NodeFuzz(ros, spec, seed=38)
    assert fuzz.wait_connected(), processes.output(process)
    missed = []
    for each in spec.inputs:
        missed += fuzz.send(each, KNOWN, count_for(each.topic, "known"))
    assert not missed, (missed, processes.output(process)[-3000:])
    unreadable = {topic: tally.unreadable for topic, tally in fuzz.tallies.items()}
    assert fuzz.counts_reach(unreadable), (unreadable, fuzz.rejected_values())
    for tally in fuzz.tallies.values():  # every kind was sent, and unreadable ones were many
        assert all(tally.sent[kind] for kind in KNOWN), tally.sent
        assert tally.unreadable >= sum(tally.sent.values()) // 3, tally.sent
    before = {topic: fuzz.rejected(topic) for topic in fuzz.tallies}
    for each in spec.inputs:
        missed += fuzz.send(each, UNKNOWN, count_for(each.topic, "unknown"))
    assert not missed, (missed, processes.output(process)[-3000:])
    seen = fuzz.diagnostics_received
    assert ros.spin_until(lambda: fuzz.diagnostics_received > seen + 1, 10.0)
    for topic, tally in fuzz.tallies.items():
        grown = fuzz.rejected(topic) - before[topic]
        assert 0 <= grown <= tally.unknown, (topic, grown, tally.sent)
    print(
        f"\n{name}: "
        + "; ".join(
            f"{topic} sent {sum(t.sent.values())} ({t.unreadable} unreadable, {t.unknown} "
            f"flipped/other type), rejected {fuzz.rejected(topic)}"
            for topic, t in fuzz.tallies.items()
        )
        + f"; {fuzz.outputs} outputs"
    )
    assert not fuzz.non_finite, fuzz.non_finite[:5]
    assert process.poll() is None, processes.output(process)[-3000:]
    assert processes.interrupt(process, timeout_s=10.0) == 0, processes.output(process)[-3000:]
    assert "Traceback" not in processes.output(process), processes.output(process)[-3000:]
