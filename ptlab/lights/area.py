"""Area lights: every emissive triangle of the scene, sampled by power.

Next-event estimation picks a point ``y`` on the lights and turns the pdf of that choice
from area into solid angle (GAMES101 lecture 16, "sampling the light"; pbrt-v4 section
12.4). A triangle is chosen with probability proportional to its power, area x mean(Le)
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

import math
from dataclasses import dataclass

import numpy as np

from ptlab.lights.base import LightLiSample, LightPoint
from ptlab.sampling import pick_from_cdf, uniform_triangle
from ptlab.vectors import dot


@dataclass
class ShapeSample:
    """Points sampled on the emissive triangles, one per shading point, with the density of
    each (pbrt-v4's ``ShapeSample``: a point on a shape and its pdf), and what the light
    there sends.

    Attributes (where every light has the same value, a read-only broadcast view):
        points: (N, 3) float32 positions on the lights.
        normals: (N, 3) float32 unit front-face normals there.
        radiance: (N, 3) float32 emitted radiance Le.
        offset: (N, 1) float32 distance that rays aimed at the point stop short of it.
        pdf_area: (N,) float32 area density with which the point was chosen.
        target: (N, 3) float32 ``points + offset * normals``, where shadow rays aim: just off
            the light's front, so that the light itself does not block them.
    """

    points: np.ndarray
    normals: np.ndarray
    radiance: np.ndarray
    offset: np.ndarray
    pdf_area: np.ndarray
    target: np.ndarray


#: ``ShapeSample`` by its first name, for code written when chapter 7 used it.
LightSample = ShapeSample


def triangle_areas(triangles: np.ndarray) -> np.ndarray:
    """(T,) float64 areas of (T, 3, 3) ``triangles``: half the length of (v1 - v0) x (v2 - v0)
    (0 for a triangle whose corners lie on a line)."""
    v0, v1, v2 = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    return 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)


def triangle_normals(triangles: np.ndarray) -> np.ndarray:
    """(T, 3) float64 unit normals of (T, 3, 3) ``triangles`` on their front face, the side
    (v1 - v0) x (v2 - v0) points to (NaN for a triangle of zero area)."""
    v0, v1, v2 = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    cross = np.cross(v1 - v0, v2 - v0)
    return cross / np.linalg.norm(cross, axis=1, keepdims=True)


def area_times_radiance(areas: np.ndarray, radiance: np.ndarray) -> np.ndarray:
    """(L,) area x mean(Le) of L emissive triangles of (L,) ``areas`` and (L, 3) radiances
    ``radiance``: each one's power over pi (pbrt-v4's ``DiffuseAreaLight::Phi`` for lights
    that emit from one face), the mean taken in ``radiance``'s float type."""
    return areas * radiance.mean(axis=1)


