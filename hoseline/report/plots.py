"""Pictures of placed hoses: the shapes in 3D and in three views, and curvature and torque along the hose.

Uses matplotlib's object interface with the Agg canvas, so it works without a
display and does not change the backend of a program that imports it.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from hoseline.io.atomic import write_bytes
from hoseline.model.mounts import Mount
from hoseline.procedures.placement.result import Result

# (title, index of the horizontal axis, index of the vertical axis)
VIEWS = (("top view (x-y)", 0, 1), ("front view (x-z)", 0, 2), ("side view (y-z)", 1, 2))
AXIS_NAMES = "xyz"
MOUNT_COLOUR = "0.3"


def plot_shapes(results: Sequence[Result], labels: Sequence[str], path_png: str | Path) -> Path:
    """Write a PNG comparing placed hoses.

    Panels: a 3D view and the three orthographic views of each centreline, with the
    mounts marked (dot at the fitting tip, arrow along the direction into the hose),
    then curvature (1/mm) and twisting moment (N*mm) along the arc length s (mm).

    results: the results to draw; labels: one legend entry per result; path_png: output file.
    Returns path_png.
    """
    if len(results) != len(labels):
        raise ValueError(f"plot_shapes: {len(results)} results but {len(labels)} labels")
    figure = Figure(figsize=(18, 11), layout="constrained")
    FigureCanvasAgg(figure)
    axes_3d = figure.add_subplot(2, 3, 1, projection="3d")
    views = [figure.add_subplot(2, 3, k) for k in (2, 3, 4)]
    axes_curvature = figure.add_subplot(2, 3, 5)
    axes_torque = figure.add_subplot(2, 3, 6)

    arrow = 0.1 * max(r.problem.hose.length for r in results)
    for result, label in zip(results, labels):
        points = result.centerline
        line = axes_3d.plot(points[:, 0], points[:, 1], points[:, 2], label=label)[0]
        for axes, (_, i, j) in zip(views, VIEWS):
            axes.plot(points[:, i], points[:, j], color=line.get_color())
        axes_curvature.plot(result.s, result.curvature, color=line.get_color(), label=label)
        axes_torque.plot(result.s, result.twisting_moment, color=line.get_color(), label=label)
        for mount in (result.problem.start, result.problem.end):
            _draw_mount(axes_3d, views, mount, arrow)

    arrow_tips = [m.point + arrow * m.direction for r in results for m in (r.problem.start, r.problem.end)]
    _finish_3d(axes_3d, np.vstack([r.centerline for r in results] + arrow_tips))
    for axes, view in zip(views, VIEWS):
        finish_view(axes, *view)
    _mark_bend_limit(axes_curvature, results[0])
    axes_curvature.set(title="curvature along the hose", xlabel="s [mm]", ylabel="curvature [1/mm]")
    axes_torque.set(title="twisting moment along the hose", xlabel="s [mm]", ylabel="twisting moment [N*mm]")
    for axes in (axes_curvature, axes_torque):
        axes.grid(True, alpha=0.3)
        axes.legend()

    return write_bytes(path_png, png_bytes(figure, dpi=100))


def finish_view(axes, title: str, i: int, j: int) -> None:
    """Title, axis labels (mm), equal scale and grid of an orthographic view: coordinate i across, j up."""
    axes.set(title=title, xlabel=f"{AXIS_NAMES[i]} [mm]", ylabel=f"{AXIS_NAMES[j]} [mm]")
    axes.set_aspect("equal", adjustable="datalim")
    axes.grid(True, alpha=0.3)


def png_bytes(figure: Figure, dpi: int = 90) -> bytes:
    """The figure as PNG file content."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi)
    return buffer.getvalue()


def _draw_mount(axes_3d, views, mount: Mount, length: float) -> None:
    """Dot at the fitting tip and an arrow of `length` mm along the direction into the hose."""
    p, d = mount.point, mount.direction * length
    axes_3d.scatter(*p, color=MOUNT_COLOUR, s=20)
    axes_3d.quiver(*p, *d, color=MOUNT_COLOUR)
    for axes, (_, i, j) in zip(views, VIEWS):
        axes.plot(p[i], p[j], "o", color=MOUNT_COLOUR, markersize=4)
        arrow = {"arrowstyle": "->", "color": MOUNT_COLOUR}
        axes.annotate("", xy=(p[i] + d[i], p[j] + d[j]), xytext=(p[i], p[j]), arrowprops=arrow)


def _finish_3d(axes, points: np.ndarray) -> None:
    """Equal scale on all three axes, labels and legend."""
    low, high = points.min(axis=0), points.max(axis=0)
    centre, half = 0.5 * (low + high), 0.5 * max(float(np.max(high - low)), 1.0)
    axes.set(xlim=(centre[0] - half, centre[0] + half), ylim=(centre[1] - half, centre[1] + half),
             zlim=(centre[2] - half, centre[2] + half), xlabel="x [mm]", ylabel="y [mm]", zlabel="z [mm]")
    axes.set_box_aspect((1, 1, 1))
    axes.set_title("3D view")
    axes.legend()


def _mark_bend_limit(axes, result: Result) -> None:
    """Horizontal line at the curvature of the catalogue minimum bend radius, if the hose has one."""
    hose = result.problem.hose
    if hose.min_bend_radius is not None:
        limit = 1.0 / (hose.min_bend_radius + hose.outer_radius)
        axes.axhline(limit, color="red", linestyle="--", label=f"min bend radius {hose.min_bend_radius:g} mm")
