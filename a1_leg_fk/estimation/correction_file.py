"""A calibration's file of model corrections (``a1-leg-fk calibrate``, read by ``--corrections
FILE``): per joint, by name, the bias [N m], viscous [N m s/rad] and Coulomb [N m] friction fitted
over a recording's swing samples with the fit's residuals, each leg's inertia scale (its
links' mass and inertia over the URDF's, :mod:`a1_leg_fk.estimation.leg_scales`) and the
payload [kg] its standing phase showed; without ROS.

The file is YAML written in its JSON-compatible flow style (every YAML 1.2 reader reads it; the
package reads it with the standard library). Reading it checks it against the robot: the same
joints (by name, every one), finite values within :class:`CorrectionSettings`' bounds and signs
(friction opposes motion), inertia scales within ``1 ± scale_bound`` (a file without them: 1),
a payload between minus half and twice the URDF's mass, and the URDF's
mass it was made with (``urdf_mass_kg``, when the file gives it) within :data:`MASS_TOLERANCE` of
the robot's: pybullet_data's A1 and Aliengo share their joint names, not their masses. Anything
else is refused in one line naming the file and the culprit.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from a1_leg_fk.estimation.model_corrections import CorrectionSettings
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

FORMAT = "a1_leg_fk model corrections 1"
"""The file's ``format`` entry."""
TERMS = ("bias_nm", "viscous_nms_per_rad", "coulomb_nm")
"""A joint's entries taken off (the fit's residuals beside them are for reading)."""
MAX_FILE_BYTES = 1_000_000
EFFORT_SCALES = (0.5, 2.0)
EFFORT_LATENCIES_S = (0.0, 0.02)
"""The efforts' scale and latency [s] a file may give (inclusive)."""
MASS_TOLERANCE = 0.01
"""The largest relative difference between the URDF's mass a file was made with and the robot's."""


class CorrectionFileError(LegFkError):
    """A calibration's file that cannot be read or does not match the robot."""


@dataclass(frozen=True)
class CorrectionFile:
    """A calibration: ``joints`` (slot order: the robot's joint names), ``terms`` per joint
    (bias [N m], viscous [N m s/rad], Coulomb [N m]), ``residuals`` per joint (swing samples,
    the residual's RMS [N m] before and after the fit), ``payload_kg`` [kg] (the standing
    phase's weight over the URDF's), ``standing_s`` [s] the standing phase used, ``source``,
    ``urdf_mass_kg`` [kg] the URDF's mass it was made with (NaN: unknown, a file without it),
    ``effort_scale`` (the efforts reported over the motors' torques) and ``effort_latency_s`` [s]
    (how late they are): not fitted (calibrate writes 1 and 0), set by hand from what the
    robot's maker or a bench test says (:mod:`a1_leg_fk.estimation.effort_timing`);
    ``inertia_scales`` per leg (FR, FL, RR, RL) its links' mass and inertia over the URDF's.
    """

    joints: tuple[str, ...]
    terms: tuple[tuple[float, float, float], ...]
    residuals: tuple[tuple[float, float, float], ...]
    payload_kg: float
    standing_s: float
    source: str
    urdf_mass_kg: float = math.nan
    effort_scale: float = 1.0
    effort_latency_s: float = 0.0
    inertia_scales: tuple[float, ...] = (1.0,) * len(LEG_NAMES)

    def text(self) -> str:
        """The file's text."""
        joints = {
            name: {
                **dict(zip(TERMS, (round(v, 4) + 0.0 for v in terms), strict=True)),
                "swing_samples": round(residual[0]),
                "residual_rms_nm": round(residual[1], 4),
                "fitted_rms_nm": round(residual[2], 4),
            }
            for name, terms, residual in zip(self.joints, self.terms, self.residuals, strict=True)
        }
        document = {
            "format": FORMAT,
            "source": self.source,
            "urdf_mass_kg": round(self.urdf_mass_kg, 4),
            "payload_kg": round(self.payload_kg, 3),
            "standing_s": round(self.standing_s, 3),
            "effort_scale": self.effort_scale,
            "effort_latency_s": self.effort_latency_s,
            "leg_inertia_scales": dict(
                zip(LEG_NAMES, (round(v, 4) for v in self.inertia_scales), strict=True)
            ),
            "joints": joints,
        }
        return json.dumps(document, indent=2) + "\n"


