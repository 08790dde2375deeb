"""A Rerun recording (``.rrd``) read back with Rerun's own reader, for the view tests."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np


def read_rrd(path: Path) -> dict[str, dict[str, list]]:
    """Entity -> column name -> values (time columns as int64 ns), temporal chunks concatenated
    in time order; static chunks under the key ``static:<entity>``."""
    import rerun as rr  # here: a test without rerun-sdk skips (importorskip) before it is needed

    entities: dict[str, dict[str, list]] = {}
    with warnings.catch_warnings():  # a streamed file (rerun --save) has no footer: scanned whole
        warnings.filterwarnings("ignore", "RRD file has no footer", rr.error_utils.RerunWarning)
        reader = rr.chunk.RrdReader(path)
    for chunk in reader.stream():
        batch = chunk.to_record_batch()
        key = ("static:" if chunk.is_static else "") + chunk.entity_path
        columns = entities.setdefault(key, {})
        for name, column in zip(batch.schema.names, batch.columns):
            values = column.cast("int64").to_pylist() if name == "stamp" else column.to_pylist()
            columns.setdefault(name, []).extend(values)
    for columns in entities.values():
        if "stamp" in columns:
            order = np.argsort(columns["stamp"], kind="stable")
            for name in columns:
                columns[name] = [columns[name][i] for i in order]
    return entities


def series(entities, entity: str) -> tuple[np.ndarray, np.ndarray]:
    """A scalar entity's (stamps [ns], values)."""
    columns = entities["/" + entity]
    return np.array(columns["stamp"]), np.array([v[0] for v in columns["Scalars:scalars"]])
