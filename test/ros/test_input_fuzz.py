"""Issue 38: every input topic of every node survives damaged messages, as a real process over
real DDS (the run and its checks: test/node_fuzz_run.py; the harness: test/node_fuzz.py; the long
run: ``make fuzz``, bench/fuzz_nodes.py).

Per node, one process; per input topic, damage of every kind in batches, each followed by good
input the node must answer; then a phase of unreadable messages only, after which the node's
``rejected_<topic>_malformed`` must have grown by exactly what its ``received_<topic>`` grew
(whatever a best-effort transport dropped), and a phase of readable damage only, after which it
must not have grown. Nothing non-finite is published, and SIGINT ends the node with exit 0 and no
traceback.
"""

from __future__ import annotations

import pytest
from fuzzed_nodes import fuzzed_nodes
from node_fuzz_run import CI_COUNTS, HEADER, run_node
from pybullet_reference import A1_URDF

pytestmark = pytest.mark.slow

NODES = fuzzed_nodes(A1_URDF.read_text())


@pytest.mark.parametrize("name", list(NODES))
def test_damaged_messages_on_every_input(name: str, processes, ros) -> None:
    run = run_node(processes, ros, NODES[name], CI_COUNTS, seed=38)
    print("\n" + "\n".join([HEADER, *run.lines()]))
    assert not run.failures, (run.failures, run.output[-3000:])
    for row in run.rows:  # every good input after a batch answered, many unreadable ones sent
        assert row.asked and row.answered == row.asked, row
        assert row.unreadable >= row.sent // 4, row