def read_correction_file(
    path: str | Path, joints: Sequence[str], urdf_mass_kg: float
) -> CorrectionFile:
    """The calibration at ``path`` for a robot of ``joints`` (slot order) and ``urdf_mass_kg``
    [kg]; :class:`CorrectionFileError` (one line) if it cannot be read or does not match the robot.
    """
    where = f"corrections file {path}"
    try:
        with Path(path).open("rb") as file:
            raw = file.read(MAX_FILE_BYTES + 1)
        document = json.loads(raw.decode("utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise CorrectionFileError(f"{where}: cannot be read: {error}") from None
    if len(raw) > MAX_FILE_BYTES or not isinstance(document, dict):
        raise CorrectionFileError(f"{where}: not a calibration (a1-leg-fk calibrate writes one)")
    if document.get("format") != FORMAT:
        raise CorrectionFileError(f"{where}: format is not {FORMAT!r}: {document.get('format')!r}")
    entries = document.get("joints")
    if not isinstance(entries, dict) or set(entries) != set(joints):
        named = sorted(entries) if isinstance(entries, dict) else entries
        raise CorrectionFileError(
            f"{where}: its joints {named} are not the robot's {sorted(joints)}"
        )
    terms = tuple(_terms(where, name, entries[name]) for name in joints)
    residuals = tuple(_residuals(where, name, entries[name]) for name in joints)
    payload = _number(where, "payload_kg", document.get("payload_kg"), 2.0 * urdf_mass_kg)
    if payload < -0.5 * urdf_mass_kg:
        raise CorrectionFileError(
            f"{where}: payload_kg {payload} is below half the URDF's mass, negated"
        )
    standing = _number(where, "standing_s", document.get("standing_s"), math.inf)
    made_for = _number(where, "urdf_mass_kg", document.get("urdf_mass_kg", math.nan), 1e6, True)
    if abs(made_for - urdf_mass_kg) > MASS_TOLERANCE * urdf_mass_kg:  # False for NaN
        raise CorrectionFileError(
            f"{where}: made for a robot whose URDF weighs {made_for:g} kg, this one's "
            f"{urdf_mass_kg:.4g} kg"
        )
    return CorrectionFile(
        tuple(joints),
        terms,
        residuals,
        payload,
        standing,
        str(document.get("source", "")),
        made_for,
        *_timing(where, document),
        _scales(where, document.get("leg_inertia_scales")),
    )


def _scales(where: str, entry: object) -> tuple[float, ...]:
    """Per leg its inertia scale (``leg_inertia_scales``: a mapping of every leg's name, within
    ``1 ± scale_bound``; absent: 1 for every leg, a file of before the scales).
    """
    if entry is None:
        return (1.0,) * len(LEG_NAMES)
    if not isinstance(entry, dict) or set(entry) != set(LEG_NAMES):
        raise CorrectionFileError(
            f"{where}: leg_inertia_scales must give each of {', '.join(LEG_NAMES)}: {entry!r}"
        )
    bound = CorrectionSettings().scale_bound
    scales = tuple(
        _number(where, f"leg_inertia_scales {leg}", entry[leg], 1.0 + bound) for leg in LEG_NAMES
    )
    for leg, scale in zip(LEG_NAMES, scales, strict=True):
        if scale < 1.0 - bound:
            raise CorrectionFileError(
                f"{where}: leg_inertia_scales {leg} {scale} is absurd (at least {1.0 - bound:g})"
            )
    return scales


def _timing(where: str, document: dict[str, object]) -> tuple[float, float]:
    """The file's effort scale (within :data:`EFFORT_SCALES`; 1 when absent) and latency [s]
    (within :data:`EFFORT_LATENCIES_S`; 0 when absent).
    """
    values = []
    for name, default, (least, most) in (
        ("effort_scale", 1.0, EFFORT_SCALES),
        ("effort_latency_s", 0.0, EFFORT_LATENCIES_S),
    ):
        value = _number(where, name, document.get(name, default), most)
        if value < least:
            raise CorrectionFileError(f"{where}: {name} {value} is absurd (at least {least:g})")
        values.append(value)
    return values[0], values[1]


def _terms(where: str, name: str, entry: object) -> tuple[float, float, float]:
    """One joint's bias, viscous and Coulomb terms, checked against the settings' bounds."""
    if not isinstance(entry, dict):
        raise CorrectionFileError(f"{where}: joint {name} is not a mapping of its terms")
    bounds = CorrectionSettings().bounds
    bias = _number(where, f"{name} bias_nm", entry.get("bias_nm"), bounds[0])
    if abs(bias) > bounds[0]:
        raise CorrectionFileError(f"{where}: {name} bias_nm {bias} is beyond +-{bounds[0]} N m")
    viscous = _number(where, f"{name} viscous_nms_per_rad", entry.get(TERMS[1]), bounds[1])
    coulomb = _number(where, f"{name} coulomb_nm", entry.get(TERMS[2]), bounds[2])
    if viscous < 0.0 or coulomb < 0.0:
        raise CorrectionFileError(f"{where}: {name}'s friction is negative (it opposes motion)")
    return bias, viscous, coulomb


def _residuals(where: str, name: str, entry: dict[str, object]) -> tuple[float, float, float]:
    """One joint's fit residuals (swing samples, RMS before and after [N m]; NaN: none)."""
    samples, before, after = (
        _number(where, f"{name} {key}", entry.get(key, math.nan), math.inf, True)
        for key in ("swing_samples", "residual_rms_nm", "fitted_rms_nm")
    )
    return samples, before, after


def _number(where: str, name: str, value: object, most: float, nan_ok: bool = False) -> float:
    """``value`` as a finite float at most ``most`` (NaN allowed with ``nan_ok``)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CorrectionFileError(f"{where}: {name} is not a number: {value!r}")
    number = float(value)
    if math.isnan(number) and nan_ok:
        return number
    if not math.isfinite(number) or number > most:
        raise CorrectionFileError(f"{where}: {name} {number} is absurd (at most {most:g})")
    return number
