"""The lights of a scene: emissive triangles, point lights and the sky, and light sampling.

Every kind of light answers the same questions (``Light``, pbrt-v4's ``Light`` interface,
section 12.1): ``sample_li``, the direction to the light, the radiance arriving from it and
the density of that choice; ``pdf_li``, the density with which ``sample_li`` would have
chosen a light point that a ray found instead (what MIS weighs with); and ``is_delta``,
whether a ray can find it at all. Light sampling first picks which kind of light a sample
comes from (``LightSampler``, which alone holds the probability ``pmf`` of each kind), then
that kind's ``sample_li`` picks a light and a point or direction on it.

One module per concept:

* ``base``: the ``Light`` protocol and what it answers with (``LightLiSample``, ``LightPoint``);
* ``area``: every emissive triangle, picked by power (``AreaLights``);
* ``point``: lights at single points (``PointLights``);
* ``sky``: a constant radiance from every direction (``Sky``);
* ``sampler``: the choice between kinds (``LightSampler``) and a scene's lights built
  (``build_lights``).
"""

from ptlab.lights.area import (
    AreaLights,
    LightSample,
    ShapeSample,
    area_times_radiance,
    solid_angle_pdf,
    triangle_areas,
    triangle_normals,
)
from ptlab.lights.base import Light, LightLiSample, LightPoint
from ptlab.lights.point import PointLights
from ptlab.lights.sampler import SKY_SHARE, LightSampler, build_lights, light_shares
from ptlab.lights.sky import Sky

__all__ = [
    "SKY_SHARE",
    "AreaLights",
    "Light",
    "LightLiSample",
    "LightPoint",
    "LightSample",
    "LightSampler",
    "PointLights",
    "ShapeSample",
    "Sky",
    "area_times_radiance",
    "build_lights",
    "light_shares",
    "solid_angle_pdf",
    "triangle_areas",
    "triangle_normals",
]
