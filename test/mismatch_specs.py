"""The mismatch family's runs by name: what each simulated robot changes from its URDF
(:class:`Mismatch`, see test/mismatch_runs.py for how each is simulated) and which runs were tuned
on and which are held out.

Kept apart from test/mismatch_runs.py: the cache names each run by a hash of the simulation's
sources and of that run's own spec, so adding a run (or moving one between tuned and held out)
simulates only the new one.
"""

from __future__ import annotations

from dataclasses import dataclass, replace


@dataclass(frozen=True)
class Mismatch:
    """How the simulated robot differs from its URDF (see the module text): joint friction
    ``damping`` [N m s/rad] and ``coulomb`` [N m] on every joint, ``thigh_mass`` and
    ``calf_mass`` fractions added, ``payload_kg`` at ``payload_at`` [m, root frame], the efforts
    reported times ``torque_scale`` and ``latency_s`` [s] late.
    """

    damping: float = 0.0
    coulomb: float = 0.0
    thigh_mass: float = 0.0
    calf_mass: float = 0.0
    payload_kg: float = 0.0
    payload_at: tuple[float, float, float] = (0.0, 0.0, 0.0)
    torque_scale: float = 1.0
    latency_s: float = 0.0


@dataclass(frozen=True)
class MismatchSpec:
    """One run: ``base`` names the contact family's run (robot, gait, motors), ``mismatch`` what
    differs, ``gait_s`` [s] how long the gait lasts."""

    base: str
    mismatch: Mismatch
    gait_s: float = 8.0


A1_FIGURES = Mismatch(damping=0.01, coulomb=0.2)
"""unitree_ros' a1.urdf ``<dynamics>`` on every joint."""
GO2_FIGURES = Mismatch(damping=0.1, coulomb=0.2)
"""unitree_mujoco's go2.xml joint ``damping`` and ``frictionloss``."""
EXACT = ("a1_trot_fast", "a1_trot_slow", "a1_trot_turn", "a1_walk", "go2_trot", "go2_walk")
"""Gaits simulated also without a mismatch: the exact robot's figures on the same trot."""
SPECS_MISMATCH = {
    **{f"{name}=exact": MismatchSpec(name, Mismatch()) for name in EXACT},
    "a1_trot_fast+friction": MismatchSpec("a1_trot_fast", Mismatch(damping=0.1, coulomb=0.4)),
    "a1_walk+heavy_legs": MismatchSpec(
        "a1_walk", Mismatch(damping=0.05, coulomb=0.2, thigh_mass=0.15, calf_mass=0.25)
    ),
    "go2_trot+friction_heavy": MismatchSpec(
        "go2_trot", Mismatch(damping=0.2, coulomb=0.6, thigh_mass=0.1, calf_mass=0.25)
    ),
    "a1_trot_turn+light_legs": MismatchSpec(
        "a1_trot_turn", Mismatch(damping=0.2, coulomb=0.6, thigh_mass=-0.1, calf_mass=-0.1)
    ),
    "a1_trot_fast+payload": MismatchSpec(
        "a1_trot_fast", replace(A1_FIGURES, payload_kg=3.0, payload_at=(0.05, 0.03, 0.03))
    ),
    "a1_trot_slow+scale_latency": MismatchSpec(
        "a1_trot_slow", Mismatch(damping=0.1, coulomb=0.3, torque_scale=0.9, latency_s=0.003)
    ),
    "go2_walk+payload_scale": MismatchSpec(
        "go2_walk",
        replace(
            GO2_FIGURES,
            payload_kg=2.0,
            payload_at=(-0.04, -0.02, 0.03),
            torque_scale=1.1,
            latency_s=0.002,
        ),
    ),
    "a1_trot_turn+everything": MismatchSpec(
        "a1_trot_turn",
        Mismatch(0.2, 0.6, 0.25, 0.25, 3.0, (0.04, -0.03, 0.02), 1.1, 0.003),
    ),
    "go2_trot+scale_latency": MismatchSpec(
        "go2_trot", replace(GO2_FIGURES, torque_scale=1.07, latency_s=0.002)
    ),
}
"""The family, by name (``BASE=exact`` or ``BASE+WHAT``)."""
TUNED = (
    "a1_trot_fast+friction",
    "a1_walk+heavy_legs",
    "go2_trot+friction_heavy",
    "a1_trot_turn+light_legs",
    "a1_trot_slow+scale_latency",
)
"""Friction and leg masses: what the corrections were tuned on; and the slow trot's scale and
latency, held out until its failure was diagnosed (the contact filter's force noise tried on it,
docs/forces.md), which makes it a tuned run."""
HELD_OUT = (
    "a1_trot_fast+payload",
    "go2_walk+payload_scale",
    "a1_trot_turn+everything",
    "go2_trot+scale_latency",
)
"""Whole kinds never looked at while tuning: payloads, torque scales, latencies (the Go2's trot
x1.07 and 2 ms late added as the slow trot's became tuned; the Go2's walk)."""
