"""Property-based fuzzing of :class:`a1_leg_fk.tracking.FootTracker`, in process and through a
real node.

Every message goes both to the tracker and to :class:`ReferenceTracker`, a deliberately simple
model written here from the documented rules (not from the tracker's code):

- a message whose ``position`` length differs from ``name``'s is rejected, then one whose
  non-empty ``velocity`` length differs; then one naming a leg joint twice (under either naming);
- a message with no leg joint at all changes nothing; one whose leg joints are all NaN/inf is
  rejected;
- otherwise every finite position is merged (the last finite value per joint wins), and a foot is
  returned for every leg the message names, unless one of that leg's values in this message is
  not finite or one of its three joints has never had a finite value;
- a foot has a velocity when the message carries finite rates for all three joints of its leg
  (and J q_dot does not overflow).

Properties: ``update`` never raises and never returns NaN/inf; the merged state equals the
model's; every foot equals :meth:`Quadruped.fk` of the merged state for its leg (<= 1e-12 m); the
outcome counters add up to the messages sent.
"""

from __future__ import annotations

import array
import math
import random
from collections import Counter

import numpy as np
import pytest
from hostile_values import SPECIAL_VALUES, UNKNOWN_NAMES
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shared import PYBULLET_NAMES, UNITREE_NAMES

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.tracking import (
    ACCEPTED,
    ALL_POSITIONS_NON_FINITE,
    DUPLICATE_NAMES,
    MAX_REMEMBERED_UNKNOWN_NAMES,
    NO_LEG_JOINTS,
    POSITION_LENGTH_MISMATCH,
    REJECTIONS,
    VELOCITY_LENGTH_MISMATCH,
    FootTracker,
)

# The names (test/shared.py) are written from the naming conventions, independently of
# legs.joint_name_index.
SLOT_OF = {
    **{n: i for i, n in enumerate(PYBULLET_NAMES)},
    **{n: i for i, n in enumerate(UNITREE_NAMES)},
}

ROBOT = Quadruped.from_urdf()
TOTALS: Counter[str] = (
    Counter()
)  # messages fuzzed per test, reported by test_fuzz_totals_are_reported


