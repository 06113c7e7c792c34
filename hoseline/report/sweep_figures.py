"""The interactive figures of the sweep report (plotly): the 3D view with a pose slider, and the plots.

Both are plotly figures; sweep_html.py puts them in one self-contained page.  To keep the page
small, coordinates are sent in single precision (about 1e-4 mm at a metre) and a slider frame
carries only what changes from pose to pose.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from hoseline.procedures.geometry.contact_shapes import contact_meshes
from hoseline.procedures.sweep.result import SweepResult

MAX_FRAMES = 200  # poses shown by the slider of the 3D view (evenly picked; the plots show all)
LOCKED_COLOUR = "#1f4e9c"
FREE_COLOUR = "#e07b00"
OBSTACLE_COLOUR = "#9a9a9a"
CONTACT_OBSTACLE_COLOUR = "#a0764a"  # the [contact] obstacles the hose rests on
CONTACT_COLOURS = "YlOrRd"  # contact points, by the size of the push
PLANE_MARGIN = 1.2  # a [contact] plane is drawn as a square this many times the span of the hose over the sweep
OK_COLOUR = "#2a9d3c"
VIOLATION_COLOUR = "#d62828"
MOUNT_ARROW = 20.0  # mm, length of the arrows along the fitting directions


def shown_poses(result: SweepResult) -> np.ndarray:
    """Indices of the poses the 3D view's slider steps through (all, or MAX_FRAMES evenly picked)."""
    count = result.pose_count
    if count <= MAX_FRAMES:
        return np.arange(count)
    return np.unique(np.round(np.linspace(0, count - 1, MAX_FRAMES)).astype(int))


def travel_axis(result: SweepResult) -> tuple[np.ndarray, str]:
    """What the plots use as abscissa: the travel for a one-stage sweep, else the pose number."""
    stages = result.sweep.stages
    if len(stages) == 1:
        unit = f" [{stages[0].unit}]" if stages[0].unit else ""
        return result.sweep.travel, f"{stages[0].name}{unit}"
    names = list(dict.fromkeys(s.name for s in stages))  # in order, each once
    return np.arange(result.pose_count), "pose number (" + ", ".join(names) + ")"


def view_figure(result: SweepResult) -> go.Figure:
    """3D view: obstacles (and [contact] obstacles), the hose, its mounts, the nearest approaches and the contact
    points, with a slider through the poses."""
    sweep = result.sweep
    figure = go.Figure()
    moving = []  # (trace index, obstacle) of obstacles that move with a body ([contact] ones too)
    for obstacle in sweep.obstacles:
        x, y, z = _single(obstacle.vertices).T
        i, j, k = obstacle.faces.T
        figure.add_trace(go.Mesh3d(x=x, y=y, z=z, i=i, j=j, k=k, color=OBSTACLE_COLOUR, opacity=0.45,
                                   name=obstacle.name, showlegend=True, hoverinfo="name", flatshading=True))
        if obstacle.body is not None:
            moving.append((len(figure.data) - 1, obstacle))
    span = np.ptp(result.centerlines.reshape(-1, 3), axis=0).max()
    meshes = contact_meshes(sweep.problem, PLANE_MARGIN * span / sweep.problem.hose.length)
    for index, mesh in enumerate(meshes):
        x, y, z = _single(mesh.vertices).T
        i, j, k = mesh.faces.T
        figure.add_trace(go.Mesh3d(x=x, y=y, z=z, i=i, j=j, k=k, color=CONTACT_OBSTACLE_COLOUR, opacity=0.35,
                                   name=f"{mesh.name} (contact)", showlegend=True, hoverinfo="name", flatshading=True))
        if sweep.contact_body(index) is not None:
            moving.append((len(figure.data) - 1, replace(mesh, body=sweep.contact_body(index))))
    for clearance in result.clearances:  # the worst approach of all poses, marked once
        k = clearance.worst
        pair = np.vstack([clearance.on_hose[k], clearance.on_obstacle[k]])
        figure.add_trace(go.Scatter3d(
            x=pair[:, 0], y=pair[:, 1], z=pair[:, 2], mode="markers", marker=dict(symbol="x", size=5, color=VIOLATION_COLOUR),
            name=f"worst clearance to {clearance.obstacle.name}: {clearance.distance[k]:.1f} mm ({result.travel_label(k)})",
        ))
    dynamic_start = len(figure.data)
    first = int(shown_poses(result)[0])
    for trace in _pose_traces(result, first):
        figure.add_trace(trace)
    dynamic = list(range(dynamic_start, len(figure.data))) + [index for index, _ in moving]

    frames, steps = [], []
    for k in shown_poses(result):
        name = str(int(k))
        frames.append(go.Frame(name=name, data=_pose_changes(result, int(k)) + _moved_obstacles(result, int(k), moving),
                               traces=dynamic))
        steps.append(dict(method="animate", label=result.travel_label(int(k)),
                          args=[[name], dict(mode="immediate", frame=dict(duration=0, redraw=True), transition=dict(duration=0))]))
    figure.frames = frames
    figure.update_layout(
        scene=dict(aspectmode="data", xaxis_title="x [mm]", yaxis_title="y [mm]", zaxis_title="z [mm]"),
        margin=dict(l=0, r=0, t=30, b=0),
        height=640,
        legend=dict(x=0.0, y=1.0, bgcolor="rgba(255,255,255,0.7)"),
        sliders=[dict(active=0, steps=steps, currentvalue=dict(prefix="pose: "), pad=dict(t=10), x=0.12, len=0.88)],
        updatemenus=[dict(type="buttons", direction="left", showactive=False, x=0.0, y=0.0, xanchor="left",
                          yanchor="top", pad=dict(t=30), buttons=[
            dict(label="play", method="animate",
                 args=[None, dict(frame=dict(duration=80, redraw=True), fromcurrent=True, transition=dict(duration=0))]),
            dict(label="pause", method="animate", args=[[None], dict(mode="immediate", frame=dict(duration=0, redraw=False))]),
        ])],
    )
    return figure


