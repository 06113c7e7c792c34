"""hysteresis.csv: the hysteresis band of a twisted hose (procedures/placement/hysteresis.py), one row per twist.

Columns: twist_deg, largest_band_mm (the widest station), then band_station_<k>_mm for every
station k = 0..N (station k sits at arc length k * segment length from the start fitting).
Numbers as in the sweep's data files (8 significant digits, round-off written as 0).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import TYPE_CHECKING

from hoseline.io.atomic import write_text
from hoseline.io.csv_numbers import cell, without_round_off

if TYPE_CHECKING:
    from hoseline.procedures.placement.hysteresis import HysteresisBand

HYSTERESIS_FILE = "hysteresis.csv"


def hysteresis_csv(band: HysteresisBand) -> str:
    """The CSV text of `band` (degrees, mm)."""
    stations = band.band.shape[1]
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(["twist_deg", "largest_band_mm"] + [f"band_station_{k}_mm" for k in range(stations)])
    widths, per_station = without_round_off(band.width), without_round_off(band.band)
    for twist, width, row in zip(without_round_off(band.twists_deg), widths, per_station):
        writer.writerow([cell(twist), cell(width)] + [cell(value) for value in row])
    return stream.getvalue()


def write_hysteresis(band: HysteresisBand, folder: str | Path) -> Path:
    """Write hysteresis.csv into an existing folder (atomically); return its path."""
    path = Path(folder) / HYSTERESIS_FILE
    write_text(path, hysteresis_csv(band))
    return path
