"""Joint states and IMU samples in, odometry samples out: the one pipeline of the node and the bag
tool (:class:`OdometryFeed`).

- Every IMU sample with an accelerometer propagates the state filter
  (:class:`~a1_leg_fk.estimation.state_filter.StateFilter`); every IMU sample is kept to pair with
  the joint states (:class:`~a1_leg_fk.estimation.imu.ImuBuffer`).
- Per joint state: the feet's contact probabilities (:class:`~a1_leg_fk.estimation.
  force_pass.ForcePass`, the contact estimate as the node and the bag tools run it: the efforts'
  dynamic foot forces fused with the feet's heights and speeds, or the kinematic evidence alone,
  see :data:`CONTACT_SOURCES`); each
  standing foot's motion (:class:`~a1_leg_fk.estimation.leg_motion.LegMotion`) and Jacobian; then
  the filter's update, gated per foot (a foot landing on a step after a flight, its stance from
  the kinematics, left out while it settles: :data:`LANDING_SETTLE_S`).
- The standing feet the estimate used, at their contact points in odom, feed the local ground
  (:class:`~a1_leg_fk.estimation.ground.LocalGround`: the plane through the recent footholds,
  :meth:`OdometryFeed.ground_plane`), with the filter's vertical position variance (a lone
  touchdown's height noise, :mod:`~a1_leg_fk.estimation.touchdown_gate`).
- Without an IMU sample with an accelerometer paired with the joint state (no IMU, ``use_imu``
  false, or an IMU without one), the legs alone: the averaging estimate of
  :class:`~a1_leg_fk.estimation.odometry.LegOdometry`, as before the filter.

Plain floats on the per-foot path; the filter's 15 x 15 algebra in numpy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

from a1_leg_fk.estimation.contact_estimator import ContactStep, EvidenceCounts, ImuSample
from a1_leg_fk.estimation.correction_file import CorrectionFileError
from a1_leg_fk.estimation.filter_model import (
    DEFAULT_GROUND,
    FOOTHOLDS,
    LEGS,
    MAX_BASE_SPEED_MPS,
    FilterSettings,
    LegMeasurement,
    stands,
)
from a1_leg_fk.estimation.force_pass import ForcePass
from a1_leg_fk.estimation.ground import LocalGround
from a1_leg_fk.estimation.ground_plane import GroundPlane
from a1_leg_fk.estimation.imu import DEFAULT_IMU_TIMEOUT_S, ImuBuffer
from a1_leg_fk.estimation.leg_motion import FootMotion, LegMotion, contact_points
from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS, ModelCorrections
from a1_leg_fk.estimation.odometry import (
    ImuReading,
    LegOdometry,
    OdometrySample,
    OdometrySettings,
)
from a1_leg_fk.estimation.stance import kinematic_stance
from a1_leg_fk.estimation.state_filter import StateFilter
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY, Vector, down_direction
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import JOINTS_PER_LEG
from a1_leg_fk.model.urdf import LegFkError

LANDING_SETTLE_S = 0.03
"""[s] a foot that lands on a step while no foot stands (after a flight;
:meth:`LocalGround.lands_on_a_step`) gives the state filter no measurement for this long, unless
the contacts weigh the feet's forces: called standing by its kinematics at the impact, it bounces
in contact (go2_stairs_down_6cm: 2-6 mm up in 25-50 ms), and held still from its first sample
it pulled the base down with it (vertical drift 0.53 %, 0.27 % since; the IMU carries the base
meanwhile). A force calls the stance as the foot takes the load: held too, 0.22 -> 0.39 %. Its
foothold is anchored when it is first used."""

Foot = tuple[Sequence[float], Sequence[float]]
"""A foot's position [m] and velocity [m/s] (``J q_dot``), base frame."""


class JointSample(NamedTuple):
    """One joint state as the estimators take it: stamp [ns], per leg its :data:`Foot` (None:
    unknown), the 12 angles [rad] and rates [rad/s] in slot order.
    """

    stamp_ns: int
    feet: Sequence[Foot | None]
    angles: Sequence[float]
    rates: Sequence[float]


NO_MOTIONS: tuple[None, ...] = (None,) * LEGS
"""No foot's motion from the contact estimate: the feed works them out."""
AUTO, FORCE, KINEMATIC = "auto", "force", "kinematic"
CONTACT_SOURCES = (AUTO, FORCE, KINEMATIC)
"""Where the contacts' evidence comes from (the node's ``contacts`` parameter, ``a1-leg-fk odom
--contacts``): ``auto`` (default) the efforts' foot forces where the joint state has efforts,
with the feet's kinematics; ``force`` the same, and a joint state without efforts has no foot
standing; ``kinematic`` the kinematics alone (efforts ignored)."""