def solid_angle_pdf(pdf_area: np.ndarray, dist2: np.ndarray, cos_theta_light: np.ndarray) -> np.ndarray:
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

    #: A triangle is found by rays as well as by light sampling (not a delta light).
    is_delta = False

    def __init__(
        self,
        v0: np.ndarray,
        v1: np.ndarray,
        v2: np.ndarray,
        radiance: np.ndarray,
        offset: np.ndarray,
    ):
        v0, v1, v2 = (np.asarray(a, dtype=np.float64) for a in (v0, v1, v2))
        triangles = np.stack([v0, v1, v2], axis=1)
        self.areas = triangle_areas(triangles)
        self.total_area = float(self.areas.sum())
        radiance = np.asarray(radiance, dtype=np.float64)
        power = area_times_radiance(self.areas, radiance)
        self.total_power = float(power.sum())
        # float32 like the renderer's random numbers: a search with mixed types converts
        # every u to float64 first (2x slower).
        self.cdf = (np.cumsum(power) / self.total_power).astype(np.float32)
        self.v0 = v0.astype(np.float32)
        self.e1 = (v1 - v0).astype(np.float32)
        self.e2 = (v2 - v0).astype(np.float32)
        self.normals = triangle_normals(triangles).astype(np.float32)
        self.radiance = radiance.astype(np.float32)
        # What `sample` looks up per chosen triangle: v0, e1, e2, the unit normal, Le, the
        # offset and pdf_area, each as rows of a (rows, L) table.
        fields = dict(
            v0=self.v0.T,
            e1=self.e1.T,
            e2=self.e2.T,
            normals=self.normals.T,
            radiance=self.radiance.T,
            offset=np.asarray(offset, np.float32)[None],
            pdf_area=self.pdf_area(self.radiance)[None],
        )
        # offset x normal per light, the step from a sampled point to its shadow ray's target:
        # the same float32 product as per sample, made once (arithmetic between two of the
        # broadcast views below is several times slower than with one array).
        fields["lift"] = fields["offset"] * fields["normals"]
        # Fields that are the same for every light (in the Cornell box: the normal, Le, the
        # offset and pdf_area) are kept as one column that broadcasts to every sample; the
        # others are packed in one table, gathered with one `take` per sample.
        self._same = {name: rows[:, :1] for name, rows in fields.items() if (rows == rows[:, :1]).all()}
        varying = [name for name in fields if name not in self._same]
        self._packed = np.vstack([fields[name] for name in varying] + [np.zeros((0, len(v0)))]).astype(
            np.float32
        )  # (one light: nothing varies)
        starts = np.cumsum([0] + [len(fields[name]) for name in varying])
        self._rows = {name: slice(a, b) for name, a, b in zip(varying, starts[:-1], starts[1:], strict=True)}

    def __len__(self) -> int:
        return len(self.areas)

    @property
    def power(self) -> float:
        """The radiant flux of all the triangles, pi x area x mean(Le) (pbrt-v4's
        ``DiffuseAreaLight::Phi`` for lights that emit from one face)."""
        return math.pi * self.total_power

    def pdf_area(self, radiance: np.ndarray) -> np.ndarray:
        """(N,) float32 area density of sampling a point on a light of radiance ``radiance``
        (N, 3): mean(Le) / total power (0 on surfaces that do not emit)."""
        return (radiance.mean(axis=1) / np.float32(self.total_power)).astype(np.float32)

    def pdf_li(self, found: LightPoint) -> np.ndarray:
        """(N,) the solid-angle density of ``sample_li`` at light points ``found``:
        ``pdf_area`` turned into solid angle (``solid_angle_pdf``)."""
        assert found.dist2 is not None
        assert found.cos_theta_light is not None
        return solid_angle_pdf(self.pdf_area(found.radiance), found.dist2, found.cos_theta_light)

    def sample(self, u: np.ndarray) -> ShapeSample:
        """Points on the lights from (N, 2) uniforms.

        ``u[:, 0]`` picks the triangle with probability power / total_power and is then
        stretched back to [0, 1) inside the interval of the cdf that picked it
        (``pick_from_cdf``), to serve with ``u[:, 1]`` as the point's coordinates on that
        triangle. The map from u to points is one-to-one, so a pair of stratified uniforms
        gives stratified points on the lights (``ptlab.samplers``).
        """
        index, stretched = pick_from_cdf(self.cdf, u[:, 0])
        data = self._packed.take(index, axis=1)  # (rows, N): rows are contiguous

        def field(name: str) -> np.ndarray:
            """(N, k) per sample: gathered rows, or one column broadcast to every sample
            (a read-only view, no copy); transposed from (k, N), so in the column-major
            layout of ptlab.vectors."""
            if name in self._same:
                return np.broadcast_to(self._same[name], (self._same[name].shape[0], len(u))).T
            return data[self._rows[name]].T

        b1, b2 = uniform_triangle(np.stack([stretched, u[:, 1]]).T)
        points = field("v0") + b1[:, None] * field("e1") + b2[:, None] * field("e2")
        return ShapeSample(
            points=points,
            normals=field("normals"),
            radiance=field("radiance"),
            offset=field("offset"),
            pdf_area=field("pdf_area")[:, 0],
            target=points + field("lift"),
        )

    def sample_li(self, p: np.ndarray, u: np.ndarray) -> LightLiSample:
        """A point on the triangles (``sample``) as seen from the points ``p`` (N, 3).

        The area density turns into one per solid angle, pdf_area |x - x'|^2 / cos(theta')
        (``solid_angle_pdf``); a light seen from behind sends no radiance.
        """
        light = self.sample(u)
        to_light = light.points - p
        dist2 = dot(to_light, to_light)
        wi = to_light / np.sqrt(dist2)[:, None]
        cos_theta_light = -dot(light.normals, wi)
        front = cos_theta_light > 0
        return LightLiSample(
            wi=wi,
            radiance=light.radiance * front[:, None],
            pdf=np.where(front, solid_angle_pdf(light.pdf_area, dist2, cos_theta_light), 0),
            target=light.target,
        )
