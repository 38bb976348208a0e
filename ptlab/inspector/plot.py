"""``ptlab inspect --plot``: one pixel's paths drawn with matplotlib.

Three panels: the image with the pixel marked, and the scene from above (x, z) and from the
side (z, y), its triangles' edges in grey, each sample's path in a colour of its own from the
camera through its vertices, shadow rays dashed to their light points (a cross where the
shadow ray was blocked), and a short stub where a ray escaped the scene.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ptlab.atomic import write_atomically

if TYPE_CHECKING:
    from ptlab.inspector.records import Sample
    from ptlab.scene import Scene

#: The views: a title and the coordinates (of x, y, z) drawn across and up.
VIEWS = (("from above (x, z)", 0, 2), ("from the side (z, y)", 2, 1))


def plot(found: Any, path: str | Path, scene: Scene, image: np.ndarray | None = None) -> None:
    """Write the picture of ``found``'s paths in ``scene`` to ``path`` (.png), beside ``image``
    (linear RGB, (H, W, 3)) with the pixel marked, if given."""
    import matplotlib

    from ptlab.image import encode_srgb8

    matplotlib.use("Agg")  # (files only: no display needed)
    import matplotlib.pyplot as plt

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
    colours = plt.get_cmap("tab10")
    for ax, (title, across, up) in zip(axes[panels - 2 :], VIEWS, strict=True):
        for a, b in edges:
            ax.plot([a[across], b[across]], [a[up], b[up]], color="0.82", linewidth=0.5, zorder=0)
        for k, sample in enumerate(found.samples):
            draw_sample(ax, sample, np.asarray(scene.camera.position, float), across, up, colours(k % 10))
        ax.set_title(title)
        # The scene fills the panel (the camera, often far outside it, is left out of view).
        low, high = (
            np.asarray(scene.triangles).reshape(-1, 3).min(axis=0),
            np.asarray(scene.triangles).reshape(-1, 3).max(axis=0),
        )
        margin = 0.08 * (high - low).max()
        ax.set_xlim(low[across] - margin, high[across] + margin)
        ax.set_ylim(low[up] - margin, high[up] + margin)
        ax.set_aspect("equal", adjustable="box")
        names = "xyz"
        ax.set_xlabel(names[across])
        ax.set_ylabel(names[up])
    figure.suptitle(
        f"{len(found.samples)} samples; paths solid, shadow rays dashed, x: blocked; value "
        + ", ".join(f"{v:.3g}" for v in found.value),
        fontsize=9,
    )
    figure.tight_layout()
    write_atomically(Path(path), lambda temporary: figure.savefig(temporary, format="png", dpi=110))
    plt.close(figure)


def scene_edges(scene: Scene, most: int = 6000) -> list[tuple[np.ndarray, np.ndarray]]:
    """Edges of the scene's triangles (of every k-th triangle, beyond ``most`` of them)."""
    triangles = np.asarray(scene.triangles, dtype=float)
    step = max(1, len(triangles) // most)
    return [(t[i], t[(i + 1) % 3]) for t in triangles[::step] for i in range(3)]


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