def _pose_traces(result: SweepResult, k: int) -> list:
    """The traces that change from pose to pose, as shown at pose k: the hose(s), the mounts, the nearest approaches,
    the contact points."""
    traces = [go.Scatter3d(mode="lines", name="hose (both ends clamped)", line=dict(color=LOCKED_COLOUR, width=9),
                           customdata=_single(result.s), hovertemplate="s = %{customdata:.1f} mm<extra>hose</extra>")]
    if result.free_centerlines is not None:
        traces.append(go.Scatter3d(mode="lines", name="hose with the end free to spin (common error)",
                                   line=dict(color=FREE_COLOUR, width=3, dash="dash"), hoverinfo="name"))
    traces.append(go.Scatter3d(mode="lines+markers", name="mounts", line=dict(color="black", width=5),
                               marker=dict(size=3, color="black"), hoverinfo="name"))
    traces.extend(go.Scatter3d(mode="lines+markers", showlegend=False, line=dict(width=4), marker=dict(size=3))
                  for _ in result.clearances)
    largest = max([float(np.max(f)) for c in result.contacts for f in c.forces if f.size] + [1e-12])
    traces.extend(go.Scatter3d(mode="markers", name=f"contact with {contact.name} (colour: push, N)",
                               marker=dict(size=5, color=[], colorscale=CONTACT_COLOURS, cmin=0.0, cmax=largest,
                                           showscale=n == 0, colorbar=dict(title="contact push [N]", x=1.0, len=0.5)))
                  for n, contact in enumerate(result.contacts))
    for trace, change in zip(traces, _pose_changes(result, k)):
        trace.update(change)
    return traces


def _pose_changes(result: SweepResult, k: int) -> list:
    """What a slider frame sends for pose k, in the order of _pose_traces: coordinates, and the
    colour and label of each nearest approach."""
    lines = [result.centerlines[k]] + ([] if result.free_centerlines is None else [result.free_centerlines[k]])
    tips = np.vstack([result.start_points[k], result.end_points[k]])
    ends = tips + MOUNT_ARROW * np.vstack([result.start_directions[k], result.end_directions[k]])
    lines.append(np.vstack([tips[0], ends[0], [np.nan] * 3, tips[1], ends[1]]))
    changes = [go.Scatter3d(x=x, y=y, z=z) for x, y, z in (_single(line).T for line in lines)]
    for clearance in result.clearances:
        x, y, z = _single(np.vstack([clearance.on_hose[k], clearance.on_obstacle[k]])).T
        ok = clearance.distance[k] >= clearance.obstacle.clearance
        label = f"{clearance.obstacle.name}: {clearance.distance[k]:.1f} mm<extra></extra>"
        changes.append(go.Scatter3d(x=x, y=y, z=z, line=dict(color=OK_COLOUR if ok else VIOLATION_COLOUR),
                                    hovertemplate=label))
    for contact in result.contacts:  # where the hose presses on each [contact] obstacle, coloured by the push
        x, y, z = _single(contact.points[k]).reshape(-1, 3).T
        forces = _single(contact.forces[k])
        changes.append(go.Scatter3d(x=x, y=y, z=z, marker=dict(color=forces), customdata=forces,
                                    hovertemplate=f"{contact.name}: %{{customdata:.3g}} N<extra></extra>"))
    return changes