class OdometryFeed:
    """The base's state for one robot. ``radii``: the feet's rolling radii [m] (default: the
    URDF's collision spheres); ``use_imu`` false ignores IMU samples (legs alone); ``contacts``
    one of :data:`CONTACT_SOURCES`; ``ground``: ``footholds`` (default: each stance foot held to
    its foothold's anchored height), ``flat`` (the stance feet anchor the height at the first
    feet's) or ``none`` (:data:`~a1_leg_fk.estimation.filter_model.GROUND_MODELS`);
    ``model_corrections``: the contact estimate's (:class:`ForcePass`).
    """

    def __init__(
        self,
        quadruped: Quadruped,
        settings: OdometrySettings | None = None,
        radii: Sequence[float] | float | None = None,
        imu_timeout_s: float = DEFAULT_IMU_TIMEOUT_S,
        use_imu: bool = True,
        contacts: str = AUTO,
        filter_settings: FilterSettings | None = None,
        ground: str = DEFAULT_GROUND,
        model_corrections: str = DEFAULT_MODEL_CORRECTIONS,
    ) -> None:
        if contacts not in CONTACT_SOURCES:
            raise LegFkError(f"contacts must be one of {', '.join(CONTACT_SOURCES)}: {contacts!r}")
        self.source = contacts
        self.motion = LegMotion(quadruped, radii)
        self.note = ""
        """Why there are no foot forces for this robot ("" when there are)."""
        self.contacts: ForcePass | None = None
        try:
            self.contacts = ForcePass(quadruped, model_corrections=model_corrections)
        except CorrectionFileError:  # bad input, not a robot without forces
            raise
        except LegFkError as error:  # a URDF without masses: the kinematic stance
            self.note = str(error)
        self.odometry = LegOdometry(settings)
        self.filter = StateFilter(filter_settings, ground)
        self.imu = ImuBuffer(imu_timeout_s)
        self.use_imu = use_imu
        self.samples_with_imu = 0
        self.samples_filtered = 0
        self.distance_m = 0.0
        """The path length of the estimate's positions [m]."""
        self._jacobians = tuple(leg.jacobian_from_trig for leg in quadruped.legs)
        self._shares_motions = (
            self.contacts is not None and self.contacts.estimator.motion.radii == self.motion.radii
        )
        """The contact estimate's feet's motions are this feed's (the same rolling radii)."""
        self._position: tuple[float, float, float] | None = None
        self.ground = LocalGround()
        """The recent footholds and the local ground's plane through them."""
        self._last: OdometrySample | None = None
        self._touchdowns: dict[int, tuple[int, bool]] = {}
        """Per standing leg its touchdown's stamp [ns] and whether it is held (:meth:`_settle`)."""

    @property
    def counts(self) -> EvidenceCounts:
        """The joint states whose contacts had force evidence, and kinematic evidence alone."""
        return self.contacts.estimator.counts if self.contacts is not None else EvidenceCounts()

    @property
    def corrections(self) -> ModelCorrections | None:
        """The contact estimate's model corrections (None: off, or no foot forces)."""
        return self.contacts.estimator.corrections if self.contacts is not None else None

    def add_imu(self, stamp_ns: int, reading: ImuReading | None) -> None:
        """One IMU sample (None: unusable, ignored); with an accelerometer it moves the filter."""
        if reading is None or not self.use_imu:
            return
        self.imu.add(stamp_ns, reading)
        if reading.specific_force is not None:
            self.filter.propagate(stamp_ns, reading.gyro, reading.specific_force,
                                  reading.orientation)  # fmt: skip

    def step(
        self,
        stamp_ns: int,
        feet: Sequence[Foot | None],
        angles: Sequence[float],
        rates: Sequence[float],
        contacts: Sequence[float] | None = None,
        efforts: Sequence[float] | None = None,
    ) -> OdometrySample | None:
        """The estimate after one joint state: per leg its foot (None: not in this joint state, or
        without velocity), the 12 merged ``angles`` [rad], ``rates`` [rad/s] and ``efforts``
        [N m] (None: none) in slot order; ``contacts`` (4) probabilities from elsewhere, else
        the contact estimate's. None, and nothing changes, when no leg has a foot.
        """
        if all(foot is None for foot in feet):
            return None
        imu = self.imu.at(stamp_ns)
        self.samples_with_imu += imu is not None
        down = down_direction(None if imu is None else imu.orientation)
        motions: Sequence[FootMotion | None] = NO_MOTIONS
        forced = contacts is None and self.contacts is not None and self.source != KINEMATIC
        forced = forced and efforts is not None  # the stances the feet's loads call
        if contacts is None:
            step = self._contacts(stamp_ns, feet, (angles, rates, efforts), imu, down)
            if step is not None:
                contacts = step.probabilities
                motions = step.motions if self._shares_motions else NO_MOTIONS
        joint = JointSample(stamp_ns, feet, angles, rates)
        height_variance = 0.0  # the legs alone: no anchored height to be uncertain about
        if imu is None or imu.specific_force is None or not self.filter.started:
            sample = self._legs_alone(joint, (contacts, motions), imu, down)
        else:  # an accelerometer: the state filter
            self.samples_filtered += 1
            sample = self._filtered(joint, (contacts, motions), imu, down, forced)
            height_variance = sample.pose_variance[2]
        position = sample.position
        centres = [None if foot is None else foot[0] for foot in feet]
        self.ground.update(
            stamp_ns * 1e-9,
            contact_points(position, sample.orientation, centres, self.motion.radii, sample.used),
            height_variance,
        )
        self._last = sample
        if self._position is not None:
            last = self._position
            self.distance_m += math.dist(position, last)
        self._position = position
        return sample

    def ground_plane(self, sample: OdometrySample) -> GroundPlane | None:
        """The local ground under the base of ``sample`` (:meth:`step`'s; None before a foot
        stood): its height [m, odom], normal, tilt and their covariance.
        """
        position = sample.position
        return self.ground.reported(position[0], position[1], sample.orientation)

    def _filtered(
        self,
        joint: JointSample,
        contacts: tuple[Sequence[float] | None, Sequence[FootMotion | None]],
        imu: ImuReading,
        down: Vector,
        forced: bool,
    ) -> OdometrySample:
        """The state filter's estimate after its update with this joint state's feet (their
        contact probabilities, and their motions where the contact estimate has them; ``forced``:
        the probabilities weigh the feet's forces).
        """
        stamp_ns, feet, angles, _ = joint
        probabilities, motions = contacts
        legs: list[LegMeasurement | None] = [None] * len(feet)
        for leg, foot in enumerate(feet):
            if probabilities is not None and foot is not None and stands(probabilities[leg]):
                motion = motions[leg] or self._motion(leg, foot, joint, down)
                joints = slice(leg * JOINTS_PER_LEG, (leg + 1) * JOINTS_PER_LEG)
                legs[leg] = self._measurement(leg, motion, angles[joints], probabilities[leg])
        self._settle(stamp_ns, feet, legs, forced)
        grounds = self._grounds(feet, legs) if self.filter.ground == FOOTHOLDS else None
        used = self.filter.update(
            stamp_ns, legs, imu.orientation, imu.orientation_variance, grounds
        )
        stance = [leg for leg, measurement in enumerate(legs) if measurement is not None]
        return self.filter.sample(stamp_ns, stance, used)

    def _settle(
        self,
        stamp_ns: int,
        feet: Sequence[Foot | None],
        legs: list[LegMeasurement | None],
        forced: bool,
    ) -> None:
        """Leave out of ``legs`` (per leg its measurement, None: swing) the feet that landed on
        a step while no foot stood in the last estimate (after a flight) until
        :data:`LANDING_SETTLE_S` after their touchdown, unless ``forced`` (their stances weigh
        their loads); ``stamp_ns``: this sample's [ns], ``feet``: :meth:`step`'s.
        """
        last = self._last
        alone = not forced and last is not None and not last.used
        touchdowns = self._touchdowns
        for leg, measurement in enumerate(legs):
            if measurement is None:
                touchdowns.pop(leg, None)
                continue
            if leg not in touchdowns:
                touchdowns[leg] = (stamp_ns, alone and self._on_a_step(leg, feet))
            landed, held = touchdowns[leg]
            if held and (stamp_ns - landed) * 1e-9 < LANDING_SETTLE_S:
                legs[leg] = None

    def _on_a_step(self, leg: int, feet: Sequence[Foot | None]) -> bool:
        """Whether the foot of ``leg`` in ``feet`` lands off the ground's prediction (a step:
        its foothold takes its own height, :meth:`LocalGround.lands_on_a_step`), placed by the
        last estimate's pose.
        """
        last = self._last
        foot = feet[leg]
        if last is None or foot is None:
            return False
        points = contact_points(
            last.position, last.orientation, [foot[0]], self.motion.radii[leg : leg + 1], [0]
        )
        return self.ground.lands_on_a_step(points[0][1])

    def _grounds(
        self, feet: Sequence[Foot | None], measured: Sequence[LegMeasurement | None]
    ) -> list[tuple[float, float] | None] | None:
        """Per leg, the ground's height [m, odom] under its foot and its variance [m²]
        (:meth:`~a1_leg_fk.estimation.ground.LocalGround.under`, the feet placed by the last
        estimate's pose); None before the first estimate, and for the legs without a
        measurement (``measured``: the filter reads the standing feet's alone, and a swinging
        foot's plane costs a fit's move per sample).
        """
        last = self._last
        if last is None:
            return None
        centres = [None if foot is None else foot[0] for foot in feet]
        legs = [leg for leg, measurement in enumerate(measured) if measurement is not None]
        points = contact_points(last.position, last.orientation, centres, self.motion.radii, legs)
        return self.ground.under(points, len(feet))

    def _contacts(
        self,
        stamp_ns: int,
        feet: Sequence[Foot | None],
        joints: tuple[Sequence[float], Sequence[float], Sequence[float] | None],
        imu: ImuReading | None,
        down: Vector,
    ) -> ContactStep | None:
        """The contact estimate (None: kinematic stance, a URDF without masses)."""
        if self.contacts is None:
            return None
        angles, rates, efforts = joints
        if self.source == KINEMATIC:
            efforts = None
        elif self.source == FORCE and efforts is None:
            none = [0.0] * len(feet)
            return ContactStep([], none, none, [], [], [None] * len(feet))
        gravity = (down[0] * STANDARD_GRAVITY, down[1] * STANDARD_GRAVITY,
                   down[2] * STANDARD_GRAVITY)  # fmt: skip
        sample = ImuSample(
            gravity if imu is not None and imu.orientation is not None else None,
            None if imu is None else imu.gyro,
            None if imu is None else imu.specific_force,
        )
        return self.contacts.message(stamp_ns, (angles, rates, efforts), feet, sample)

    def _motion(self, leg: int, foot: Foot, joint: JointSample, down: Vector) -> FootMotion:
        """Leg ``leg``'s foot's motion worked out here (the contact estimate had none)."""
        joints = slice(leg * JOINTS_PER_LEG, (leg + 1) * JOINTS_PER_LEG)
        return self.motion.foot(
            leg, joint.angles[joints], joint.rates[joints], foot[0], foot[1], down
        )

    def _measurement(
        self, leg: int, motion: FootMotion, q: Sequence[float], probability: float
    ) -> LegMeasurement | None:
        """A standing foot's measurement: its motion and ``J Jᵀ`` (``q``: its leg's three angles
        [rad]); None when unusable (:func:`usable`).
        """
        if not usable(motion):
            return None
        c = self._jacobians[leg](math.cos(q[0]), math.sin(q[0]), math.cos(q[1]), math.sin(q[1]),
                                 math.cos(q[2]), math.sin(q[2]))  # fmt: skip
        xx = c[0] * c[0] + c[3] * c[3] + c[6] * c[6]
        xy = c[0] * c[1] + c[3] * c[4] + c[6] * c[7]
        xz = c[0] * c[2] + c[3] * c[5] + c[6] * c[8]
        yy = c[1] * c[1] + c[4] * c[4] + c[7] * c[7]
        yz = c[1] * c[2] + c[4] * c[5] + c[7] * c[8]
        zz = c[2] * c[2] + c[5] * c[5] + c[8] * c[8]
        return LegMeasurement(motion, probability, (xx, xy, xz, xy, yy, yz, xz, yz, zz))

    def _legs_alone(
        self,
        joint: JointSample,
        contacts: tuple[Sequence[float] | None, Sequence[FootMotion | None]],
        imu: ImuReading | None,
        down: Vector,
    ) -> OdometrySample:
        """The averaging estimate of the standing feet (no accelerometer to propagate with; their
        contact probabilities, and their motions where the contact estimate has them).
        """
        stamp_ns, feet, _, _ = joint
        probabilities, shared = contacts
        odometry = self.odometry
        depths: list[float | None] = [None] * len(feet)
        motions: list[FootMotion | None] = [None] * len(feet)
        for leg, foot in enumerate(feet):
            if foot is not None:
                depth = self.motion.contact(leg, foot[0], down)[1]
                depths[leg] = depth if math.isfinite(depth) else None
        if probabilities is None:
            weights = kinematic_stance(depths, odometry.settings.stance_band_m)
        else:
            weights = odometry.stance(depths, probabilities)
        for leg in list(weights):
            foot = feet[leg]
            assert foot is not None
            motion = shared[leg] or self._motion(leg, foot, joint, down)
            if usable(motion):
                motions[leg] = motion
            else:
                del weights[leg]
        return odometry.estimate(stamp_ns, motions, weights, imu)


def usable(motion: FootMotion) -> bool:
    """A foot's motion gives a measurement: its base velocity finite and no faster than
    :data:`~a1_leg_fk.estimation.filter_model.MAX_BASE_SPEED_MPS` on any axis.
    """
    ex, ey, ez = motion.e
    fastest = MAX_BASE_SPEED_MPS
    return abs(ex) <= fastest and abs(ey) <= fastest and abs(ez) <= fastest  # False for NaN
