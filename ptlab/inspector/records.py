"""What the inspector records of one pixel's paths, vertex by vertex, and the recorder that
the integrators report to.

The integrators (``ptlab.integrators.path``, ``whitted``, and ``surface_hit`` in
``wavefront``) call the recorder of ``ptlab.integrators.wavefront.recording`` at each step of
a bounce, with the step's own arrays, when one is set: what is printed is what the renderer
computed, not a second tracer's guess. Each call turns the rows of a batch (paths of the
inspected pixel, a film row per sample) into the dataclasses below.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

from ptlab.vectors import dot

Vec = list[float]


def _vec(a: np.ndarray) -> Vec:
    """A row of an array as a plain list of floats (JSON, printing)."""
    return [float(x) for x in np.asarray(a, dtype=np.float64).ravel()]


@dataclass
class LightSample:
    """Next-event estimation at a vertex: one point on a light and its shadow ray.

    Attributes:
        point: where the shadow ray stops, on the light.
        light: which kind of light was picked ("area light", "point light", "sky").
        pdf: the density of the choice per solid angle.
        visible: the shadow ray reached the light (None: no shadow ray was cast, the light
            facing away from the point or lying behind its surface).
        mis_weight: the MIS weight of the light sample (None without MIS).
        contribution: what it added to the pixel: throughput f_r Li cos / pdf (x weight).
    """

    point: Vec | None = None
    light: str | None = None
    pdf: float | None = None
    visible: bool | None = None
    mis_weight: float | None = None
    contribution: Vec | None = None


@dataclass
class BsdfSample:
    """The sampled direction that the path goes on along.

    Attributes:
        wi: the direction sampled from the material.
        f: the BSDF value f_r(wo, wi) (None where not recorded).
        pdf: its density (for a mirror or glass a Dirac: 0 here).
        cos_theta: cos between wi and the normal.
        weight: f_r cos / pdf, what the throughput is multiplied by (for a mirror or glass,
            the reflectance; Whitted's glass: kr or (1 - kr) T / eta^2).
    """

    wi: Vec | None = None
    f: Vec | None = None
    pdf: float | None = None
    cos_theta: float | None = None
    weight: Vec | None = None


@dataclass
class Roulette:
    """Russian roulette at a vertex: the survival probability and the outcome."""

    survival: float | None = None
    survived: bool | None = None


@dataclass
class Vertex:
    """A surface a path hit, and what the integrator did there.

    Attributes:
        depth: the bounce (0: what the camera ray hit).
        position: the hit point.
        triangle: the triangle's index in the scene.
        material: the triangle's material, by its name in the scene file.
        normal: the shading normal, turned to the side the ray came from.
        front: the ray hit the triangle's front face.
        wo: the direction back along the ray.
        emission: the emission seen here that was added (throughput Le x weight), if any.
        light: the light sample (None where there was none: a mirror, glass, the last bounce).
        roulette: Russian roulette, where it was played.
        bsdf: the sampled next direction (the path tracer).
        split: Whitted's next rays: one for a mirror, two for glass.
        sky: the sky seen by the ray that left this vertex and escaped, as it was added.
        throughput: the path's throughput after the vertex (0 if the path ended here).
    """

    depth: int
    position: Vec
    triangle: int
    material: str
    normal: Vec
    front: bool
    wo: Vec
    emission: Vec | None = None
    light: LightSample | None = None
    roulette: Roulette | None = None
    bsdf: BsdfSample | None = None
    split: list[BsdfSample] = field(default_factory=list)
    sky: Vec | None = None
    throughput: Vec | None = None


@dataclass
class Sample:
    """One camera sample of the pixel: its vertices in order and what it added.

    Attributes:
        index: the sample's number within the pixel (0, 1, ..., spp - 1).
        contribution: its radiance (r, g, b), as the renderer added it to the film.
        vertices: the surfaces it hit, in order (Whitted's glass: both branches).
        sky: the sky its camera ray saw, if it escaped at once.
    """

    index: int
    contribution: Vec
    vertices: list[Vertex] = field(default_factory=list)
    sky: Vec | None = None


#: How a kind of light (``LightSampler.kinds``) is named in a record, by class name.
LIGHT_NAMES = {"AreaLights": "area light", "PointLights": "point light", "Sky": "sky"}


class Recorder:
    """What the integrators report, by film row (a sample of the inspected pixel each).

    Each ``vertices`` call starts a bounce: the later calls of the bounce (``light``,
    ``roulette``, ``bsdf``, ...) come with the same ``SurfaceHit`` and arrays row for row.
    """

    def __init__(self) -> None:
        self.vertices_of: dict[int, list[Vertex]] = defaultdict(list)
        self.sky_of: dict[int, Vec] = {}
        self._hit: object = None
        self._rows: list[Vertex] = []

    def _at(self, hit) -> list[Vertex]:
        """The vertices of ``hit``'s rows (none for a hit that was not reported)."""
        return self._rows if hit is self._hit else []

    def vertices(self, scene, hit) -> None:
        """A vertex for each row of ``hit`` (``surface_hit``)."""
        depths = np.broadcast_to(np.asarray(hit.depth), hit.prim.shape)
        material_ids = scene.material_ids.take(hit.prim)
        names = scene.material_names
        rows = []
        for k, prim in enumerate(hit.prim):
            m = int(material_ids[k])
            vertex = Vertex(
                depth=int(depths[k]),
                position=_vec(hit.p[k]),
                triangle=int(prim),
                material=names[m] if m < len(names) else f"material {m}",
                normal=_vec(hit.n[k]),
                front=bool(hit.front[k]),
                wo=_vec(hit.wo[k]),
            )
            self.vertices_of[int(hit.pixel[k])].append(vertex)
            rows.append(vertex)
        self._hit, self._rows = hit, rows

    def emission(self, hit, rows: np.ndarray, radiance: np.ndarray) -> None:
        """The emission that the rows ``rows`` of ``hit`` saw and added (``add_emission``)."""
        vertices = self._at(hit)
        for i, k in enumerate(rows):
            if vertices:
                vertices[k].emission = _vec(radiance[i])

    def light(self, scene, hit, light, kind, visible, mis, radiance: np.ndarray) -> None:
        """``direct_light``'s light samples, row for row."""
        kinds = scene.light_sampler.kinds
        # (``direct_light`` casts no shadow ray where the light faces away or is behind the
        # surface, or at a mirror or glass: "visible" is None there.)
        traced = (dot(hit.n, light.wi) > 0) & (light.pdf > 0) & ~hit.delta
        for k, vertex in enumerate(self._at(hit)):
            name = type(kinds[int(kind[k])]).__name__
            vertex.light = LightSample(
                point=_vec(light.target[k]),
                light=LIGHT_NAMES.get(name, name),
                pdf=float(light.pdf[k]),
                visible=bool(visible[k]) if traced[k] else None,
                mis_weight=None if mis is None else float(mis[k]),
                contribution=_vec(radiance[k]),
            )

    def light_contribution(self, hit, radiance: np.ndarray) -> None:
        """A light sample's contribution only, row for row (a student's ``direct_light``,
        whose inside the recorder does not see)."""
        for k, vertex in enumerate(self._at(hit)):
            vertex.light = LightSample(contribution=_vec(radiance[k]))

    def roulette(self, hit, survival, survive: np.ndarray) -> None:
        """``russian_roulette``'s survival probabilities (None: not known, a student's) and
        outcomes."""
        odds = None if survival is None else np.broadcast_to(np.asarray(survival, np.float64), survive.shape)
        for k, vertex in enumerate(self._at(hit)):
            vertex.roulette = Roulette(None if odds is None else float(odds[k]), bool(survive[k]))

    def bsdf(self, hit, wi, weight, pdf, throughput, survive) -> None:
        """``scatter``'s sampled directions, with f_r, pdf and cos at them (asked of the
        vertices' own materials, only while recording), and the throughput after."""
        vertices = self._at(hit)
        if not vertices:
            return

        with np.errstate(all="ignore"):
            f = hit.bsdf.f(wi)
            if pdf is None:
                pdf = hit.bsdf.pdf(wi)
            cos_theta = dot(wi, hit.n)
        for k, vertex in enumerate(vertices):
            vertex.bsdf = BsdfSample(
                _vec(wi[k]), _vec(f[k]), float(pdf[k]), float(cos_theta[k]), _vec(weight[k])
            )
            vertex.throughput = _vec(throughput[k] if survive[k] else np.zeros(3))

    def next_paths(self, hit, paths) -> None:
        """A student's ``scatter``: the next rays it returned, found by their film rows,
        and the throughput after (0 for the rows it ended)."""
        vertices = self._at(hit)
        by_row = {int(row): i for i, row in enumerate(np.asarray(paths.pixel))}
        for k, vertex in enumerate(vertices):
            i = by_row.get(int(hit.pixel[k]))
            if i is None:
                vertex.throughput = [0.0, 0.0, 0.0]
                continue
            vertex.bsdf = BsdfSample(wi=_vec(paths.dirs[i]))
            vertex.throughput = _vec(paths.throughput[i])

    def split(self, hit, rows, wi, weight, throughput) -> None:
        """Whitted's next rays (``next_rays``): rows of ``hit``, repeated for glass."""
        vertices = self._at(hit)
        for i, k in enumerate(rows):
            if vertices:
                cos_theta = float(np.dot(wi[i], hit.n[k]))
                vertices[k].split.append(
                    BsdfSample(wi=_vec(wi[i]), cos_theta=cos_theta, weight=_vec(weight[i]))
                )

    def sky(self, paths, rows: np.ndarray, radiance: np.ndarray) -> None:
        """The sky seen by the rays ``rows`` of ``paths`` that escaped (``add_sky``): given to
        the vertex each left, or to the sample if it was a camera ray."""
        depths = np.broadcast_to(np.asarray(paths.depth), paths.pixel.shape)
        for i, k in enumerate(rows):
            row, depth = int(paths.pixel[k]), int(depths[k])
            left = [v for v in self.vertices_of[row] if v.depth == depth - 1]
            if left:
                left[-1].sky = _vec(radiance[i])
            else:
                self.sky_of[row] = _vec(radiance[i])
