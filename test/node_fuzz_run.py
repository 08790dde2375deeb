"""One node's whole fuzz run and its checks (issue 38), for the CI test
(test/ros/test_input_fuzz.py) and ``make fuzz`` (bench/fuzz_nodes.py); the harness:
test/node_fuzz.py.

The run, per node, one process:

1. per input topic, :data:`~node_fuzz.KNOWN` damage in batches, good input after each batch;
2. per input topic, :data:`~node_fuzz.UNKNOWN` damage (bit flips, another type's bytes), the same;
3. exact counts, independent of delivery: every topic gets only unreadable messages (no good input
   in between), then the node's ``rejected_<topic>_malformed`` must have grown by exactly what its
   ``received_<topic>`` grew (and received no more than was sent); then only readable damage
   (bytes appended, absurd values): ``rejected_<topic>_malformed`` must not grow;
4. good input answered once more; nothing non-finite published; the node alive; SIGINT: exit 0,
   no traceback.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from node_fuzz import KNOWN, UNKNOWN, FuzzedNode, NodeFuzz


@dataclass(frozen=True)
class Counts:
    """Damaged messages per input topic for each part of the run (robot_description gets a
    ``description_share``-th: it is paced)."""

    known: int
    unknown: int
    exact: int  # each of the two exact phases
    description_share: int = 5

    @property
    def total(self) -> int:
        return self.known + self.unknown + 2 * self.exact

    def of(self, topic: str) -> Counts:
        share = self.description_share if topic == "robot_description" else 1
        return Counts(self.known // share, self.unknown // share, self.exact // share, 1)


CI_COUNTS = Counts(known=120, unknown=50, exact=20)
"""Damaged messages per input topic in CI (robot_description: a fifth, paced)."""


@dataclass
class TopicRow:
    """One input topic's outcome."""

    topic: str
    sent: int = 0
    unreadable: int = 0  # sent unreadable by construction
    rejected: int = 0  # rejected_<topic>_malformed at the end
    asked: int = 0  # good inputs after a batch of damage
    answered: int = 0
    exact: str = ""  # the unreadable phase: "received R, rejected R"


@dataclass
class NodeRun:
    """One node's outcome: its topics' rows and every failed check."""

    name: str
    rows: list[TopicRow] = field(default_factory=list)
    exact: dict[str, str] = field(default_factory=dict)  # per topic: the unreadable phase
    failures: list[str] = field(default_factory=list)
    crashed: bool = False
    traceback: bool = False
    output: str = ""

    def lines(self) -> list[str]:
        """The table's rows of this node."""
        return [
            f"{self.name:<26} {row.topic:<18} {row.sent:>6} {row.unreadable:>6} {row.rejected:>8} "
            f"{row.answered:>4}/{row.asked:<4} {int(self.crashed):>5} {int(self.traceback):>5}  "
            f"{row.exact}"
            for row in self.rows
        ]


HEADER = (
    f"{'node':<26} {'topic':<18} {'sent':>6} {'unread':>6} {'rejected':>8} {'answered':>9} "
    f"{'crash':>5} {'trace':>5}  exact phase (received = rejected)"
)


def run_node(processes, probe, spec: FuzzedNode, counts: Counts, seed: int) -> NodeRun:
    """Fuzz ``spec``'s node (started with ``processes``, driven from ``probe``) with
    ``counts``; every check that failed is in the result's ``failures``.
    """
    process = processes.start(spec.command, env=spec.env)
    fuzz = NodeFuzz(probe, spec, seed)
    run = NodeRun(spec.name)
    if not fuzz.wait_connected():
        run.failures.append("no answer to good input at the start")
    else:
        _damage(fuzz, spec, counts, run)
    run.failures += [f"non-finite output {value}" for value in fuzz.non_finite[:5]]
    for topic, tally in fuzz.tallies.items():
        sent, rejected = sum(tally.sent.values()), fuzz.rejected(topic)
        if not 0 <= rejected <= tally.unreadable + tally.unknown:
            run.failures.append(f"{topic}: {rejected} rejected of {tally.sent}")
        row = TopicRow(topic, sent, tally.unreadable, rejected, tally.asked, tally.answered)
        row.exact = run.exact.get(topic, "")
        run.rows.append(row)
    run.crashed = process.poll() is not None
    code = processes.interrupt(process, timeout_s=10.0) if not run.crashed else process.poll()
    run.output = processes.output(process)
    run.traceback = "Traceback" in run.output
    if run.crashed or code != 0:
        run.failures.append(f"exit code {code} (crashed: {run.crashed})")
    if run.traceback:
        run.failures.append("a traceback in the output")
    return run


def _damage(fuzz: NodeFuzz, spec: FuzzedNode, counts: Counts, run: NodeRun) -> None:
    """Parts 1 to 3 of the run (module docstring)."""
    for kinds, part in ((KNOWN, "known"), (UNKNOWN, "unknown")):
        for each in spec.inputs:
            run.failures += fuzz.send(each, kinds, getattr(counts.of(each.topic), part))
    for must_reject in (True, False):
        before = fuzz.settled()
        sent = {each.topic: sum(fuzz.tallies[each.topic].sent.values()) for each in spec.inputs}
        for each in spec.inputs:
            phase_kinds = each.unreadable if must_reject else each.readable
            fuzz.send_only(each, phase_kinds, counts.of(each.topic).exact)
        after = fuzz.settled()
        if before is None or after is None:
            run.failures.append("/diagnostics did not settle")
            return
        for each in spec.inputs:
            topic = each.topic
            received = after[topic][0] - before[topic][0]
            rejected = after[topic][1] - before[topic][1]
            phase = sum(fuzz.tallies[topic].sent.values()) - sent[topic]
            wanted = received if must_reject else 0
            if rejected != wanted or not 0 < received <= phase:
                run.failures.append(
                    f"{topic}: {'un' if must_reject else ''}readable only: sent {phase}, "
                    f"received {received}, rejected {rejected} (wanted {wanted})"
                )
            if must_reject:
                run.exact[topic] = f"received {received}, rejected {rejected}"
    if not fuzz.good_input_answered(every=True):
        run.failures.append("no answer to good input at the end")
