"""The pictures of ``ptlab converge``, drawn with matplotlib.

* ``convergence_chart``: relMSE against seconds on log-log axes, one line per estimator,
  with a dotted line of slope -1 (the rate of every unbiased Monte Carlo estimator) through
  the best estimator's first point, and the target error if one is given. Lower is better;
  the horizontal gap between two lines at one error is their ratio of time.
* ``equal_time_strip``: the reference and, for each estimator, its render closest to one
  common time, above a heat map of each pixel's relative squared error (same colour scale
  for all, logarithmic), so one sees *where* each estimator fails.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ptlab.atomic import write_atomically
from ptlab.image import encode_srgb8
from ptlab.measure.metrics import relative_squared_error


def _pyplot():
    """matplotlib's pyplot on the file-only Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(figure, path: Path) -> None:
    write_atomically(path, lambda temporary: figure.savefig(temporary, format="png", dpi=110))


def convergence_chart(
    ladders: list, path: Path, title: str, target: float | None = None, estimated: bool = False
) -> None:
    """Write the log-log chart of relMSE against seconds (``ladders``: lists of
    ``ptlab.measure.converge.Measurement``, one list per estimator); ``estimated``: the
    errors are the renders' own estimates, not measured against a reference."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(6.4, 4.6))
    for ladder in ladders:
        seconds = [rung.seconds for rung in ladder]
        errors = [rung.relmse for rung in ladder]
        axes.loglog(seconds, errors, marker="o", markersize=4, label=ladder[0].estimator)
        last = ladder[-1]
        axes.annotate(
            f"{last.spp} spp",
            (last.seconds, last.relmse),
            fontsize=7,
            textcoords="offset points",
            xytext=(4, 2),
        )
    best = min(ladders, key=lambda ladder: ladder[0].relmse * ladder[0].seconds)[0]
    span = np.array(
        [
            min(r.seconds for ladder in ladders for r in ladder),
            max(r.seconds for ladder in ladders for r in ladder),
        ]
    )
    axes.loglog(
        span, best.relmse * best.seconds / span, ":", color="grey", linewidth=1, label="slope -1 (1 / time)"
    )
    if target is not None:
        axes.axhline(target, color="black", linewidth=0.8, linestyle="--", label=f"relMSE {target:g}")
    axes.set_xlabel("render time (seconds)")
    axes.set_ylabel("relMSE as each render estimates it" if estimated else "relMSE against the reference")
    axes.set_title(title, fontsize=10)
    axes.grid(True, which="both", linewidth=0.3, alpha=0.5)
    axes.legend(fontsize=8)
    figure.tight_layout()
    _save(figure, path)
    plt.close(figure)


def equal_time_strip(ladders: list, reference: np.ndarray, path: Path) -> float:
    """Write the equal-time comparison; return the common time it shows.

    The common time is the longest that every estimator reached; each estimator shows the
    rung closest to it (on a log scale of time).
    """
    plt = _pyplot()
    from matplotlib.colors import LogNorm

    common = min(ladder[-1].seconds for ladder in ladders)
    shown = [min(ladder, key=lambda rung: abs(np.log(rung.seconds / common))) for ladder in ladders]
    columns = 1 + len(shown)
    height, width = reference.shape[:2]
    panel = 2.4
    figure, axes = plt.subplots(
        2, columns, squeeze=False, figsize=(panel * columns, 2 * panel * height / width + 0.9)
    )
    axes[0, 0].imshow(encode_srgb8(reference))
    axes[0, 0].set_title("reference", fontsize=8)
    axes[1, 0].axis("off")
    smallest_error = 1e-4
    norm = LogNorm(vmin=smallest_error, vmax=1.0)
    heat = None
    for column, rung in enumerate(shown, start=1):
        axes[0, column].imshow(encode_srgb8(rung.image))
        axes[0, column].set_title(f"{rung.estimator}\n{rung.spp} spp, {rung.seconds:.1f} s", fontsize=8)
        error = np.maximum(relative_squared_error(rung.image, reference), smallest_error)
        heat = axes[1, column].imshow(error, cmap="inferno", norm=norm)
        axes[1, column].set_title(f"relMSE {rung.relmse:.3g}", fontsize=8)
    for axis in axes.flat:
        axis.set_xticks([])
        axis.set_yticks([])
    colorbar = figure.colorbar(heat, ax=axes[1, 0], location="left", fraction=0.5)
    colorbar.set_label("relative squared error", fontsize=7)
    colorbar.ax.tick_params(labelsize=6)
    figure.suptitle(f"equal time: about {common:.1f} s each", fontsize=9)
    figure.tight_layout()
    _save(figure, path)
    plt.close(figure)
    return common
