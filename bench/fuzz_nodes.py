"""The long fuzz of the nodes' inputs (issue 38; ``make fuzz``, after bench/fuzz_recordings.py):
every input topic of ``foot_fk_node``, ``leg_odometry_node`` and ``foot_ik_node`` (joint_states,
imu, gait_phase, robot_description, foot_targets/<leg>) gets 2,000 damaged messages (truncated,
absurd lengths, bytes appended, absurd values, bit flips, another type's bytes), interleaved with
good input, each node a real process over real DDS; and ``foot_fk_node`` and
``leg_odometry_node`` with ``input: unitree_lowstate`` on ``lowstate``, once per Unitree layout
(``unitree_go``, and ``unitree_legged_msgs`` as a ROS 2 workspace defines it), each message
package built with colcon first as the CI test builds it (test/unitree_workspace.py, about a
minute per package); with the CI test's run and checks (test/node_fuzz_run.py, harness
test/node_fuzz.py): every good input after a batch answered (``leg_odometry_node`` on
``lowstate``: as many odometry messages as good LowStates sent), the counts exact (a phase of
unreadable messages only: ``rejected_<topic>_malformed`` grows by what ``received_<topic>``
grows; one of readable damage only: it does not grow), nothing non-finite published, exit 0 on
SIGINT without a traceback.

Run: ``.venv/bin/python bench/fuzz_nodes.py [--per-topic 2000] [--seed 38] [--node NAME]``
(about 9 minutes). Prints one row per node and topic; exit 1 if any check failed.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import tempfile
import time
from pathlib import Path

from common import machine

# conftest first: it claims a free ROS domain before rclpy is imported
from conftest import Processes, RosProbe
from fuzzed_nodes import LOWSTATE_NODES, fuzzed_nodes, lowstate_name
from node_fuzz import FuzzedNode
from node_fuzz_run import HEADER, Counts, run_node
from pybullet_reference import A1_URDF
from unitree_workspace import build, load_here

from a1_leg_fk.wire.unitree_types import GO_LOW_STATE, LEGGED_LOW_STATE

LOWSTATE_RUNS = {
    lowstate_name(executable, msgtype): (executable, msgtype)
    for executable in LOWSTATE_NODES
    for msgtype in (GO_LOW_STATE, LEGGED_LOW_STATE)
}
"""The LowState runs, by name: the node and the layout it reads."""


def counts(per_topic: int) -> Counts:
    """``per_topic`` damaged messages per topic: 60 % known, 25 % unknown, 7.5 % each exact
    phase.
    """
    exact = per_topic * 3 // 40
    unknown = per_topic // 4
    return Counts(per_topic - unknown - 2 * exact, unknown, exact, description_share=1)


def lowstate_nodes(folder: Path, names: list[str]) -> dict[str, FuzzedNode]:
    """The LowState runs among ``names``, their message packages built in ``folder`` and loaded
    into this process (to publish their messages raw)."""
    runs = {name: LOWSTATE_RUNS[name] for name in names if name in LOWSTATE_RUNS}
    packages = tuple(dict.fromkeys(msgtype.split("/")[0] for _, msgtype in runs.values()))
    if not packages:
        return {}
    environments = build(folder, packages)
    nodes = {}
    for name, (executable, msgtype) in runs.items():
        package = msgtype.split("/")[0]
        load_here(environments[package])
        message = importlib.import_module(f"{package}.msg").LowState
        nodes[name] = LOWSTATE_NODES[executable](msgtype, message, environments[package])
    return nodes


def main() -> int:
    nodes = fuzzed_nodes(A1_URDF.read_text())
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--per-topic", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=38)
    parser.add_argument("--node", choices=sorted([*nodes, *LOWSTATE_RUNS]), action="append")
    options = parser.parse_args()
    print(machine())
    started, failed = time.perf_counter(), []
    lines = [HEADER]
    names = options.node or [*nodes, *LOWSTATE_RUNS]
    with tempfile.TemporaryDirectory(prefix="a1_leg_fk_fuzz_nodes_") as folder:
        nodes |= lowstate_nodes(Path(folder), names)
        print(f"message packages built: {time.perf_counter() - started:.0f} s", flush=True)
        for name in names:
            processes, probe = Processes(Path(folder)), RosProbe()
            try:
                run = run_node(
                    processes, probe, nodes[name], counts(options.per_topic), options.seed
                )
            finally:
                probe.close()
                processes.stop_all()
            lines += run.lines()
            print(f"{name}: {time.perf_counter() - started:.0f} s", flush=True)
            for row in run.rows:
                if row.answered != row.asked:
                    run.failures.append(f"{row.topic}: {row.answered}/{row.asked} answered")
            failed += [f"{name}: {failure}" for failure in run.failures]
            if run.failures:
                print(run.output[-3000:])
    print("\n".join(lines))
    print("\n".join(f"FAILED {line}" for line in failed) or "every check passed")
    print(f"wall time: {time.perf_counter() - started:.0f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
