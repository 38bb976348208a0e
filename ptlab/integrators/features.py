"""Feature images: what a denoiser is given beside the noisy colour, gathered by the path
tracer from the same samples.

Intel Open Image Denoise (OIDN), like most denoisers for path tracing, is guided by two
images that are nearly noise-free where the colour is not, and that show where the picture's
edges are (OIDN's documentation, "RT" filter):

* **albedo**: the fraction of light the first surface reflects, per channel, in [0, 1];
* **normal**: the shading normal there.

Both are taken at each path's *first hit that is not a perfect mirror or glass*: a mirror's
albedo would be the same everywhere in it, while what it shows is the surface it reflects, so
the path is followed through mirrors and glass, as OIDN's documentation asks. The albedo is one
sample of the material's directional albedo, the bounce weight f cos / pdf that the path
tracer draws there anyway (the ``albedo`` debug view's estimate, ``ptlab.integrators.debug``):
any material gives one without being asked for a colour, and a diffuse surface's is its albedo
exactly. It is clipped to [0, 1], as OIDN wants it.

A third image is kept apart instead of being denoised: **direct**, the emission a path sees
before that first hit (a light seen by the camera, or in a mirror). A small, very bright
light is what a denoiser spreads into the dark pixels around it; the renderers that denoise
keep it out and add it back afterwards (``ptlab.denoise``).

The path tracer reports to ``FeatureBuffers`` through one hook per step, as it reports to the
inspector (``ptlab.integrators.wavefront.recorder``): while no features are gathered each
hook costs a lookup. The buffers have a row per path, as the film does in a render
(``ptlab.rendering.jobs``), which sums each pixel's paths afterwards.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

import numpy as np

from ptlab.vectors import take_rows

#: The feature images, in the order of ``FeatureBuffers.values``' columns.
FEATURES = ("direct", "albedo", "normal")


class FeatureBuffers:
    """Per film row (a path): its direct emission, and the albedo and normal of its first
    hit that is not a mirror or glass.

    Attributes:
        values: (rows, 9) float32, the three images side by side (``FEATURES``' order);
        direct, albedo, normal: its (rows, 3) columns.
        found: (rows,) bool: the path has had that first hit (its albedo and normal are set).
    """

    def __init__(self, rows: int):
        # (One array, the three images its columns: summed per pixel as one, with no copy.
        # Column by column, float32 like the paths' radiance: rows are set 3x faster so than
        # as float64 rows; each pixel's sums are float64, ``ptlab.rendering.jobs``.)
        self.values = np.zeros((rows, 3 * len(FEATURES)), dtype=np.float32, order="F")
        self.direct, self.albedo, self.normal = (self.values[:, 3 * k : 3 * k + 3] for k in range(3))
        self.found = np.zeros(rows, dtype=bool)

    def emission(self, pixel: np.ndarray, sees_emission: np.ndarray, radiance: np.ndarray) -> None:
        """Emission ``radiance`` (N, 3) added to film rows ``pixel`` (N,) by rays that count
        it in full (``sees_emission``: from the camera or a mirror or glass): the part from
        paths that have not yet had their first hit is direct."""
        # (A path before its first hit came only through mirrors and glass, so it sees
        # emission in full: the candidates are those rows, a few in a closed room.)
        candidates = np.flatnonzero(sees_emission)
        if len(candidates) == 0:
            return
        direct = candidates[~self.found.take(pixel.take(candidates))]
        rows = pixel.take(direct)
        values = np.asarray(take_rows(radiance, direct), dtype=np.float32)
        finite = np.isfinite(values).all(axis=1)  # (the film leaves such samples out too)
        np.add.at(self.direct, rows[finite], values[finite])

    def first_hits(self, pixel: np.ndarray, sees_emission: np.ndarray, delta: np.ndarray, n, weight) -> None:
        """At a bounce: the vertices of film rows ``pixel`` that are their path's first hit
        not on a mirror or glass (not ``delta``) record ``n`` (N, 3) and, as the albedo, the
        bounce weight ``weight`` (N, 3) clipped to [0, 1]."""
        candidates = np.flatnonzero(sees_emission & ~delta)
        if len(candidates) == 0:
            return
        rows = pixel.take(candidates)
        first = ~self.found.take(rows)
        if not first.all():
            candidates, rows = candidates[first], rows[first]
        # (A path's rows are its own: each is set once, by plain assignment, column by column.)
        for c in range(3):
            albedo = np.clip(weight[:, c].take(candidates), 0.0, 1.0)
            self.albedo[:, c][rows] = np.where(np.isnan(albedo), np.float32(0), albedo)
            self.normal[:, c][rows] = n[:, c].take(candidates)
        self.found[rows] = True


_features: ContextVar[FeatureBuffers | None] = ContextVar("features", default=None)


def features() -> FeatureBuffers | None:
    """The buffers of ``gathering_features`` under way, or None (the path tracer's hooks:
    ``if (aov := features()) is not None: aov.<step>(...)``)."""
    return _features.get()


@contextmanager
def gathering_features(rows: int) -> Iterator[FeatureBuffers]:
    """Gather the features of film rows 0, ..., ``rows`` - 1 while the block runs."""
    buffers = FeatureBuffers(rows)
    token = _features.set(buffers)
    try:
        yield buffers
    finally:
        _features.reset(token)
