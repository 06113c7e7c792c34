"""PNG pictures of a sweep for documents: the hose through the poses, and the plots against travel.

matplotlib's object interface with the Agg canvas, as plots.py.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from hoseline.io.atomic import write_bytes
from hoseline.procedures.sweep.result import SweepResult
from hoseline.report.plots import VIEWS, finish_view, png_bytes
from hoseline.report.sweep_figures import FREE_COLOUR, LOCKED_COLOUR, OBSTACLE_COLOUR, VIOLATION_COLOUR, travel_axis

SHAPES_SHOWN = 9  # poses drawn in the view picture besides the worst one
OBSTACLE_TRIANGLES = 3000  # triangles drawn per obstacle, at most


def plot_sweep_view(result: SweepResult, path_png: str | Path) -> Path:
    """3D and three orthographic views: the hose at a few poses (grey), at its worst-clearance pose
    (blue, with the nearest approach in red) and the obstacles (grey points) there."""
    worst = _worst_pose(result)
    figure = Figure(figsize=(16, 12), layout="constrained")
    FigureCanvasAgg(figure)
    axes_3d = figure.add_subplot(2, 2, 1, projection="3d")
    views = [figure.add_subplot(2, 2, k) for k in (2, 3, 4)]
    picked = np.unique(np.linspace(0, result.pose_count - 1, SHAPES_SHOWN).astype(int))
    meshes = [_obstacle_triangles(result, o, worst) for o in result.sweep.obstacles]
    for triangles in meshes:
        axes_3d.add_collection3d(Poly3DCollection(triangles, facecolor=OBSTACLE_COLOUR, edgecolor="none", alpha=0.3))
        for axes, (_, i, j) in zip(views, VIEWS):
            axes.add_collection(PolyCollection(triangles[:, :, [i, j]], facecolor=OBSTACLE_COLOUR, edgecolor="none",
                                               alpha=0.08))
    for axes, (title, i, j) in [(axes_3d, ("3D view", 0, 1))] + list(zip(views, VIEWS)):
        project = (lambda p: (p[:, 0], p[:, 1], p[:, 2])) if axes is axes_3d else (lambda p, i=i, j=j: (p[:, i], p[:, j]))
        for k in picked:
            axes.plot(*project(result.centerlines[k]), color="0.6", linewidth=0.8)
        axes.plot(*project(result.centerlines[worst]), color=LOCKED_COLOUR, linewidth=2.5,
                  label=f"hose at {result.travel_label(worst)}")
        if result.free_centerlines is not None:
            axes.plot(*project(result.free_centerlines[worst]), color=FREE_COLOUR, linestyle="--",
                      label="end free to spin (common error)")
        for clearance in result.clearances:
            pair = np.vstack([clearance.on_hose[worst], clearance.on_obstacle[worst]])
            axes.plot(*project(pair), color=VIOLATION_COLOUR, marker="o", markersize=3)
        if axes is not axes_3d:
            finish_view(axes, title, i, j)
    axes_3d.set(xlabel="x [mm]", ylabel="y [mm]", zlabel="z [mm]", title="hose through the sweep (grey: other poses)")
    everything = np.vstack([result.centerlines.reshape(-1, 3)] + [t.reshape(-1, 3) for t in meshes])
    low, high = everything.min(axis=0), everything.max(axis=0)
    flat = 0.5 * result.sweep.problem.hose.outer_diameter  # a planar sweep spans nothing across its plane
    low, high = low - flat, high + flat
    axes_3d.set(xlim=(low[0], high[0]), ylim=(low[1], high[1]), zlim=(low[2], high[2]))
    axes_3d.set_box_aspect(high - low)
    axes_3d.legend(loc="upper left")
    return write_bytes(path_png, png_bytes(figure))


def plot_sweep_curves(result: SweepResult, path_png: str | Path) -> Path:
    """Clearance (if there are obstacles), smallest bend radius, twisting moment and the free-roll
    separation (if compared) against travel."""
    x, label = travel_axis(result)
    shown = ((_clearance_panel, bool(result.clearances)), (_bend_panel, True), (_twist_panel, True),
             (_separation_panel, result.separation is not None))
    drawn = [panel for panel, drawing in shown if drawing]
    figure = Figure(figsize=(14, 4.5 * math.ceil(len(drawn) / 2)), layout="constrained")
    FigureCanvasAgg(figure)
    panels = figure.subplots(math.ceil(len(drawn) / 2), 2, sharex=True, squeeze=False).ravel()
    for axes, draw in zip(panels, drawn):
        draw(axes, result, x)
        axes.grid(True, alpha=0.3)
        if axes.lines:
            axes.legend()
    for axes in panels[len(drawn):]:  # no empty panel
        axes.remove()
    for axes in panels[:len(drawn)][-2:]:
        axes.set_xlabel(label)
        axes.xaxis.set_tick_params(labelbottom=True)
    return write_bytes(path_png, png_bytes(figure))


def _clearance_panel(axes, result: SweepResult, x: np.ndarray) -> None:
    for clearance in result.clearances:
        line = axes.plot(x, clearance.distance, label=clearance.obstacle.name)[0]
        axes.axhline(clearance.obstacle.clearance, color=line.get_color(), linestyle="--", linewidth=0.8)
    axes.set(title="clearance (dashed: required)", ylabel="mm")


def _bend_panel(axes, result: SweepResult, x: np.ndarray) -> None:
    axes.plot(x, result.min_bend_radius, label="smallest bend radius (inside)")
    if result.sweep.problem.hose.min_bend_radius is not None:
        axes.axhline(result.sweep.problem.hose.min_bend_radius, color=VIOLATION_COLOUR, linestyle="--",
                     label="catalogue minimum")
    axes.set(title="bend radius", ylabel="mm")


def _twist_panel(axes, result: SweepResult, x: np.ndarray) -> None:
    axes.plot(x, result.max_twisting_moment, label="largest |twisting moment|")
    axes.plot(x, result.max_differential_torque, label="largest |differential torque|")
    axes.set(title="twisting moment", ylabel="N*mm")


def _separation_panel(axes, result: SweepResult, x: np.ndarray) -> None:
    axes.plot(x, result.separation, color=FREE_COLOUR, label="clamped vs end free to spin")
    axes.set(title="separation of the free-roll answer", ylabel="mm")


def _worst_pose(result: SweepResult) -> int:
    """The pose of least clearance to any obstacle (of smallest bend radius without obstacles)."""
    if result.clearances:
        return int(np.argmin(np.min([c.distance for c in result.clearances], axis=0)))
    return int(np.argmin(result.min_bend_radius))


def _obstacle_triangles(result: SweepResult, obstacle, k: int) -> np.ndarray:
    """At most OBSTACLE_TRIANGLES triangles (T, 3, 3) of an obstacle, where it is at pose k (mm)."""
    step = max(1, len(obstacle.faces) // OBSTACLE_TRIANGLES)
    return result.sweep.pose(obstacle.body, k).points(obstacle.vertices)[obstacle.faces[::step]]

