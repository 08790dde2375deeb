"""The contacts of a gait as CSV (``a1-leg-fk gait --csv-contacts``)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from a1_leg_fk.gait.contacts import Contacts
from a1_leg_fk.model.legs import LEG_NAMES


def write_contacts_csv(contacts: Contacts, path: Path) -> None:
    """One row per sample: ``time_s``, ``<leg>_stance`` (0/1), ``<leg>_height_m``,
    ``<leg>_speed_mps`` (empty where unknown), ``<leg>_blip`` (1 where the minimum-phase rule
    changed the sample's stance: a blip dropped or bridged, else 0).
    """
    header = [
        "time_s",
        *(f"{leg}_stance" for leg in LEG_NAMES),
        *(f"{leg}_height_m" for leg in LEG_NAMES),
        *(f"{leg}_speed_mps" for leg in LEG_NAMES),
        *(f"{leg}_blip" for leg in LEG_NAMES),
    ]
    blips = (
        contacts.blip_samples
        if contacts.blip_samples is not None
        else np.zeros(contacts.stance.shape, dtype=bool)
    )
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(header)
        for row in range(contacts.times_s.size):
            stance = [
                int(value) if known else ""
                for value, known in zip(contacts.stance[row], contacts.valid[row])
            ]
            numbers = [
                _csv_value(value)
                for value in (*contacts.heights_m[row], *contacts.speeds_mps[row])
            ]
            changed = [int(value) for value in blips[row]]
            writer.writerow([f"{contacts.times_s[row]:.9f}", *stance, *numbers, *changed])


def _csv_value(value: float) -> str:
    return "" if np.isnan(value) else repr(float(value))
