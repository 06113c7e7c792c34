"""The ends the page drags when the problem has end fittings: the ports, each carrying its rigid fitting.

A fitting (model/fittings.py) is rigid and clamped at its port, so a port moved and turned moves
and turns the fitting with it: the outlet, where the flexible hose is clamped, follows as one
rigid body.  The port has no roll of its own in the problem file (a point and a direction), so
the page's port frame is the outlet frame carried back along the fitting: turned by the shortest
rotation taking the outlet's d3 onto the port's (about the elbow's bend axis; none for a
straight fitting).  Frames are rows d1, d2, d3 with d3 along the hose, as the fittings' (the end
port's d3 points into its fitting, against the port direction; the end frames without the twist).

Turning a port by the rotation R (world) turns the fitting's `reference` by R, so its clocking
keeps the same meaning, and the outlet frame by R; the outlet's point and direction are the
fitting's (Fitting.outlet, through the problem file), and its frame's d3 is that direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hoseline.mechanics.rotations import rotation_matrix
from hoseline.model.fittings import EndFittings, Fitting
from hoseline.model.mounts import Mount


@dataclass(frozen=True)
class PortAnchor:
    """The ports' frames and the outlets' frames at one moment (the placement the session continues from).

    start_port, end_port: port frames (rows d1, d2, d3); start_outlet, end_outlet: the outlet frames
    then (the end's without the twist); fittings: the EndFittings then (ports and fittings, mm).
    """

    start_port: np.ndarray
    end_port: np.ndarray
    start_outlet: np.ndarray
    end_outlet: np.ndarray
    fittings: EndFittings

    @classmethod
    def at(cls, fittings: EndFittings, start_outlet: np.ndarray, end_outlet: np.ndarray) -> "PortAnchor":
        """The anchor of ports `fittings` with the flexible hose clamped at the outlet frames given (end without twist)."""
        return cls(carried_back(start_outlet, fittings.start_port.direction),
                   carried_back(end_outlet, -fittings.end_port.direction),
                   np.array(start_outlet, dtype=float), np.array(end_outlet, dtype=float), fittings)

    def turns(self, start_port: np.ndarray, end_port: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The world rotations taking the anchor's port frames to `start_port` and `end_port` (rows d1, d2, d3)."""
        return np.asarray(start_port).T @ self.start_port, np.asarray(end_port).T @ self.end_port

    def outlet_frames(self, start_port: np.ndarray, end_port: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The outlet frames (the end's without the twist) of the fittings carried by ports with these frames."""
        start_turn, end_turn = self.turns(start_port, end_port)
        return self.start_outlet @ start_turn.T, self.end_outlet @ end_turn.T

    def fitting_tables(self, tables: dict, start_port: np.ndarray, end_port: np.ndarray) -> dict:
        """The problem file's [fittings] tables with each elbow's reference turned with its port."""
        tables = {name: dict(table) for name, table in tables.items()}
        turns = dict(zip(("start", "end"), self.turns(start_port, end_port)))
        for name, _, fitting in self.fittings.pieces():
            if fitting.reference is not None:
                tables[name]["reference"] = (turns[name] @ fitting.reference).tolist()
        return tables


def carried_back(outlet_frame: np.ndarray, port_d3: np.ndarray) -> np.ndarray:
    """A port frame: `outlet_frame` (rows d1, d2, d3) turned by the shortest rotation taking its d3 onto `port_d3`."""
    outlet_frame = np.asarray(outlet_frame, dtype=float)
    axis = np.cross(outlet_frame[2], port_d3)
    sine, cosine = float(np.linalg.norm(axis)), float(outlet_frame[2] @ port_d3)
    if sine == 0.0:  # a straight fitting: the same direction (an elbow turns by less than 180 degrees)
        return outlet_frame.copy()
    return outlet_frame @ rotation_matrix(axis / sine * math.atan2(sine, cosine)).T


def piece_outline(port_point: np.ndarray, port_frame: np.ndarray, port_direction: np.ndarray, fitting: Fitting,
                  hose_outer_diameter: float) -> dict:
    """A fitting as the page draws it, in its port's frame (so it moves rigidly with the port's gizmo).

    Returns {"centreline": (K, 3) mm in the port frame's axes, "radius": mm}.
    """
    world = fitting.centreline(Mount(np.asarray(port_point, dtype=float), np.asarray(port_direction, dtype=float)))
    return {"centreline": ((world - port_point) @ np.asarray(port_frame).T).tolist(),
            "radius": fitting.radius(hose_outer_diameter)}
