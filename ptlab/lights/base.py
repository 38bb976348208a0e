"""What every kind of light answers: the ``Light`` protocol and the records it answers with.

A light is asked two questions (pbrt-v4's ``Light`` interface, section 12.1): ``sample_li``,
the direction to a light point chosen for a shading point, the radiance arriving from it and
the density of that choice (a ``LightLiSample``); and ``pdf_li``, the density with which
``sample_li`` would have chosen a light point that a ray found instead (a ``LightPoint``:
what multiple importance sampling weighs with). ``is_delta`` says whether a ray can find
the light at all.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


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
