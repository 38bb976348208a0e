"""``ptlab inspect --plot``: one pixel's paths drawn with matplotlib.

Three panels: the image with the pixel marked, and the scene from above and from the side,
its triangles' edges in grey, each sample's path in a colour of its own from the camera
through its vertices, shadow rays dashed to their light points (a cross where the shadow ray
was blocked), and a short stub where a ray escaped the scene.

Both views are seen as the camera sees them, never mirrored: from above, the camera looks up
the panel and the image's left is the panel's left; from the side (from the camera's right),
it looks to the right. Each panel's axes are the scene's own (x, y, z), reversed where the
camera looks along a negative one, so a vertex's coordinates can be read off the ticks.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ptlab.atomic import check_writable_file, write_atomically

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ptlab.camera import Camera
    from ptlab.inspector.records import Sample
    from ptlab.scene import Scene

AXIS_NAMES = "xyz"
#: The most triangles whose edges are drawn (every k-th beyond): matplotlib takes about a
#: second per 60 000 edges, and at the panel's few hundred pixels more are a grey blur.
MOST_TRIANGLES = 20_000


@dataclass(frozen=True)
class View:
    """A panel's projection: the scene's axes drawn across and up, and their directions.

    Attributes:
        title: the panel's title.
        across, up: the scene axes (0, 1, 2 for x, y, z) drawn to the right and upwards.
        across_sign, up_sign: +1 where the axis grows to the right (upwards), -1 where the
            panel shows it reversed.
    """

    title: str
    across: int
    up: int
    across_sign: int
    up_sign: int


def views(camera: Camera) -> tuple[View, View]:
    """The view from above and the view from the side of a scene seen by ``camera``.

    Above is the scene axis closest to the camera's up. From above, the panel's right is the
    horizontal axis closest to the camera's right, signed as it; the panel's up is the other
    horizontal axis, signed so that the panel is a rotation of the view from above (right x
    forward = up), not its mirror image: the camera then looks up the panel. From the side,
    the camera's forward runs to the right and its up upwards (seen from the camera's right).
    """
    right, up = np.asarray(camera.right, float), np.asarray(camera.up, float)
    vertical = int(np.argmax(np.abs(up)))
    vertical_sign = 1 if up[vertical] > 0 else -1
    horizontal = [axis for axis in range(3) if axis != vertical]
    across = max(horizontal, key=lambda axis: abs(right[axis]))
    depth = horizontal[0] if across == horizontal[1] else horizontal[1]
    across_sign = 1 if right[across] > 0 else -1
    # The sign that makes (across, depth, vertical) a right-handed frame, as (right, forward, up) is.
    handed = float(np.dot(np.cross(np.eye(3)[across], np.eye(3)[depth]), np.eye(3)[vertical]))
    depth_sign = int(np.sign(handed)) * across_sign * vertical_sign
    names = [AXIS_NAMES[axis] for axis in (across, depth, vertical)]
    return (
        View(f"from above ({names[0]}, {names[1]})", across, depth, across_sign, depth_sign),
        View(f"from the side ({names[1]}, {names[2]})", depth, vertical, depth_sign, vertical_sign),
    )


def plot(found: Any, path: str | Path, scene: Scene, image: np.ndarray | None = None) -> None:
    """Write the picture of ``found``'s paths in ``scene`` to ``path`` (.png), beside ``image``
    (linear RGB, (H, W, 3)) with the pixel marked, if given."""
    import matplotlib.pyplot as plt

    path = check_writable_file(path)  # (before the drawing, which takes a while)
    figure = draw(found, scene, image)
    try:
        write_atomically(path, lambda temporary: figure.savefig(temporary, format="png", dpi=110))
    finally:
        plt.close(figure)


def draw(found: Any, scene: Scene, image: np.ndarray | None = None) -> Figure:
    """The figure ``plot`` writes: the image (if given), then the views from above and from
    the side (``views``). The caller closes it (``matplotlib.pyplot.close``)."""
    import matplotlib

    from ptlab.image import encode_srgb8

    matplotlib.use("Agg")  # (files only: no display needed)
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    panels = 3 if image is not None else 2
    figure, axes = plt.subplots(1, panels, figsize=(5.2 * panels, 5.2))
    if image is not None:
        ax = axes[0]
        ax.imshow(encode_srgb8(image))
        x, y = found.pixel
        ax.plot([x], [y], marker="s", markersize=9, markerfacecolor="none", markeredgecolor="magenta")
        ax.set_title(f"{found.scene}: pixel ({x}, {y})")
        ax.set_axis_off()
    edges = scene_edges(scene)
    corners = np.asarray(scene.triangles, float).reshape(-1, 3)
    low, high = corners.min(axis=0), corners.max(axis=0)
    margin = 0.08 * (high - low).max()
    colours = plt.get_cmap("tab10")
    camera = np.asarray(scene.camera.position, float)
    for ax, view in zip(axes[panels - 2 :], views(scene.camera), strict=True):
        # One artist for all the edges: matplotlib draws an artist at a time, and one per
        # edge took most of the plot's time (seconds per thousand triangles).
        ax.add_collection(
            LineCollection(list(edges[:, :, [view.across, view.up]]), colors="0.82", linewidths=0.5)
        )
        for k, sample in enumerate(found.samples):
            draw_sample(ax, sample, camera, view.across, view.up, colours(k % 10))
        ax.set_title(view.title)
        # The scene fills the panel (the camera, often far outside it, is left out of view).
        for limits, axis, sign in (
            (ax.set_xlim, view.across, view.across_sign),
            (ax.set_ylim, view.up, view.up_sign),
        ):
            ends = (low[axis] - margin, high[axis] + margin)
            limits(ends if sign > 0 else ends[::-1])
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(AXIS_NAMES[view.across])
        ax.set_ylabel(AXIS_NAMES[view.up])
    figure.suptitle(
        f"{len(found.samples)} samples; paths solid, shadow rays dashed, x: blocked; value "
        + ", ".join(f"{v:.3g}" for v in found.value),
        fontsize=9,
    )
    figure.tight_layout()
    return figure


def scene_edges(scene: Scene, most: int = MOST_TRIANGLES) -> np.ndarray:
    """(3 T, 2, 3): the three edges of each of the scene's T triangles (of every k-th
    triangle, beyond ``most`` of them), as their ends."""
    triangles = np.asarray(scene.triangles, dtype=float)[:: max(1, len(scene.triangles) // most)]
    return np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=2).reshape(-1, 2, 3)


def draw_sample(ax, sample: Sample, camera: np.ndarray, across: int, up: int, colour) -> None:
    """One sample's path: camera to each vertex, shadow rays, escapes."""
    previous_at: dict[int, np.ndarray] = {-1: camera}
    scale = 0.1 * max(1.0, float(np.ptp(np.array([v.position for v in sample.vertices] + [camera]))))
    for v in sample.vertices:
        p = np.array(v.position)
        start = previous_at.get(v.depth - 1, camera)
        ax.plot([start[across], p[across]], [start[up], p[up]], color=colour, linewidth=1.2)
        ax.plot([p[across]], [p[up]], "o", color=colour, markersize=3)
        previous_at[v.depth] = p
        light = v.light
        if light is not None and light.point is not None and light.visible is not None:
            q = np.array(light.point)
            ax.plot([p[across], q[across]], [p[up], q[up]], linestyle="--", color=colour, linewidth=0.8)
            if not light.visible:
                ax.plot([q[across]], [q[up]], "x", color="red", markersize=6)
        if v.sky is not None and v.bsdf is not None and v.bsdf.wi is not None:
            q = p + scale * np.array(v.bsdf.wi)
            ax.plot([p[across], q[across]], [p[up], q[up]], color=colour, linewidth=1.2, linestyle=":")
