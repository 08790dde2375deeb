"""``make mutate``: plausible bugs put into the estimation and kinematics code one at a time, each
in a scratch copy of the tree, the fast test subset (:data:`FAST_SUBSET`) run after each; a
mutation the subset does not fail *survives*. Prints the kill table (mutation, the first test
that failed, seconds) and exits 1 if any survives, 2 if the tree itself fails the subset or a
mutation's text is not found exactly once (a refactor must not silently make one a no-op).

    python test/mutations.py [--jobs N] [--only NAME ...] [--list]

The tree is copied (without ``.git``, virtual environments and caches) once per job into a
temporary folder; each mutation is applied there, the subset run with ``PYTHONPATH`` the copy,
and the file restored. The real files are never touched.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from queue import Queue

ROOT = Path(__file__).resolve().parent.parent
FAST_SUBSET = (
    "test/estimation/test_state_filter.py",
    "test/estimation/test_state_filter_motion.py",
    "test/estimation/test_filter_model.py",
    "test/estimation/test_momentum_observer.py",
    "test/estimation/test_leg_scales.py",
    "test/estimation/test_contact_filter.py",
    "test/estimation/test_contact_estimator.py",
    "test/estimation/test_leg_odometry.py",
    "test/estimation/test_leg_order.py",
    "test/estimation/test_foot_ground.py",
    "test/estimation/test_foot_jolt.py",
    "test/estimation/test_foot_rise.py",
    "test/estimation/test_ground.py",
    "test/estimation/test_touchdown_gate.py",
    "test/estimation/test_ground_walks.py",
    "test/gait/test_gait_edges.py",
    "test/estimation/test_pooled_rise.py",
    "test/estimation/test_load_edges.py",
    "test/estimation/test_stance_edges.py",
    "test/estimation/test_contact_smoother.py",
    "test/estimation/test_forced_stance.py",
    "test/estimation/test_swing_force.py",
    "test/recording/test_lowstate.py::test_the_imu_quaternion_is_read_w_first",
)
"""The tests every mutation must fail (about a minute on two idle cores): no simulated family,
no ROS nodes."""
RUN_TIMEOUT_S = 600.0
"""[s] A subset run longer than this (a mutation that hangs a loop) counts as killed by it."""
IGNORED = shutil.ignore_patterns(
    ".git", ".venv", "venv", "__pycache__", ".mypy_cache", ".ruff_cache", ".pytest_cache",
    "build", "install", "log", "*.egg-info", "bench",
)  # fmt: skip


@dataclass(frozen=True)
class Mutation:
    """One bug: in ``path`` (relative to the tree) the text ``old``, found exactly once,
    replaced by ``new``."""

    name: str
    path: str
    old: str
    new: str


MUTATIONS = (
    Mutation(
        "gyro sign flipped in the filter's propagation",
        "a1_leg_fk/estimation/state_filter.py",
        "((gyro[0] - bx) * dt, (gyro[1] - by) * dt, (gyro[2] - bz) * dt)",
        "((bx - gyro[0]) * dt, (by - gyro[1]) * dt, (bz - gyro[2]) * dt)",
    ),
    Mutation(
        "accelerometer bias dropped from the propagation",
        "a1_leg_fk/estimation/state_filter.py",
        "specific_force[0] - cx, specific_force[1] - cy, specific_force[2] - cz",
        "specific_force[0], specific_force[1], specific_force[2]",
    ),
    Mutation(
        "rolling radius 0 in the stance foot's velocity",
        "a1_leg_fk/estimation/leg_motion.py",
        "cx, cy, cz = radius * down[0], radius * down[1], radius * down[2]",
        "cx, cy, cz = 0.0, 0.0, 0.0",
    ),
    Mutation(
        "contact filter's force evidence x 0",
        "a1_leg_fk/estimation/contact_filter.py",
        "push = clip_odds((force - model.force_half_n) / model.force_scale_n, limit, limit)",
        "push = clip_odds(0.0 * force / model.force_scale_n, limit, limit)",
    ),
    Mutation(
        "the force's fade of a foot's speed off",
        "a1_leg_fk/estimation/contact_filter.py",
        "fades[leg] = 1.0 - max(press, 0.0) / limit",
        "fades[leg] = 1.0",
    ),
    Mutation(
        "the force's fade from even odds, without the swing feet's RMS force as its margin",
        "a1_leg_fk/estimation/contact_filter.py",
        "margin += self.swing_force.update(dt_s, forces, [not on for on in standing])",
        "self.swing_force.update(dt_s, forces, [not on for on in standing])",
    ),
    Mutation(
        "the swing feet's force window's edge exact (a rounded stamp moves a sample across it)",
        "a1_leg_fk/estimation/swing_force.py",
        "EDGE_S = 1e-6",
        "EDGE_S = 0.0",
    ),
    Mutation(
        "a forced foot's smoothed stance begins before the filter's",
        "a1_leg_fk/estimation/contact_smoother.py",
        "return filter_touchdowns(kept, filtered, rows.forced, before), filtered",
        "return kept, filtered",
    ),
    Mutation(
        "a forced foot's lone stance blip in a swing kept",
        "a1_leg_fk/estimation/forced_stance.py",
        "if short and alone and forced[first:end, leg].all():",
        "if False:",
    ),
    Mutation(
        "the unloading ramp carries a sample at one standard error",
        "a1_leg_fk/estimation/load_edges.py",
        "RAMP_CONFIDENCE = 1.5",
        "RAMP_CONFIDENCE = 1.0",
    ),
    Mutation(
        "a forced foot whose force says swing keeps its low-and-still stance",
        "a1_leg_fk/estimation/contact_filter.py",
        "pushes[leg], caps[leg] = push, 0.0 if push < 0.0 else weak",
        "pushes[leg], caps[leg] = push, weak",
    ),
    Mutation(
        "contact filter's speeds against every low foot, not the feet that stood",
        "a1_leg_fk/estimation/kinematic_evidence.py",
        "references = _references(velocities, (low, stepped), standing, forced)",
        "references = _references(velocities, (low, stepped), [False] * LEGS, forced)",
    ),
    Mutation(
        "a landed foot with a force still called swing by its height",
        "a1_leg_fk/estimation/kinematic_evidence.py",
        "rise = math.nan if forced[leg] and rise != math.inf else rise",
        "rise = math.nan if forced[leg] else rise",
    ),
    Mutation(
        "contact filter's rise above a foot's own foothold ignored",
        "a1_leg_fk/estimation/kinematic_evidence.py",
        "if x > rise < 0.0 or landed:",
        "if x > rise < -math.inf or landed:",
    ),
    Mutation(
        "a landed foot's height above the others still says swing",
        "a1_leg_fk/estimation/kinematic_evidence.py",
        "if x > rise < 0.0 or landed:",
        "if x > rise < 0.0:",
    ),
    Mutation(
        "no rigid feet's rule: the fixed even-odds height everywhere",
        "a1_leg_fk/estimation/kinematic_evidence.py",
        "if not (rigid and half < model.height_half_m):",
        "if not (rigid and half < 0.0):",
    ),
    Mutation(
        "feet that give taken for rigid",
        "a1_leg_fk/estimation/kinematic_evidence.py",
        "rigid = rise_spread_m < model.rigid_rise_share * model.rise_half_m",
        "rigid = rise_spread_m == rise_spread_m",
    ),
    Mutation(
        "a landed foot below the fixed even-odds height rescued from the rigid feet's rule",
        "a1_leg_fk/estimation/kinematic_evidence.py",
        "landed = x < 0.0 < rise == math.inf and height >= fixed",
        "landed = x < 0.0 < rise == math.inf",
    ),
    Mutation(
        "a foot lands at the top of an arc it rose to",
        "a1_leg_fk/estimation/foot_rise.py",
        "self._down[leg] = above < 0.0",
        "self._down[leg] = above == above",
    ),
    Mutation(
        "a foot's height not taken over the tread under it",
        "a1_leg_fk/estimation/foot_ground.py",
        "min(value - lowest, tread)",
        "value - lowest",
    ),
    Mutation(
        "a foot's own foothold is its tread",
        "a1_leg_fk/estimation/foot_rise.py",
        "if other != leg and tread <= z + band_m:",
        "if tread <= z + band_m:",
    ),
    Mutation(
        "a foot's rise taken about the frame's origin, not its foothold",
        "a1_leg_fk/estimation/foot_rise.py",
        "- gx * (point[0] - base[0]) - gy * (point[1] - base[1])",
        "- gx * point[0] - gy * point[1]",
    ),
    Mutation(
        "FR <-> FL Jacobian products swapped in the odometry feed",
        "a1_leg_fk/estimation/odometry_feed.py",
        "c = self._jacobians[leg](",
        "c = self._jacobians[(1, 0, 2, 3)[leg]](",
    ),
    Mutation(
        "the gate accepts every foot",
        "a1_leg_fk/estimation/foot_gate.py",
        "if value <= s.gate_chi2]",
        "if value <= s.gate_chi2 or True]",
    ),
    Mutation(
        "reported velocity variance x 100",
        "a1_leg_fk/estimation/state_sample.py",
        "variances[0] + dx,\n            variances[1] + dy,\n            variances[2] + dz,",
        "100.0 * variances[0] + dx,\n            100.0 * variances[1] + dy,\n"
        "            100.0 * variances[2] + dz,",
    ),
    Mutation(
        "momentum observer gain / 10",
        "a1_leg_fk/estimation/momentum_observer.py",
        "keep = exp(-gain * dt)",
        "keep = exp(-gain / 10.0 * dt)",
    ),
    Mutation(
        "FR <-> FL swapped in the tracker's feet",
        "a1_leg_fk/tracking.py",
        "out[foot.leg_slot] = (",
        "out[(1, 0, 2, 3)[foot.leg_slot]] = (",
    ),
    Mutation(
        "sign of the momentum observer's Coriolis term",
        "a1_leg_fk/estimation/momentum_observer.py",
        "e0, e1, e2 = t0 - g0 + k0, t1 - g1 + k1, t2 - g2 + k2",
        "e0, e1, e2 = t0 - g0 - k0, t1 - g1 - k1, t2 - g2 - k2",
    ),
    Mutation(
        "the IMU quaternion read x-first",
        "a1_leg_fk/wire/lowstate.py",
        "quaternion[:, [1, 2, 3, 0]],",
        "quaternion[:, [0, 1, 2, 3]],",
    ),
    Mutation(
        "gravity left unrotated (level) in the force output",
        "a1_leg_fk/estimation/contact_estimator.py",
        "gravity = LEVEL_GRAVITY if imu.gravity is None else imu.gravity",
        "gravity = LEVEL_GRAVITY",
    ),
    Mutation(
        "the touchdown term dropped",
        "a1_leg_fk/estimation/state_filter.py",
        "self.impact.variance(leg, (stamp_ns - touchdown) / 1e9)",
        "0.0",
    ),
    Mutation(
        "the touchdowns' horizontal jolt dropped",
        "a1_leg_fk/estimation/state_filter.py",
        "sideways = self.jolt.sideways(stamp_ns, stack.up)",
        "sideways = None",
    ),
    Mutation(
        "the flat-ground row's sign",
        "a1_leg_fk/estimation/filter_stack.py",
        "rows += (ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux, 1.0)",
        "rows += (rz * uy - ry * uz, rx * uz - rz * ux, ry * ux - rx * uy, -1.0)",
    ),
    Mutation(
        "the footholds' slope added to the feet's heights, not taken off",
        "a1_leg_fk/estimation/foot_ground.py",
        "o[2] - gx * o[0] - gy * o[1]",
        "o[2] + gx * o[0] + gy * o[1]",
    ),
    Mutation(
        "a touchdown never takes the ground's prediction (no anchoring)",
        "a1_leg_fk/estimation/touchdown_gate.py",
        "offset_m * offset_m <= self.step_gate**2 * (variance + sigma_m * sigma_m)",
        "False",
    ),
    Mutation(
        "a touchdown never waits for the foot to stop coming down",
        "a1_leg_fk/estimation/stance_edges.py",
        "if not (rates > DESCENT_MPS).any():",
        "if True:",
    ),
    Mutation(
        "a late rise fitted from its first 0.1 mm (a soft foot's unloading taken for it)",
        "a1_leg_fk/estimation/stance_edges.py",
        "heights[start - 1] > ground + 0.5 * LIFT_M",
        "heights[start - 1] > ground + EDGE_NOISE_FLOOR_M",
    ),
    Mutation(
        "the contact smoother's liftoffs not pooled (each stance's own rise fit alone)",
        "a1_leg_fk/estimation/contact_smoother.py",
        "placed = recent_liftoffs(times, heights, placed, POOL_S, since)",
        "placed = placed",
    ),
    Mutation(
        "the gait's edge tolerance x 10",
        "a1_leg_fk/gait/edges.py",
        "base = max(EDGE_NOISE_DEVIATIONS * noise_m, EDGE_NOISE_FLOOR_M)",
        "base = 10.0 * max(EDGE_NOISE_DEVIATIONS * noise_m, EDGE_NOISE_FLOOR_M)",
    ),
    Mutation(
        "a soft foot's unloading ramp not followed (the gait's lift-off partway up it)",
        "a1_leg_fk/gait/edges.py",
        "if rise is None or not rise > noise_m:",
        "if True:",
    ),
    Mutation(
        "the load's noise floor / 10 (a lift-off's last newtons x 10 below it)",
        "a1_leg_fk/estimation/load_edges.py",
        "FLOOR_SIGMAS = 8.0",
        "FLOOR_SIGMAS = 0.8",
    ),
    Mutation(
        "the legs' inertia scale fitted without its instrument (plain least squares)",
        "a1_leg_fk/estimation/leg_scales.py",
        "z0, z1, z2 = 0.5 * (a0 + b0), 0.5 * (a1 + b1), 0.5 * (a2 + b2)  # the instrument",
        "z0, z1, z2 = w0, w1, w2",
    ),
    Mutation(
        "the legs' torque W without the efforts through the lag",
        "a1_leg_fk/estimation/momentum_observer.py",
        "r0, r1, r2 = scales.correct(slot, residual, (r0 + f0, r1 + f1, r2 + f2))",
        "r0, r1, r2 = scales.correct(slot, residual, (r0, r1, r2))",
    ),
    Mutation(
        "the strides' pooled rise fitted without the stance's drift",
        "a1_leg_fk/estimation/pooled_rise.py",
        "np.broadcast_arrays(np.ones_like(times), times, rising)",
        "np.broadcast_arrays(np.ones_like(times), 0.0 * times, rising)",
    ),
    Mutation(
        "the unloading ramp carried past a cliff the samples' own loads show",
        "a1_leg_fk/estimation/load_edges.py",
        "if noise_n is not None and offset > FLOOR_SIGMAS * noise_n:",
        "if False:",
    ),
    Mutation(
        "the load's dip never bridged",
        "a1_leg_fk/estimation/load_edges.py",
        "if standing.size and (swing > DIP_SIGMAS * noise_n).all():",
        "if False:",
    ),
    Mutation(
        "a standing foot's ground not carried along the slope it landed on",
        "a1_leg_fk/estimation/ground.py",
        "return anchor[2] + grade[0] * (point[0] - anchor[0]) + grade[1] * (point[1] - anchor[1])",
        "return anchor[2]",
    ),
    Mutation(
        "a step measured against the standing feet counts as touchdown noise",
        "a1_leg_fk/estimation/ground.py",
        "and (agrees or (alone and not self._a_step(agrees))):",
        "and True:",
    ),
    Mutation(
        "a touchdown against the standing feet judged at the touchdowns' scatter",
        "a1_leg_fk/estimation/touchdown_gate.py",
        "        if not alone:\n            return self.min_sigma_m\n",
        "",
    ),
    Mutation(
        "a staircase's touchdowns offered the slope's prediction (no treads)",
        "a1_leg_fk/estimation/touchdown_gate.py",
        "return fits and 2 * sum(self._votes) < len(self._votes)",
        "return False",
    ),
    Mutation(
        "a staircase's treads judged whatever its touchdowns' scatter (the A1's early landings)",
        "a1_leg_fk/estimation/touchdown_gate.py",
        "fits = sigma is not None and sigma <= self.min_sigma_m",
        "fits = True",
    ),
    Mutation(
        "a lone touchdown's noise without the estimate's vertical variance",
        "a1_leg_fk/estimation/touchdown_gate.py",
        "max(height_variance, 0.0)",
        "0.0",
    ),
    Mutation(
        "the legs' scales learnt from stuck joints (a friction's hold read as a lighter leg)",
        "a1_leg_fk/estimation/leg_scales.py",
        "sums[:3] if sticks else",
        "sums[:3] if False else",
    ),
    Mutation(
        "the reported ground takes the contact estimate's flickers (every stance a foothold)",
        "a1_leg_fk/estimation/ground.py",
        "if stamp_s - since >= MIN_FOOTHOLD_S:",
        "if True:",
    ),
)


def check(mutations: tuple[Mutation, ...], root: Path) -> list[str]:
    """The mutations whose old text is not found exactly once in ``root``, in words."""
    problems = []
    for mutation in mutations:
        count = (root / mutation.path).read_text().count(mutation.old)
        if count != 1:
            problems.append(f"{mutation.name}: its text is found {count} times in {mutation.path}")
    return problems


def run_subset(copy: Path, tests: tuple[str, ...] = FAST_SUBSET) -> tuple[str | None, float]:
    """Run ``tests`` in ``copy``: the first failing test (None: all passed), seconds."""
    env = {**os.environ, "PYTHONPATH": str(copy), "PYTHONDONTWRITEBYTECODE": "1"}
    command = [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "-rfE",
               "--timeout=300", *tests]  # fmt: skip
    start = time.monotonic()
    try:
        done = subprocess.run(
            command, cwd=copy, env=env, capture_output=True, text=True, timeout=RUN_TIMEOUT_S,
            check=False,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        return "(timeout)", time.monotonic() - start
    seconds = time.monotonic() - start
    if done.returncode == 0:
        return None, seconds
    failed = re.findall(r"^(?:FAILED|ERROR) (\S+)", done.stdout, re.MULTILINE)
    return (failed[0] if failed else f"(exit {done.returncode})"), seconds


def mutated(copy: Path, mutation: Mutation, tests: tuple[str, ...]) -> tuple[str | None, float]:
    """Apply ``mutation`` in ``copy``, run the subset, restore the file."""
    path = copy / mutation.path
    original = path.read_text()
    path.write_text(original.replace(mutation.old, mutation.new, 1))
    try:
        return run_subset(copy, tests)
    finally:
        path.write_text(original)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=2, help="mutations run at once (default 2)")
    parser.add_argument("--only", nargs="*", default=(), help="run the mutations named so")
    parser.add_argument("--list", action="store_true", help="list the mutations and exit")
    parser.add_argument("--tests", nargs="+", default=FAST_SUBSET, help="another test subset")
    args = parser.parse_args(argv)
    unknown = sorted(set(args.only) - {m.name for m in MUTATIONS})
    if unknown:
        print(f"mutations.py: no mutation named {unknown[0]!r} (--list names them)",
              file=sys.stderr)  # fmt: skip
        return 2
    mutations = tuple(m for m in MUTATIONS if not args.only or m.name in args.only)
    if args.list:
        for mutation in MUTATIONS:
            print(f"{mutation.path}: {mutation.name}")
        return 0
    problems = check(mutations, ROOT)
    if problems:
        print("\n".join(problems), file=sys.stderr)
        return 2
    jobs = max(1, min(args.jobs, len(mutations)))
    with tempfile.TemporaryDirectory(prefix="a1_leg_fk-mutate-") as scratch:
        copies: Queue[Path] = Queue()
        for job in range(jobs):
            copy = Path(scratch) / f"tree{job}"
            shutil.copytree(ROOT, copy, ignore=IGNORED)
            copies.put(copy)
        start = time.monotonic()
        tests = tuple(args.tests)
        baseline, seconds = run_subset(copies.queue[0], tests)
        print(f"the fast subset, unmutated: {seconds:.1f} s", flush=True)
        if baseline is not None:
            print(f"the tree fails its own fast subset: {baseline}", file=sys.stderr)
            return 2

        def one(mutation: Mutation) -> tuple[str | None, float]:
            copy = copies.get()
            try:
                return mutated(copy, mutation, tests)
            finally:
                copies.put(copy)

        with ThreadPoolExecutor(max_workers=jobs) as pool:
            results = list(pool.map(one, mutations))
    width = max(len(m.name) for m in mutations)
    print(f"\n{'mutation':<{width}}  {'seconds':>7}  killed by")
    for mutation, (killer, seconds) in zip(mutations, results, strict=True):
        print(f"{mutation.name:<{width}}  {seconds:7.1f}  {killer or 'SURVIVED'}")
    survivors = sum(killer is None for killer, _ in results)
    print(
        f"\n{len(mutations) - survivors} of {len(mutations)} killed, {survivors} survived "
        f"({time.monotonic() - start:.0f} s in all)"
    )
    return 1 if survivors else 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except KeyboardInterrupt:  # the scratch copies are removed on the way out
        sys.exit(130)
