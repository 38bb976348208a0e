"""A ptlab scene as a Mitsuba 3 scene file: the same triangles, colours, light and camera.

``write_mitsuba_scene`` writes, from a loaded ``Scene`` (``ptlab.load_scene``), a Mitsuba 3
XML scene (Mitsuba 3 documentation, "File format") and one OBJ mesh per material:

* the triangles of each material, each with its own three vertices, read with face normals,
  so that Mitsuba's normals are ptlab's face normals;
* a ``diffuse`` BSDF of the same RGB albedo inside ``twosided``: ptlab's materials are
  two-sided (the renderer turns the normal toward the viewer), Mitsuba's ``diffuse`` alone is
  black from behind;
* an ``area`` emitter of the same RGB radiance on each emissive material: both emit from the
  front face only, the side that (v1 - v0) x (v2 - v0) points to (``ptlab.lights``);
* a ``perspective`` sensor with the same eye, viewing direction, up and *vertical* field of
  view (Mitsuba's ``look_at`` puts cross(up, forward) on the image's left, ptlab's camera puts
  forward x up on its right: the same side, so the images need no flip);
* a box pixel filter: ptlab jitters each sample uniformly inside its pixel;
* the ``path`` integrator without a depth limit, or with the scene file's ``max_depth``
  (Mitsuba counts the camera ray as depth 1, ptlab counts bounces: Mitsuba's N + 1 is
  ptlab's N).

The XML takes the parameters ``$sampler``, ``$spp``, ``$seed`` and ``$rr_depth``
(``mi.load_file(path, sampler=...)``, or ``mitsuba -D sampler=...``). Mitsuba itself is not
needed to write it. What has no counterpart here (a material other than ``Diffuse``, a
textured albedo, vertex normals, point lights, a sky) raises ``PtlabError`` naming it, rather than being
left out of Mitsuba's scene, which would then render something else.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np

from ptlab.errors import PtlabError
from ptlab.materials import Diffuse
from ptlab.scene import Scene

#: Mitsuba's own default ``rr_depth``; the scene file's default for ``$rr_depth``.
MITSUBA_RR_DEPTH = 5
#: The scene file's parameters and what they are when not given (``mitsuba -D name=value``).
PARAMETER_DEFAULTS: dict[str, object] = dict(sampler="independent", spp=64, seed=0, rr_depth=MITSUBA_RR_DEPTH)
#: The scene file's name inside the folder it is written to.
SCENE_XML = "scene.xml"


def exported_materials(scene: Scene) -> list[Diffuse]:
    """The scene's materials, each a plain ``Diffuse`` of a constant albedo; or ``PtlabError``
    (one line) for the first thing in ``scene`` that the Mitsuba scene would not have: another
    material, a textured albedo, vertex normals, point lights or a sky."""
    if scene.normals is not None:  # (the meshes written here are flat: face normals)
        raise PtlabError(
            f"scene {scene.name}: its meshes have vertex normals (smooth shading); "
            f"this export writes flat triangles only"
        )
    materials = []
    for name, material in zip(_material_names(scene), scene.materials, strict=True):
        # (exactly Diffuse: a subclass may shade otherwise)
        if type(material) is not Diffuse:
            raise PtlabError(
                f"scene {scene.name}: material {name!r} is a {type(material).__name__}; "
                f"only diffuse materials have a Mitsuba counterpart here"
            )
        if material.textured:
            raise PtlabError(
                f"scene {scene.name}: material {name!r} has a textured albedo; "
                f"only a constant one has a Mitsuba counterpart here"
            )
        materials.append(material)
    if scene.point_lights is not None:
        raise PtlabError(f"scene {scene.name}: point lights have no Mitsuba counterpart here")
    if scene.sky is not None:
        raise PtlabError(f"scene {scene.name}: a sky has no Mitsuba counterpart here")
    return materials


def mitsuba_max_depth(scene: Scene) -> int:
    """Mitsuba's ``max_depth`` for the scene file's: -1 (none) if it sets none, else one more
    than ptlab's (Mitsuba's 1 is the light seen directly, ptlab's 0)."""
    max_depth = scene.defaults.max_depth
    return -1 if max_depth is None else max_depth + 1


