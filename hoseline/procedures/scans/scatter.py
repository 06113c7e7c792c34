"""Preset and hysteresis: how far repeated scans of one hose in one mounting lie apart.

Keil & Thomas scanned one hose several times after twisting and releasing its ends and
found the scans 2.33 inches apart: a real hose does not come back to one shape.  Given the
centrelines of several such scans, this finds along the hose the mean centreline, the
envelope radius (the largest distance of any scan from the mean) and the spread (the
largest distance between two scans).  A clearance checked on the mean shape needs the
envelope radius as extra margin; one checked on a single scan or on a model matched to
one, the full spread.  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.procedures.scans.deviation import closest_on_polyline


@dataclass
class ScatterEnvelope:
    """The scatter of repeated scans along the hose.

    s: (m,) arc length along the mean centreline, mm.  mean: (m, 3) mean centreline, mm.
    radius: (m,) largest distance of a scan from the mean, mm.
    spread: (m,) largest distance between two scans, mm.  scans: how many.
    """

    s: np.ndarray
    mean: np.ndarray
    radius: np.ndarray
    spread: np.ndarray
    scans: int

    @property
    def margin(self) -> float:
        """Extra clearance around the mean shape that covers every scan, mm."""
        return float(np.max(self.radius))

    @property
    def max_spread(self) -> float:
        """Largest distance between two scans anywhere along the hose, mm."""
        return float(np.max(self.spread))

    @property
    def s_at_max_spread(self) -> float:
        """Arc length along the mean centreline where the scans spread most, mm."""
        return float(self.s[int(np.argmax(self.spread))])

    def summary(self) -> dict:
        """Scan count, margin, largest spread and where, mm."""
        return {"scans": self.scans, "margin_mm": self.margin, "max_spread_mm": self.max_spread,
                "s_at_max_spread_mm": self.s_at_max_spread}


def scatter_envelope(centerlines: list[np.ndarray], spacing: float = 5.0) -> ScatterEnvelope:
    """Envelope of two or more scan centrelines (each (n_k, 3), ordered from the same end), mm.

    Stations every `spacing` mm along the first centreline; the mean of every scan's closest
    point to a station is the mean centreline there, and each scan's closest point to that
    mean point gives its distance from the mean and from the other scans.
    """
    if len(centerlines) < 2:
        raise ValueError(f"{len(centerlines)} scan(s): the scatter needs at least two scans of the same mounting")
    reference = centerlines[0]
    s_ref = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(reference, axis=0), axis=1))])
    stations = np.linspace(0.0, s_ref[-1], max(2, int(round(s_ref[-1] / spacing)) + 1))
    guide = np.column_stack([np.interp(stations, s_ref, reference[:, k]) for k in range(3)])
    corresponding = np.stack([closest_on_polyline(guide, line)[2] for line in centerlines])  # (scans, m, 3)
    mean = corresponding.mean(axis=0)
    corresponding = np.stack([closest_on_polyline(mean, line)[2] for line in centerlines])
    radius = np.max(np.linalg.norm(corresponding - mean[None], axis=2), axis=0)
    pairs = corresponding[:, None] - corresponding[None, :]
    spread = np.max(np.linalg.norm(pairs, axis=3), axis=(0, 1))
    s_mean = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(mean, axis=0), axis=1))])
    return ScatterEnvelope(s_mean, mean, radius, spread, len(centerlines))