class ReferenceTracker:
    """The simple model the tracker is checked against (see the module docstring)."""

    def __init__(self) -> None:
        self.state = [math.nan] * 12
        self.outcomes: Counter = Counter()
        self.messages = 0

    def update(self, names, positions, velocities) -> tuple[str, dict[int, tuple | None]]:
        """(outcome, {leg slot: expected velocity rates or None}) for one message."""
        self.messages += 1
        outcome, legs = self._update(list(names), list(positions), list(velocities))
        self.outcomes[outcome] += 1
        return outcome, legs

    def _update(self, names, positions, velocities):
        if len(positions) != len(names):
            return POSITION_LENGTH_MISMATCH, {}
        if velocities and len(velocities) != len(names):
            return VELOCITY_LENGTH_MISMATCH, {}
        known = [(i, SLOT_OF[n]) for i, n in enumerate(names) if n in SLOT_OF]
        if len({slot for _, slot in known}) != len(known):
            return DUPLICATE_NAMES, {}
        if not known:
            return NO_LEG_JOINTS, {}
        finite = [(i, slot) for i, slot in known if math.isfinite(positions[i])]
        if not finite:
            return ALL_POSITIONS_NON_FINITE, {}
        for i, slot in finite:
            self.state[slot] = positions[i]
        bad_legs = {slot // 3 for i, slot in known if not math.isfinite(positions[i])}
        legs = {}
        for leg in sorted({slot // 3 for _, slot in known} - bad_legs):
            if any(math.isnan(a) for a in self.state[3 * leg : 3 * leg + 3]):
                continue
            rates = (
                {slot: velocities[i] for i, slot in known if slot // 3 == leg}
                if velocities
                else {}
            )
            ordered = [rates.get(3 * leg + k, math.nan) for k in range(3)]
            legs[leg] = tuple(ordered) if all(math.isfinite(r) for r in ordered) else None
        return ACCEPTED, legs


def filled_state(state: list[float]) -> list[float]:
    return [0.0 if math.isnan(a) else a for a in state]


def check_message(
    tracker: FootTracker, model: ReferenceTracker, names, positions, velocities
) -> None:
    """Send one message to both; assert every per-message property."""
    feet = tracker.update(names, positions, velocities)
    outcome, legs = model.update(names, positions, velocities)
    assert tracker.last_outcome == outcome, (
        names[:20],
        list(positions)[:20],
        list(velocities)[:20],
    )
    # The merged state equals the model's (NaN where never known), bit for bit.
    for got, want in zip(tracker.angles, model.state):
        assert (math.isnan(got) and math.isnan(want)) or got == want
    assert [f.leg_slot for f in feet] == sorted(legs), (feet, legs)
    if not feet:
        return
    expected = ROBOT.fk(filled_state(model.state))
    jacobians = None
    for foot in feet:
        assert all(math.isfinite(v) for v in foot.position), foot
        assert max(abs(a - b) for a, b in zip(foot.position, expected[foot.leg_slot])) <= 1e-12, (
            foot
        )
        rates = legs[foot.leg_slot]
        if rates is None:
            assert foot.velocity is None, foot
            continue
        if jacobians is None:
            jacobians = ROBOT.jacobians(filled_state(model.state))
        with np.errstate(over="ignore", invalid="ignore"):
            want = jacobians[foot.leg_slot] @ np.array(rates)
            scale = float(np.abs(jacobians[foot.leg_slot]).sum() * max(abs(r) for r in rates))
        if foot.velocity is None:
            # Dropped only when J q_dot overflows (rates near 1e308).
            assert not np.all(np.isfinite(want)) or not math.isfinite(scale) or scale > 1e300, (
                foot,
                rates,
            )
            continue
        assert all(math.isfinite(v) for v in foot.velocity), foot
        assert np.max(np.abs(np.array(foot.velocity) - want)) <= 1e-12 + 1e-12 * scale, (
            foot,
            want,
            rates,
        )


def check_totals(tracker: FootTracker, model: ReferenceTracker) -> None:
    counts = tracker.counts
    assert counts.messages == model.messages
    assert sum(counts.outcomes.values()) == model.messages
    assert set(counts.outcomes) <= {ACCEPTED, NO_LEG_JOINTS, *REJECTIONS}
    assert +counts.outcomes == +model.outcomes
    assert len(counts.unknown_names) <= MAX_REMEMBERED_UNKNOWN_NAMES
    assert len(tracker.take_new_unknown_names()) <= MAX_REMEMBERED_UNKNOWN_NAMES


# --- strategies ----------------------------------------------------------------------------

values = st.one_of(
    st.floats(-4.0, 4.0),
    st.sampled_from(SPECIAL_VALUES),
    st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True),
)
name_pool = st.one_of(
    st.sampled_from(PYBULLET_NAMES),
    st.sampled_from(UNITREE_NAMES),
    st.sampled_from(UNKNOWN_NAMES),
    st.text(max_size=12),
)


@st.composite
def messages(draw) -> tuple[list[str], object, object]:
    kind = draw(st.sampled_from(["random", "random", "random", "partial", "full", "huge"]))
    rng = draw(st.randoms(use_true_random=False))
    if kind == "random":
        names = draw(st.lists(name_pool, max_size=16))
    elif kind == "partial":  # a few joints of one naming or the other, no duplicates
        naming = draw(st.sampled_from([PYBULLET_NAMES, UNITREE_NAMES]))
        names = rng.sample(naming, draw(st.integers(1, 11)))
    elif kind == "full":
        names = list(draw(st.sampled_from([PYBULLET_NAMES, UNITREE_NAMES])))
        rng.shuffle(names)
    else:  # up to 10,000 names: unknown ones (partly repeated) around a full set of leg joints
        count = draw(st.integers(12, 10_000))
        names = [f"extra_{rng.randrange(3 * count)}_joint" for _ in range(count - 12)] + list(
            PYBULLET_NAMES
        )
        if draw(st.booleans()):
            names.append(rng.choice(UNITREE_NAMES))  # one duplicate leg joint: rejected
        rng.shuffle(names)
    length = len(names)
    position_length = draw(st.sampled_from([length] * 6 + [0, length + 1, max(length - 1, 0)]))
    velocity_length = draw(st.sampled_from([0, 0, length, length, length + 1, max(length - 1, 0)]))
    if (
        length > 64
    ):  # drawing 10,000 floats one by one is slow; mix drawn specials into a seeded stream
        specials = draw(st.lists(values, min_size=1, max_size=8))
        positions = [
            rng.choice(specials) if rng.random() < 0.05 else rng.uniform(-3, 3)
            for _ in range(position_length)
        ]
        velocities = [
            rng.choice(specials) if rng.random() < 0.05 else rng.uniform(-20, 20)
            for _ in range(velocity_length)
        ]
    else:
        positions = draw(st.lists(values, min_size=position_length, max_size=position_length))
        velocities = draw(st.lists(values, min_size=velocity_length, max_size=velocity_length))
    # rclpy hands the node array.array('d') for float64[] fields; plain lists must work as well.
    if draw(st.booleans()):
        return names, array.array("d", positions), array.array("d", velocities)
    return names, positions, velocities


@st.composite
def interleaved_streams(draw) -> list[tuple[list[str], list[float], list[float]]]:
    """Two publishers (one per naming) each sending a fixed subset of the joints, alternating."""
    rng = draw(st.randoms(use_true_random=False))
    slots = list(range(12))
    rng.shuffle(slots)
    cut = draw(st.integers(1, 11))
    parts = [(sorted(slots[:cut]), PYBULLET_NAMES), (sorted(slots[cut:]), UNITREE_NAMES)]
    stream = []
    for step in range(draw(st.integers(2, 12))):
        part, naming = parts[step % 2] if draw(st.booleans()) else parts[(step + 1) % 2]
        positions = [
            draw(values) if draw(st.integers(0, 9)) == 0 else rng.uniform(-2, 2) for _ in part
        ]
        velocities = [rng.uniform(-5, 5) for _ in part] if draw(st.booleans()) else []
        stream.append(([naming[s] for s in part], positions, velocities))
    return stream


FUZZ_SETTINGS = settings(
    max_examples=400,
    deadline=None,
    suppress_health_check=[
        HealthCheck.too_slow,
        HealthCheck.data_too_large,
        HealthCheck.large_base_example,
    ],
)


def test_name_mapping_is_the_two_a1_namings():
    assert dict(ROBOT.name_to_slot) == SLOT_OF


@FUZZ_SETTINGS
@given(st.lists(messages(), min_size=1, max_size=25))
def test_random_message_sequences_match_the_reference_model(stream):
    tracker, model = FootTracker(ROBOT), ReferenceTracker()
    for names, positions, velocities in stream:
        check_message(tracker, model, names, positions, velocities)
    check_totals(tracker, model)
    TOTALS["hypothesis messages"] += len(stream)


@settings(FUZZ_SETTINGS, max_examples=200)
@given(interleaved_streams(), st.lists(messages(), max_size=5))
def test_interleaved_partial_publishers_merge_like_the_reference_model(stream, noise):
    tracker, model = FootTracker(ROBOT), ReferenceTracker()
    for names, positions, velocities in stream + noise + stream:
        check_message(tracker, model, names, positions, velocities)
    check_totals(tracker, model)
    TOTALS["hypothesis messages"] += 2 * len(stream) + len(noise)


def test_seeded_bulk_fuzz_20k_messages():
    """Plain random volume on top of hypothesis: 20,000 messages through one long-lived tracker."""
    rng = random.Random(20240611)
    pool = PYBULLET_NAMES + UNITREE_NAMES + UNKNOWN_NAMES
    tracker, model = FootTracker(ROBOT), ReferenceTracker()
    for _ in range(20_000):
        roll = rng.random()
        if roll < 0.5:
            names = list(rng.choice([PYBULLET_NAMES, UNITREE_NAMES]))
        elif roll < 0.8:
            names = rng.sample(rng.choice([PYBULLET_NAMES, UNITREE_NAMES]), rng.randint(1, 11))
        else:
            names = [rng.choice(pool) for _ in range(rng.randint(0, 14))]
        n = len(names)
        position_length = n if rng.random() < 0.95 else rng.choice([0, n + 1, max(n - 1, 0)])
        velocity_length = rng.choice([0, n, n, n]) if rng.random() < 0.97 else n + 2

        def value(spread: float) -> float:
            return (
                rng.choice(SPECIAL_VALUES) if rng.random() < 0.03 else rng.uniform(-spread, spread)
            )

        positions = array.array("d", (value(3.0) for _ in range(position_length)))
        velocities = array.array("d", (value(20.0) for _ in range(velocity_length)))
        check_message(tracker, model, names, positions, velocities)
    check_totals(tracker, model)
    assert tracker.counts.outcomes[ACCEPTED] > 10_000  # the stream is mostly good
    TOTALS["seeded messages"] += 20_000


def test_name_flood_keeps_memory_bounded():
    """50 messages of 10,000 fresh unknown names each: remembered names stay capped."""
    tracker, model = FootTracker(ROBOT), ReferenceTracker()
    for batch in range(50):
        names = [f"flood_{batch}_{i}" for i in range(10_000 - 12)] + PYBULLET_NAMES
        check_message(tracker, model, names, [0.1] * len(names), [])
    check_totals(tracker, model)
    assert len(tracker.counts.unknown_names) == MAX_REMEMBERED_UNKNOWN_NAMES
    TOTALS["seeded messages"] += 50


@pytest.mark.parametrize(
    ("names", "positions", "velocities", "outcome"),
    [
        ([], [], [], NO_LEG_JOINTS),
        ([""], [0.0], [], NO_LEG_JOINTS),
        (
            ["", ""],
            [0.0, 0.0],
            [],
            NO_LEG_JOINTS,
        ),  # repeated unknown names are ignored, not rejected
        (
            ["FR_upper_joint", "FR_thigh_joint"],
            [0.8, 0.8],
            [],
            DUPLICATE_NAMES,
        ),  # one joint, both namings
        (PYBULLET_NAMES, [math.nan] * 12, [], ALL_POSITIONS_NON_FINITE),
        (PYBULLET_NAMES, [0.1] * 12, [0.0] * 11, VELOCITY_LENGTH_MISMATCH),
        (PYBULLET_NAMES, [0.1] * 13, [], POSITION_LENGTH_MISMATCH),
        (PYBULLET_NAMES, [1e308] * 12, [1e308] * 12, ACCEPTED),
        (PYBULLET_NAMES, [5e-324] * 12, [-5e-324] * 12, ACCEPTED),
    ],
)
def test_edge_messages(names, positions, velocities, outcome):
    tracker, model = FootTracker(ROBOT), ReferenceTracker()
    check_message(tracker, model, names, positions, velocities)
    assert tracker.last_outcome == outcome
    check_totals(tracker, model)


def test_fuzz_totals_are_reported(capsys):
    """Prints how many messages the tests above fuzzed (visible with -s or in the report)."""
    with capsys.disabled():
        print(f"\nfuzzed FootTracker messages: {dict(TOTALS)}, total {sum(TOTALS.values())}")