def write_mitsuba_scene(scene: Scene, folder: Path, width: int, height: int) -> Path:
    """Write ``scene.xml`` and one OBJ mesh per material into ``folder``; return the XML's path.

    Args:
        scene: a scene of diffuse materials and area lights (``exported_materials``).
        folder: an existing folder; files of the same names in it are overwritten.
        width, height: the film's resolution in pixels.
    """
    exported_materials(scene)  # (before writing anything)
    meshes = {k: write_material_mesh(scene, k, folder) for k in range(len(scene.materials))}
    xml = scene_xml(scene, {k: mesh.name for k, mesh in meshes.items() if mesh is not None}, width, height)
    path = folder / SCENE_XML
    path.write_text(xml)
    return path


def write_material_mesh(scene: Scene, material: int, folder: Path) -> Path | None:
    """Write the triangles of material number ``material`` as ``folder/material<k>.obj``;
    return its path, or None (and write nothing) if no triangle has that material."""
    triangles = scene.triangles[scene.material_ids == material]
    if not len(triangles):
        return None
    mesh = folder / f"material{material}.obj"
    with open(mesh, "w") as out:
        out.write(
            f"# ptlab scene {_one_line(scene.name)}, material {_one_line(_material_names(scene)[material])}\n"
        )
        # Every triangle has its own three vertices, so the normals are ptlab's face normals.
        np.savetxt(out, triangles.reshape(-1, 3), fmt="v %.17g %.17g %.17g")
        np.savetxt(out, np.arange(1, 3 * len(triangles) + 1).reshape(-1, 3), fmt="f %d %d %d")
    return mesh


def scene_xml(scene: Scene, meshes: dict[int, str], width: int, height: int) -> str:
    """The Mitsuba XML of ``scene``, whose material number k has its triangles in the OBJ file
    ``meshes[k]`` (a material missing from ``meshes`` has none). Raises ``PtlabError`` for what
    Mitsuba's scene would not have (``exported_materials``)."""
    materials = exported_materials(scene)
    shapes = [_shape_xml(materials[k], mesh) for k, mesh in sorted(meshes.items())]
    camera = scene.camera
    # Nothing may lie beyond the far clipping plane (ptlab has none).
    far = 2 * float(np.linalg.norm(scene.triangles - camera.position, axis=-1).max()) + 1
    defaults = "".join(
        f'  <default name="{name}" value="{value}"/>\n' for name, value in PARAMETER_DEFAULTS.items()
    )
    return f"""<scene version="3.0.0">
{defaults}  <integrator type="path">
    <integer name="max_depth" value="{mitsuba_max_depth(scene)}"/><integer name="rr_depth" value="$rr_depth"/>
  </integrator>
  <sensor type="perspective">
    <float name="fov" value="{float(camera.fov_y)!r}"/><string name="fov_axis" value="y"/>
    <float name="far_clip" value="{far!r}"/>
    <transform name="to_world">
      <lookat origin="{_xml_vector(camera.position)}"
              target="{_xml_vector(camera.position + camera.forward)}"
              up="{_xml_vector(camera.up)}"/>
    </transform>
    <sampler type="$sampler">
      <integer name="sample_count" value="$spp"/><integer name="seed" value="$seed"/>
    </sampler>
    <film type="hdrfilm">
      <integer name="width" value="{width}"/><integer name="height" value="{height}"/>
      <string name="pixel_format" value="rgb"/><rfilter type="box"/>
    </film>
  </sensor>
{chr(10).join(shapes)}
</scene>
"""


def _shape_xml(material: Diffuse, mesh: str) -> str:
    """One ``shape`` element: the OBJ file ``mesh`` with ``material``'s BSDF and emitter."""
    emitter = (
        ""
        if material.emission is None
        else f'<emitter type="area"><rgb name="radiance" value="{_xml_vector(material.emission)}"/></emitter>'
    )
    return (
        f'  <shape type="obj"><string name="filename" value="{mesh}"/>'
        f'<boolean name="face_normals" value="true"/>\n'
        f'    <bsdf type="twosided"><bsdf type="diffuse">'
        f'<rgb name="reflectance" value="{_xml_vector(material.albedo)}"/></bsdf></bsdf>'
        f"{emitter}</shape>"
    )


def _material_names(scene: Scene) -> list[str]:
    """Each material's name in the scene file, or ``material<k>`` where it has none (a scene
    made in Python)."""
    given = scene.material_names
    return [given[k] if k < len(given) else f"material{k}" for k in range(len(scene.materials))]


def _one_line(text: str) -> str:
    """``text`` with its runs of white space, line breaks included, as single spaces: a name
    in a comment line cannot start a line of the file."""
    return " ".join(text.split())


def _xml_vector(values: Iterable[float]) -> str:
    """Mitsuba's ``"x, y, z"``, each number exact (``repr`` of a float round-trips)."""
    return ", ".join(repr(float(v)) for v in values)
