"""Light sampling: which kind of light each light sample comes from, and a scene's lights
built with the share of the samples each kind gets."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TypeVar

import numpy as np

from ptlab.lights.area import AreaLights, area_times_radiance, triangle_areas
from ptlab.lights.base import Light, LightLiSample, LightPoint
from ptlab.lights.point import PointLights
from ptlab.lights.sky import Sky
from ptlab.sampling import discrete_cdf, pick_from_cdf
from ptlab.vectors import take_rows

#: The probability with which light sampling picks the sky when there are other lights too:
#: pbrt-v4's rule (``BVHLightSampler``: the infinite lights against all the others, one to
#: one), not the sky's share of the power (see ``light_shares``).
SKY_SHARE = 0.5

_Kind = TypeVar("_Kind")


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
        lights: the scene's kinds of light, each a ``Light`` (``AreaLights``,
            ``PointLights``, ``Sky``: one of each at most).
        shares: the probability of picking each of ``lights``, in their order; they add up
            to 1 (``build_lights`` makes them so). The default fits one kind of light.

    Attributes:
        kinds: the lights given, in their order.
        pmf: (K,) float64 the probability of picking each of ``kinds``.
        is_delta: (K,) bool, which of ``kinds`` are delta lights.
    """

    def __init__(self, lights: Sequence[Light], *, shares: Sequence[float] = (1.0,)):
        self.kinds: list[Light] = list(lights)
        if len(shares) != len(self.kinds):
            raise ValueError(f"{len(shares)} shares for {len(self.kinds)} kinds of light: give one per kind")
        self.pmf = np.array(shares, dtype=np.float64)
        self.is_delta = np.array([kind.is_delta for kind in self.kinds], dtype=bool)

    def _of_kind(self, kind: type[_Kind]) -> _Kind | None:
        """The light of class ``kind`` among ``kinds``, or None."""
        return next((light for light in self.kinds if isinstance(light, kind)), None)

    @property
    def area_lights(self) -> AreaLights | None:
        """The emissive triangles among ``kinds`` (None in a scene without)."""
        return self._of_kind(AreaLights)

    @property
    def point_lights(self) -> PointLights | None:
        """The point lights among ``kinds`` (None in a scene without)."""
        return self._of_kind(PointLights)

    @property
    def sky(self) -> Sky | None:
        """The sky among ``kinds`` (None in a scene without)."""
        return self._of_kind(Sky)

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
            u: (N, 2) the uniforms with ``u[:, 0]`` stretched back to [0, 1)
            (``pick_from_cdf``; ``u`` itself when there is one kind to pick: nothing to
            spend on the choice).
        """
        if np.count_nonzero(sampled) == 1:
            return np.full(len(u), int(np.argmax(sampled)), dtype=np.intp), u
        kind, stretched = pick_from_cdf(discrete_cdf(self.pmf_among(sampled)), u[:, 0])
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
    kinds: list[tuple[Light, float]] = [
        (kind, share)
        for kind, share in ((area_lights, area_share), (point_lights, point_share), (sampled_sky, sky_share))
        if kind is not None
    ]
    if not kinds:
        return None
    return LightSampler([kind for kind, _ in kinds], shares=[share for _, share in kinds])
