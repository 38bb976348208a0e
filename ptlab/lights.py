"""Area lights: every emissive triangle of the scene, sampled by power.

Next-event estimation picks a point ``y`` on the lights and turns the pdf of that choice
from area into solid angle (GAMES101 lecture 16, "sampling the light"; pbrt-v4 section
12.2). A triangle is chosen with probability proportional to its power, area x mean(Le)
(pbrt-v4's ``PowerLightSampler``), then a uniform point on it, so a point on triangle i has
the area density

    pdf_area = mean(Le_i) / sum_j (area_j mean(Le_j)).

When every light has the same Le (the Cornell box) that is the homework's
``1 / total_area``: picking by area. With lights of different brightness, picking by area
would spend most samples on big dim lights and few on small bright ones (Veach's test
scene, ``scenes/veach-mis``). (The homework framework picks its two light triangles with
other probabilities while still dividing by the uniform pdf; that is biased.)

Each light emits from its front face only, the side its winding's normal
``(v1 - v0) x (v2 - v0)`` points to.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ptlab.sampling import uniform_triangle


@dataclass
class LightSample:
    """Points sampled on the lights, one per shading point.

    Attributes (where every light has the same value, a read-only broadcast view):
        points: (N, 3) float32 positions on the lights.
        normals: (N, 3) float32 unit front-face normals there.
        radiance: (N, 3) float32 emitted radiance Le.
        offset: (N, 1) float32 distance that rays aimed at the point stop short of it.
        pdf_area: (N,) float32 area density with which the point was chosen.
    """

    points: np.ndarray
    normals: np.ndarray
    radiance: np.ndarray
    offset: np.ndarray
    pdf_area: np.ndarray


def solid_angle_pdf(pdf_area: np.ndarray, dist2: np.ndarray,
                    cos_theta_light: np.ndarray) -> np.ndarray:
    """(N,) density per solid angle of a light point chosen with density ``pdf_area`` per
    area, seen at squared distance ``dist2`` and angle ``cos_theta_light`` to its normal:
    pdf_area |x - x'|^2 / cos (pbrt-v4 eq. 4.9; inf or NaN where cos <= 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return pdf_area * dist2 / cos_theta_light


class AreaLights:
    """All emissive triangles of a scene.

    Args:
        v0, v1, v2: (L, 3) vertices of the emissive triangles.
        radiance: (L, 3) emitted radiance of each.
        offset: (L,) how far rays stay off each triangle (``Scene`` computes it).
    """

    def __init__(self, v0: np.ndarray, v1: np.ndarray, v2: np.ndarray, radiance: np.ndarray,
                 offset: np.ndarray):
        v0, v1, v2 = (np.asarray(a, dtype=np.float64) for a in (v0, v1, v2))
        cross = np.cross(v1 - v0, v2 - v0)
        double_area = np.linalg.norm(cross, axis=1)
        self.areas = 0.5 * double_area
        self.total_area = float(self.areas.sum())
        radiance = np.asarray(radiance, dtype=np.float64)
        power = self.areas * radiance.mean(axis=1)
        self.total_power = float(power.sum())
        # float32 like the renderer's random numbers: a search with mixed types converts
        # every u to float64 first (2x slower).
        self.cdf = (np.cumsum(power) / self.total_power).astype(np.float32)
        self.v0 = v0.astype(np.float32)
        self.e1 = (v1 - v0).astype(np.float32)
        self.e2 = (v2 - v0).astype(np.float32)
        self.normals = (cross / double_area[:, None]).astype(np.float32)
        self.radiance = radiance.astype(np.float32)
        # What `sample` looks up per chosen triangle: v0, e1, e2, the unit normal, Le, the
        # offset, pdf_area, the cdf below the triangle's interval and 1 / the interval's width
        # (to stretch u back to [0, 1)), each as rows of a (rows, L) table.
        cdf_below = np.concatenate([[0.0], self.cdf[:-1]]).astype(np.float32)
        width = np.maximum(self.cdf - cdf_below, np.float32(1e-30))
        fields = dict(v0=self.v0.T, e1=self.e1.T, e2=self.e2.T, normals=self.normals.T,
                      radiance=self.radiance.T, offset=np.asarray(offset, np.float32)[None],
                      pdf_area=self.pdf_area(self.radiance)[None], cdf_below=cdf_below[None],
                      stretch=(1 / width)[None])
        # Fields that are the same for every light (in the Cornell box: the normal, Le, the
        # offset, pdf_area and the stretch) are kept as one column that broadcasts to every
        # sample; the others are packed in one table, gathered with one `take` per sample.
        self._same = {name: rows[:, :1] for name, rows in fields.items()
                      if (rows == rows[:, :1]).all()}
        varying = [name for name in fields if name not in self._same]
        self._packed = np.vstack([fields[name] for name in varying] + [np.zeros((0, len(v0)))]
                                 ).astype(np.float32)     # (one light: nothing varies)
        starts = np.cumsum([0] + [len(fields[name]) for name in varying])
        self._rows = {name: slice(a, b)
                      for name, a, b in zip(varying, starts[:-1], starts[1:], strict=True)}

    def __len__(self) -> int:
        return len(self.areas)

    def pdf_area(self, radiance: np.ndarray) -> np.ndarray:
        """(N,) float32 area density of sampling a point on a light of radiance ``radiance``
        (N, 3): mean(Le) / total power (0 on surfaces that do not emit)."""
        return (radiance.mean(axis=1) / np.float32(self.total_power)).astype(np.float32)


    def sample(self, u: np.ndarray) -> LightSample:
        """Points on the lights from (N, 2) uniforms.

        ``u[:, 0]`` picks the triangle and is then stretched back to [0, 1) inside the
        interval of the cdf that picked it, to serve with ``u[:, 1]`` as the point's
        coordinates on that triangle. The map from u to points is one-to-one, so a pair of
        stratified uniforms gives stratified points on the lights (``ptlab.samplers``).
        """
        # A triangle with probability power / total_power (inverse-CDF lookup): the number of
        # cdf entries at or below u. For a handful of lights (the Cornell box has two)
        # counting them pass by pass is ~10x faster than a binary search.
        u0 = u[:, 0]
        if len(self.cdf) <= 16:
            index = np.zeros(len(u0), dtype=np.intp)
            for edge in self.cdf[:-1]:
                index += u0 >= edge
        else:
            index = np.searchsorted(self.cdf, u0, side="right")
            np.minimum(index, len(self.areas) - 1, out=index)  # guards cdf[-1] rounding below 1
        data = self._packed.take(index, axis=1)     # (rows, N): rows are contiguous

        def field(name: str) -> np.ndarray:
            """(N, k) per sample: gathered rows, or one column broadcast to every sample
            (a read-only view, no copy); transposed from (k, N), so in the column-major
            layout of ptlab.vectors."""
            if name in self._same:
                return np.broadcast_to(self._same[name], (self._same[name].shape[0], len(u0))).T
            return data[self._rows[name]].T

        # u0 within [cdf_below, cdf_at), stretched to [0, 1) (and kept below 1 in float32).
        stretched = (u0 - field("cdf_below")[:, 0]) * field("stretch")[:, 0]
        np.minimum(stretched, np.float32(1 - 2.0 ** -24), out=stretched)
        b1, b2 = uniform_triangle(np.stack([stretched, u[:, 1]]).T)
        points = field("v0") + b1[:, None] * field("e1") + b2[:, None] * field("e2")
        return LightSample(points=points, normals=field("normals"), radiance=field("radiance"),
                           offset=field("offset"), pdf_area=field("pdf_area")[:, 0])
