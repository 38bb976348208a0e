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

Besides triangles, a scene may have **point lights** and a **sky** (``PointLights``,
``Sky``, below). Every kind of light answers the same questions (``Light``, pbrt-v4's
``Light`` interface, section 12.1): ``sample_li``, the direction to the light, the radiance
arriving from it and the density of that choice; ``pdf_li``, the density with which
``sample_li`` would have chosen a light point that a ray found instead (what MIS weighs
with); and ``is_delta``, whether a ray can find it at all. Light sampling first picks which
kind of light a sample comes from (``LightSampler``, which alone holds the probability
``pmf`` of each kind), then that kind's ``sample_li`` picks a light and a point on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ptlab.sampling import uniform_sphere, uniform_triangle
from ptlab.vectors import dot, take_rows


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


@dataclass
class LightLiSample:
    """One light sample per shading point, seen from the point (pbrt-v4's ``LightLiSample``).

    Attributes:
        wi: (N, 3) float32 unit directions from the points toward the lights.
        radiance: (N, 3) float32 radiance arriving along ``wi`` (0 where none can).
        pdf: (N,) float32 density of the choice, per solid angle; for a point light, which
            sits in one direction only, the probability of having picked it (a delta light).
        target: (N, 3) float32 where a shadow ray toward the light stops.
    """

    wi: np.ndarray
    radiance: np.ndarray
    pdf: np.ndarray
    target: np.ndarray


@dataclass
class LightPoint:
    """Where rays from shading points found a light that is not a delta light: the light
    point that ``pdf_li`` gives the density of (Mitsuba 3 builds its ``DirectionSample3f``
    from a hit for ``Emitter::pdf_direction`` the same way).

    Attributes:
        radiance: (N, 3) float32 radiance Le the light emits there (which triangle it is,
            for ``AreaLights``, is known by it).
        dist2: (N,) float32 squared distance from the shading point (None for the sky).
        cos_theta_light: (N,) float32 cosine between the light's normal and the direction
            back to the shading point (None for the sky).
    """

    radiance: np.ndarray
    dist2: np.ndarray | None = None
    cos_theta_light: np.ndarray | None = None


class Light(Protocol):
    """A kind of light, as the integrators ask it (pbrt-v4's ``Light``, section 12.1).

    ``sample_li`` and ``pdf_li`` give densities *given that this kind was picked*: the
    probability of picking it is the ``LightSampler``'s (``pmf``). Emission, where a ray can
    see the light: ``Scene.emission`` for the triangles, ``Sky.radiance`` for the sky.
    """

    #: True for a light that sits in one point or direction, which no ray can find (its MIS
    #: weight is 1); ``pdf_li`` is then 0.
    is_delta: bool

    def sample_li(self, p: np.ndarray, u: np.ndarray) -> LightLiSample:
        """One light sample for each shading point ``p`` (N, 3) from uniforms ``u`` (N, 2)."""
        ...

    def pdf_li(self, found: LightPoint) -> np.ndarray:
        """(N,) float32 solid-angle density with which ``sample_li`` picks the points ``found``."""
        ...


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
        # offset, pdf_area, the cdf below the triangle's interval and 1 / the interval's width
        # (to stretch u back to [0, 1)), each as rows of a (rows, L) table.
        cdf_below = np.concatenate([[0.0], self.cdf[:-1]]).astype(np.float32)
        width = np.maximum(self.cdf - cdf_below, np.float32(1e-30))
        fields = dict(
            v0=self.v0.T,
            e1=self.e1.T,
            e2=self.e2.T,
            normals=self.normals.T,
            radiance=self.radiance.T,
            offset=np.asarray(offset, np.float32)[None],
            pdf_area=self.pdf_area(self.radiance)[None],
            cdf_below=cdf_below[None],
            stretch=(1 / width)[None],
        )
        # offset x normal per light, the step from a sampled point to its shadow ray's target:
        # the same float32 product as per sample, made once (arithmetic between two of the
        # broadcast views below is several times slower than with one array).
        fields["lift"] = fields["offset"] * fields["normals"]
        # Fields that are the same for every light (in the Cornell box: the normal, Le, the
        # offset, pdf_area and the stretch) are kept as one column that broadcasts to every
        # sample; the others are packed in one table, gathered with one `take` per sample.
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
        data = self._packed.take(index, axis=1)  # (rows, N): rows are contiguous

        def field(name: str) -> np.ndarray:
            """(N, k) per sample: gathered rows, or one column broadcast to every sample
            (a read-only view, no copy); transposed from (k, N), so in the column-major
            layout of ptlab.vectors."""
            if name in self._same:
                return np.broadcast_to(self._same[name], (self._same[name].shape[0], len(u0))).T
            return data[self._rows[name]].T

        # u0 within [cdf_below, cdf_at), stretched to [0, 1) (and kept below 1 in float32).
        stretched = (u0 - field("cdf_below")[:, 0]) * field("stretch")[:, 0]
        np.minimum(stretched, np.float32(1 - 2.0**-24), out=stretched)
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