def _single(values) -> np.ndarray:
    """Values in single precision, for the page (half the size; 1e-4 mm at a metre is plenty to look at)."""
    return np.asarray(values, dtype=np.float32)


def _moved_obstacles(result: SweepResult, k: int, moving) -> list:
    """The obstacles that move with a body, at pose k (only their vertices change)."""
    traces = []
    for _, obstacle in moving:
        x, y, z = _single(result.sweep.pose(obstacle.body, k).points(obstacle.vertices)).T
        traces.append(go.Mesh3d(x=x, y=y, z=z))
    return traces


def plots_figure(result: SweepResult) -> go.Figure:
    """Clearance (if there are obstacles), contact push and length (with [contact]), bend radius, twisting
    moment, separation (if compared) and reactions against travel."""
    x, label = travel_axis(result)
    x = _single(x)
    labels = [result.travel_label(k) for k in range(result.pose_count)]
    clearance, bend, twist, separation, reactions = (
        "clearance to the obstacles [mm]", "smallest bend radius (inside) [mm]", "twisting moment [N*mm]",
        "end free to spin: separation [mm]", "mount reactions [N]")
    pushes, lying = "contact push [N]", "length in contact [mm]"
    panels = ([clearance] if result.clearances else []) + ([pushes, lying] if result.contacts else []) + \
        [bend, twist] + ([separation] if result.separation is not None else []) + [reactions]  # no empty panels
    figure = make_subplots(rows=len(panels), cols=1, shared_xaxes=True, subplot_titles=panels, vertical_spacing=0.05)
    labelled = set()  # rows whose first curve carries the pose names for the hover

    def add(panel, y, name, colour=None):
        row = panels.index(panel) + 1
        trace = go.Scatter(x=x, y=_single(y), name=name, mode="lines", legendgroup=str(row), line=dict(color=colour),
                           hovertemplate="%{y:.4g}<extra>" + name + "</extra>")
        if row not in labelled:
            labelled.add(row)
            trace.update(text=labels, hovertemplate="%{text}: %{y:.4g}<extra>" + name + "</extra>")
        figure.add_trace(trace, row=row, col=1)

    def add_limit(panel, value, name):
        """A constant as a dashed line from the first to the last pose."""
        row = panels.index(panel) + 1
        figure.add_trace(go.Scatter(x=x[[0, -1]], y=[value, value], name=name, mode="lines", legendgroup=str(row),
                                    line=dict(color=VIOLATION_COLOUR, dash="dash"),
                                    hovertemplate=f"{value:.4g}<extra>{name}</extra>"), row=row, col=1)

    for near in result.clearances:
        add(clearance, near.distance, near.obstacle.name)
    for near in result.clearances:
        add_limit(clearance, near.obstacle.clearance, f"required for {near.obstacle.name}")
    for contact in result.contacts:
        add(pushes, np.linalg.norm(contact.total_force, axis=1), f"{contact.name}")
        add(lying, contact.length_in_contact, f"{contact.name}")
    add(bend, result.min_bend_radius, "smallest bend radius")
    limit = result.sweep.problem.hose.min_bend_radius
    if limit is not None:
        add_limit(bend, limit, "catalogue minimum")
    add(twist, result.max_twisting_moment, "largest |twisting moment|")
    add(twist, result.max_differential_torque, "largest |differential torque|")
    if result.separation is not None:
        add(separation, result.separation, "largest distance, clamped vs free to spin", FREE_COLOUR)
    add(reactions, np.linalg.norm(result.start_force, axis=1), "start mount force")
    add(reactions, np.linalg.norm(result.end_force, axis=1), "end mount force")
    figure.update_xaxes(title_text=label, row=len(panels), col=1)
    figure.update_layout(height=260 * len(panels), margin=dict(l=60, r=20, t=40, b=40), hovermode="x unified")
    return figure