def pick(weights: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse-CDF choice of one item per uniform, and the uniform reused.

    Args:
        weights: (K,) non-negative weights of K items (not all 0); item i is chosen with
            probability weights[i] / sum(weights), never an item of weight 0.
        u: (N,) uniforms in [0, 1).

    Returns:
        index: (N,) intp item chosen for each u;
        stretched: (N,) float32 u stretched from the chosen item's interval of the cdf back to
        [0, 1), so that it can serve again, as stratified as it was (``ptlab.samplers``).
    """
    cdf = np.cumsum(weights, dtype=np.float64)
    cdf /= cdf[-1]  # exactly 1 from the last item of non-zero weight on
    # The number of cdf entries at or below u: cdf[index - 1] <= u < cdf[index].
    index = np.searchsorted(cdf, u, side="right")
    below = np.concatenate([[0.0], cdf[:-1]])
    width = (cdf - below).take(index)
    stretched = ((u - below.take(index)) / width).astype(np.float32)
    return index, np.minimum(stretched, np.float32(1 - 2.0**-24))


class PointLights:
    """Lights that sit at single points and shine equally in every direction.

    A point light of intensity I (W/sr, an RGB triple) sends the radiance-like quantity
    I / r^2 to a point at distance r: the irradiance there is E = I cos(theta) / r^2
    (pbrt-v4's ``PointLight``, section 12.2; GAMES101 lecture 14). No ray can hit a point,
    so only light sampling finds it: a *delta* light, whose multiple-importance weight is 1.
    Its power is 4 pi mean(I) (pbrt-v4's ``PointLight::Phi``, the mean over RGB as for area
    lights); light sampling picks one of them in proportion to it.

    Args:
        positions: (K, 3) where the lights are.
        intensity: (K, 3) their intensities, W/sr, each channel >= 0.
    """

    is_delta = True

    def __init__(self, positions, intensity):
        self.positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        self.intensity = np.asarray(intensity, dtype=np.float64).reshape(-1, 3)
        if len(self.positions) != len(self.intensity) or len(self.positions) == 0:
            raise ValueError(
                f"{len(self.positions)} positions for {len(self.intensity)} "
                f"intensities: give one (3,) intensity per point light"
            )
        if (self.intensity < 0).any() or not (self.intensity.mean(axis=1) > 0).all():
            raise ValueError("a point light's intensity must be >= 0 in each channel and not 0 in all three")
        #: (K,) each light's power, and their sum.
        self.powers = 4 * math.pi * self.intensity.mean(axis=1)
        self.power = float(self.powers.sum())
        #: (K,) the probability that ``sample_li`` picks each.
        self.probability = (self.powers / self.power).astype(np.float32)

    def __len__(self) -> int:
        return len(self.positions)

    def __repr__(self) -> str:
        return f"PointLights(positions={self.positions.tolist()}, intensity={self.intensity.tolist()})"

    def pdf_li(self, found: LightPoint) -> np.ndarray:
        """(N,) zeros: no ray finds a point light."""
        return np.zeros(len(found.radiance), np.float32)

    def sample_li(self, p: np.ndarray, u: np.ndarray) -> LightLiSample:
        """One of the lights for each point ``p`` (N, 3), picked by power with ``u[:, 0]``."""
        index, _ = pick(self.powers, u[:, 0])
        position = self.positions.astype(np.float32).take(index, axis=0)
        to_light = position - p
        dist2 = dot(to_light, to_light)
        radiance = self.intensity.astype(np.float32).take(index, axis=0) / dist2[:, None]
        return LightLiSample(
            wi=to_light / np.sqrt(dist2)[:, None],
            radiance=radiance,
            pdf=self.probability.take(index),
            target=position,
        )


class Sky:
    """A constant radiance L from every direction that no surface blocks: what rays that
    escape the scene see (GAMES101 Homework 5's background colour), and a light.

    Light sampling picks directions uniformly on the sphere, pdf 1 / (4 pi), as pbrt-v4's
    ``UniformInfiniteLight`` does (section 12.5.1). Its density is the same for every
    direction, so the MIS weight of a ray that escapes needs nothing of the vertex it left;
    the half of the directions below the surface costs no shadow ray. (Cosine-weighted
    directions around the normal would suit a diffuse surface better when the sky is
    sampled alone, but their density depends on that normal.)

    Args:
        radiance: (3,) the sky's radiance L.
        distance: how far shadow rays toward the sky go: beyond the whole scene.
    """

    is_delta = False

    def __init__(self, radiance, distance: float = 1.0):
        self.radiance = np.asarray(radiance, dtype=np.float64).reshape(3)
        if (self.radiance < 0).any() or not np.isfinite(self.radiance).all():
            raise ValueError(f"the sky's radiance must be finite and >= 0, got {self.radiance.tolist()}")
        self.distance = float(distance)

    def __repr__(self) -> str:
        return f"Sky(radiance={self.radiance.tolist()})"

    def pdf_li(self, found: LightPoint) -> np.ndarray:
        """(N,) 1 / (4 pi) for every direction (``uniform_sphere``'s density)."""
        return np.full(len(found.radiance), 1 / (4 * math.pi), dtype=np.float32)

    def sample_li(self, p: np.ndarray, u: np.ndarray) -> LightLiSample:
        """A direction uniform on the sphere for each point ``p`` (N, 3)."""
        wi = uniform_sphere(u).astype(np.float32)
        n = len(p)
        radiance = np.broadcast_to(self.radiance.astype(np.float32), (n, 3))
        return LightLiSample(
            wi=wi,
            radiance=radiance,
            pdf=self.pdf_li(LightPoint(radiance)),
            target=p + np.float32(self.distance) * wi,
        )


#: The probability with which light sampling picks the sky when there are other lights too:
#: pbrt-v4's rule (``BVHLightSampler``: the infinite lights against all the others, one to
#: one), not the sky's share of the power (see ``light_shares``).
SKY_SHARE = 0.5


def light_shares(area_power: float, point_power: float, sky: bool) -> tuple[float, float, float]:
    """The probabilities with which light sampling picks the triangles, the point lights and
    the sky (each 0 when the scene has none).

    Triangles and point lights are picked in proportion to their power, as pbrt-v4's
    ``PowerLightSampler`` picks lights (pi area mean(Le) and 4 pi mean(I), section 12.6.2).
    The sky gets ``SKY_SHARE``: its power, the flux 4 pi^2 r^2 mean(L) through the scene's
    bounding sphere of radius r (pbrt-v4's ``UniformInfiniteLight::Phi``), cannot be compared
    with a point light's, most of which misses the scene. In ``games101-hw5`` and
    ``games101-hw6`` it would give the sky under 1% of the samples for about as much light
    as the point lights bring, and ``"nee"``'s error would be 70-700 times as large
    (docs/performance.md).
    """
    finite = area_power + point_power
    if point_power == 0 and not sky:
        return 1.0, 0.0, 0.0  # (exactly 1: scenes of triangles only keep their numbers)
    if finite == 0:
        return 0.0, 0.0, 1.0
    sky_share = SKY_SHARE if sky else 0.0
    rest = 1.0 - sky_share
    return rest * area_power / finite, rest * point_power / finite, sky_share


class LightSampler:
    """Which kind of light each light sample comes from: the triangles, the point lights or
    the sky (pbrt-v4's ``LightSampler``, section 12.6), each picked with its probability
    ``pmf`` (``light_shares``). The kinds' own densities (``sample_li``, ``pdf_li``) are
    given that kind; a light sample's density is their product with the kind's probability.

    ``pick`` spends the first uniform of the sample's pair on the choice and stretches it
    back to [0, 1) for the chosen kind's own ``sample_li``, which then picks its light and a
    point or direction on it (``ptlab.samplers``: one pair of dimensions per light sample).

    Args:
        area_lights, point_lights, sky: the scene's ``AreaLights``, ``PointLights`` and
            ``Sky`` (None for a kind it has not).
        shares: the probability of each kind given, in the order above; they add up to 1
            (``build_lights`` makes them so).

    Attributes:
        kinds: the kinds given, in this order.
        pmf: (K,) float64 the probability of picking each of ``kinds``.
    """

    def __init__(
        self,
        area_lights: AreaLights | None = None,
        point_lights: PointLights | None = None,
        sky: Sky | None = None,
        shares: tuple[float, ...] = (1.0,),
    ):
        self.area_lights, self.point_lights, self.sky = area_lights, point_lights, sky
        self.kinds: list[Light] = [kind for kind in (area_lights, point_lights, sky) if kind is not None]
        self.pmf = np.array(shares, dtype=np.float64).reshape(len(self.kinds))
        #: (K,) bool: which kinds are delta lights.
        self.is_delta = np.array([kind.is_delta for kind in self.kinds], dtype=bool)

    def pmf_among(self, sampled: np.ndarray) -> np.ndarray:
        """(K,) the probability of picking each kind when only those ``sampled`` (K,) bool
        may be picked (the others are left to BSDF sampling, or to nothing)."""
        shares = np.where(sampled, self.pmf, 0.0)
        return shares / shares.sum()

    def pick(self, u: np.ndarray, sampled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The kind of light of each sample, among those ``sampled`` only.

        Args:
            u: (N, 2) the light sample's uniforms.
            sampled: (K,) bool, the kinds that may be picked (``pmf_among``).

        Returns:
            kind: (N,) intp index into ``kinds``;
            u: (N, 2) the uniforms with ``u[:, 0]`` stretched back to [0, 1) (``u`` itself
            when there is one kind to pick: nothing to spend on the choice).
        """
        if np.count_nonzero(sampled) == 1:
            return np.full(len(u), int(np.argmax(sampled)), dtype=np.intp), u
        kind, stretched = pick(self.pmf_among(sampled), u[:, 0])
        return kind, np.stack([stretched, u[:, 1]]).T

    def sample_li(
        self, p: np.ndarray, u: np.ndarray, sampled: np.ndarray
    ) -> tuple[LightLiSample, np.ndarray]:
        """One light sample for each shading point ``p`` (N, 3) from uniforms ``u`` (N, 2):
        a kind picked among those ``sampled`` (``pick``), then that kind's ``sample_li``,
        whose density is multiplied by the kind's probability.

        Returns:
            the samples, and (N,) intp the kind of each (an index into ``kinds``).
        """
        kind, u = self.pick(u, sampled)
        pmf = self.pmf_among(sampled).astype(np.float32)
        if np.count_nonzero(sampled) == 1:  # one kind: its sample as it is, no gathering
            k = int(kind[0]) if len(kind) else 0
            sample = self.kinds[k].sample_li(p, u)
            sample.pdf = sample.pdf * pmf[k]
            return sample, kind
        n = len(p)
        wi, radiance, target = (np.zeros((n, 3), np.float32, order="F") for _ in range(3))
        pdf = np.zeros(n, np.float32)
        for k, light in enumerate(self.kinds):
            rows = np.flatnonzero(kind == k)
            if len(rows):
                one = light.sample_li(take_rows(p, rows), take_rows(u, rows))
                wi[rows], radiance[rows], target[rows] = one.wi, one.radiance, one.target
                pdf[rows] = one.pdf * pmf[k]
        return LightLiSample(wi=wi, radiance=radiance, pdf=pdf, target=target), kind

    def pdf_li(self, light: Light, found: LightPoint, sampled: np.ndarray) -> np.ndarray:
        """(N,) the density with which ``sample_li`` (among the kinds ``sampled``) picks the
        points ``found`` of ``light``, one of ``kinds``: its kind's probability times its
        ``pdf_li`` (0 for a kind not sampled)."""
        k = next(i for i, kind in enumerate(self.kinds) if kind is light)
        return np.float32(self.pmf_among(sampled)[k]) * light.pdf_li(found)


def build_lights(
    triangles: np.ndarray,
    radiance: np.ndarray,
    offset: np.ndarray,
    point_lights: PointLights | None = None,
    sky: Sky | None = None,
    sky_distance: float = 1.0,
) -> LightSampler | None:
    """The lights of a scene as light sampling picks them, each kind with its share of the
    samples (``light_shares``); None for a scene without light.

    The ``sky`` given is left as it is: the sky sampled is a new one, whose shadow rays go
    ``sky_distance`` far.

    Args:
        triangles: (L, 3, 3) float64, the scene's emissive triangles. Those of zero area are
            no light: no ray hits them and no light sample lands on them.
        radiance: (L, 3) float32, the radiance each emits.
        offset: (L,) how far rays stay off each (``Scene`` computes it).
        point_lights, sky: the scene's, or None.
        sky_distance: with a sky, how far shadow rays toward it go: out of the whole scene.
    """
    areas = triangle_areas(triangles)
    lit = areas > 0
    # (mean(Le) in float32 here but in float64 in AreaLights' power: they differ in the last
    # bits, and changing either would change the images of scenes with two kinds of light.)
    area_share, point_share, sky_share = light_shares(
        math.pi * float(np.sum(area_times_radiance(areas[lit], radiance[lit]))),
        point_lights.power if point_lights is not None else 0.0,
        sky is not None,
    )
    emitters = triangles[lit]
    area_lights = (
        AreaLights(emitters[:, 0], emitters[:, 1], emitters[:, 2], radiance[lit], offset[lit])
        if lit.any()
        else None
    )
    sampled_sky = Sky(sky.radiance, distance=sky_distance) if sky is not None else None
    shares = [
        share
        for kind, share in ((area_lights, area_share), (point_lights, point_share), (sampled_sky, sky_share))
        if kind is not None
    ]
    if not shares:
        return None
    return LightSampler(area_lights, point_lights, sampled_sky, tuple(shares))
