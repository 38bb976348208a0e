"""Scene files: a small TOML file naming a camera, materials and meshes, read into a ``Scene``.

A scene file looks like this (``scenes/cornell-box/scene.toml`` is a full example)::

    [camera]
    position = [278, 273, -800]
    look_at = [278, 273, 0]     # or: direction = [0, 0, 1]
    up = [0, 1, 0]              # optional, default +y
    fov = 40                    # vertical field of view, degrees

    [materials.white]
    type = "diffuse"
    albedo = [0.725, 0.71, 0.68]

    [materials.light]
    type = "diffuse"
    albedo = 0.65                           # one number is a grey
    emission = [47.8348, 38.5664, 31.0808]  # emitted radiance, from the front face

    [[mesh]]
    file = "meshes/floor.obj"   # OBJ, STL, PLY, OFF or glTF; relative to the scene file
    material = "white"

and may add point lights (``[[point_light]]``), a sky (``[sky]``) and the render's defaults
(``[render]``): ``docs/scene-format.md`` describes every key.

``load_scene`` finds the file (a path, a folder holding ``scene.toml``, or the name of a
built-in scene), checks every value and flattens every mesh into the ``Scene``'s one array
of triangles. Anything wrong in the file raises a ``SceneError`` that names the file, the
key and the problem.
"""

from __future__ import annotations

import math
import reprlib
import tomllib
from pathlib import Path

import numpy as np

from ptlab.atomic import path_kind
from ptlab.camera import Camera
from ptlab.errors import PtlabError, SceneError, is_integer
from ptlab.lights import PointLights, Sky, area_times_radiance, triangle_areas
from ptlab.materials import Dielectric, Diffuse, Material, Microfacet, Mirror
from ptlab.meshes import drop_zero_area, has_area, read_mesh
from ptlab.scene import OFFSET_SCALE, RenderDefaults, Scene, bounds
from ptlab.textures import Checkerboard

SCENE_FILE_NAME = "scene.toml"

#: The keys each material type takes in a scene file (besides ``type`` and ``emission``).
MATERIAL_KEYS = {
    "diffuse": {"albedo"},
    "microfacet": {"f0", "roughness", "alpha", "kd", "ks", "sampling"},
    "mirror": {"reflectance", "fresnel"},
    "dielectric": {"eta", "transmittance"},
}

# The sizes float32 rays can trace (docs/scene-format.md, "Sizes"). Scaling a scene scales
# its ray offsets with it, so a scene renders the same picture at any size between these
# two, as long as it lies near the origin (the third):
#: Every coordinate, of a vertex or of the camera, lies within +-MAX_COORDINATE. Ray-triangle
#: tests (Moller-Trumbore, Embree's) multiply three lengths of the scene together, since a
#: shadow ray's direction is as long as the ray: float32 (at most 3.4e38) overflows for
#: coordinates of about 4e12 (measured: the Cornell box scaled by 7e9 loses shadow rays).
MAX_COORDINATE = 1e10
#: A scene's box is at least this wide: Embree misses rays in a smaller one (measured: the
#: Cornell box scaled to 1e-8 across).
MIN_SCENE_SIZE = 1e-6
#: No vertex lies farther than this many times the scene's width from the origin. The ray
#: offsets grow with the distance from the origin (OFFSET_SCALE of a triangle's largest
#: coordinate), so farther out they would exceed 1% of the scene and lose its contact
#: shadows and small gaps (measured: the Cornell box moved 1e7 away renders 70% too dark).
MAX_DISTANCE_IN_SIZES = 0.01 / OFFSET_SCALE
#: The smallest sphere: a thousandth of the smallest scene (trimesh's icospheres collapse
#: below a radius of about 1e-17).
MIN_RADIUS = 1e-3 * MIN_SCENE_SIZE
#: Each channel of an emission is at most this: a path's float32 radiance is the emission
#: times its throughput (up to ~1e10 after deep Russian roulette) and the light's geometry
#: factor (up to ~1e9 next to it), which must stay far below float32's 3.4e38.
MAX_RADIANCE = 1e15
#: The largest width or height, and the most bounces, a ``[render]`` table may ask for.
MAX_RESOLUTION = 1 << 16
MAX_DEPTH = 10_000


def builtin_scenes_dir() -> Path:
    """The folder of the built-in scenes: inside the installed package, or the checkout's."""
    package = Path(__file__).resolve().parent
    for candidate in (package / "scenes", package.parent / "scenes"):
        if candidate.is_dir():
            return candidate
    return package / "scenes"


def builtin_scene_names() -> list[str]:
    """Names of the scenes that ship with ptlab, e.g. ``cornell-box``."""
    root = builtin_scenes_dir()
    if not root.is_dir():
        return []
    return sorted(p.name for p in root.iterdir() if (p / SCENE_FILE_NAME).is_file())


def builtin_scene_description(name: str) -> str:
    """The ``description`` line of a built-in scene's file ("" if it has none)."""
    try:
        with open(builtin_scenes_dir() / name / SCENE_FILE_NAME, "rb") as file:
            description = tomllib.load(file).get("description", "")
    except (OSError, tomllib.TOMLDecodeError):
        return ""
    return description if isinstance(description, str) else ""


def find_scene_file(name_or_path: str | Path) -> Path:
    """A scene file from a path (a file, or a folder holding ``scene.toml``) or a built-in name."""
    path = Path(name_or_path)
    kind = path_kind(path)
    if kind == "file":
        return path
    if kind == "folder":
        if path_kind(path / SCENE_FILE_NAME) == "file":
            return path / SCENE_FILE_NAME
        raise SceneError(path, f"folder has no {SCENE_FILE_NAME}")
    builtin = builtin_scenes_dir() / str(name_or_path) / SCENE_FILE_NAME
    if path_kind(builtin) == "file":
        return builtin
    names = ", ".join(builtin_scene_names()) or "none found"
    raise SceneError(name_or_path, f"no such scene file or built-in scene (built-in: {names})")


def load_scene(name_or_path: str | Path) -> Scene:
    """Load a scene by built-in name (``"cornell-box"``) or from a scene file path."""
    path = find_scene_file(name_or_path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as error:
        raise SceneError(path, f"malformed TOML: {error}") from None
    except RecursionError:  # tomllib parses nested arrays and tables recursively
        raise SceneError(path, "malformed TOML: arrays or tables nested too deeply") from None
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(path, f"cannot read: {error}") from None
    return _SceneReader(path).read(data)


def _shown(value: object) -> str:
    """A short repr of a value from the scene file, for an error message."""
    short = reprlib.Repr()
    short.maxstring = short.maxother = 40
    short.maxlist = short.maxdict = 6
    short.maxlevel = 2
    return short.repr(value)


def _as_float(value: int | float) -> float | None:
    """A TOML number as a finite float; None for inf, NaN or an integer too large for a float."""
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _scaled_to_one(vector: np.ndarray) -> np.ndarray:
    """``vector`` times the power of two that brings its largest component into [0.5, 1).

    Exact (no rounding), so it changes no direction computed from it, and its length can
    then be computed without overflow or underflow, whatever the scale of the input.
    """
    _, exponent = np.frexp(np.abs(vector).max())
    return np.ldexp(vector, -exponent)


class _SceneReader:
    """Turns the parsed TOML of one scene file into a ``Scene``, checking every value."""

    def __init__(self, path: Path):
        self.path = path

    def error(self, key: str | None, problem: str) -> SceneError:
        return SceneError(self.path, problem, key)

    def read(self, data: dict) -> Scene:
        self.check_keys(
            data, None, {"description", "camera", "materials", "mesh", "point_light", "sky", "render"}
        )
        if not isinstance(data.get("description", ""), str):
            raise self.error("description", "must be text: one line that says what the scene shows")
        if "camera" not in data:
            raise self.error(None, "no [camera] section")
        camera = self.camera(data["camera"])
        materials_table = data.get("materials", {})
        if not isinstance(materials_table, dict):
            raise self.error(
                "materials", f"must be a table of [materials.NAME] tables, got {_shown(materials_table)}"
            )
        if not materials_table:
            raise self.error("materials", "no materials: add a [materials.NAME] section")
        names = list(materials_table)
        materials = [self.material(f"materials.{name}", spec) for name, spec in materials_table.items()]
        meshes = data.get("mesh", [])
        if not isinstance(meshes, list):
            raise self.error("mesh", f"must be an array of tables, each one [[mesh]], got {_shown(meshes)}")
        if not meshes:
            raise self.error("mesh", "no meshes: add a [[mesh]] section")
        triangles, uvs, material_ids, keys = [], [], [], []
        for i, spec in enumerate(meshes):
            tri, uv, material, key = self.mesh(f"mesh[{i}]", spec, names)
            if materials[material].textured and uv is None:
                raise self.error(
                    key,
                    f"material {names[material]!r} is textured, but this mesh "
                    f"has no texture coordinates (a `quad`'s `uv`, or `vt` "
                    f"lines in an OBJ file)",
                )
            triangles.append(tri)
            uvs.append(uv if uv is not None else np.zeros((len(tri), 3, 2)))
            material_ids.append(np.full(len(tri), material, dtype=np.intp))
            keys.append(key)
        self.check_extent(triangles, keys)
        all_triangles = np.concatenate(triangles)
        material_of_triangle = np.concatenate(material_ids)
        point_lights = self.point_lights(data.get("point_light", []))
        sky = self.sky(data["sky"]) if "sky" in data else None
        self.check_light_power(all_triangles, material_of_triangle, materials, point_lights)
        textured = any(m.textured for m in materials)
        scene = Scene(
            triangles=all_triangles,
            material_ids=material_of_triangle,
            materials=materials,
            camera=camera,
            name=self.path.parent.name if self.path.name == SCENE_FILE_NAME else self.path.stem,
            material_names=names,
            point_lights=point_lights,
            sky=sky,
            uvs=np.concatenate(uvs) if textured else None,
            defaults=self.render_defaults(data.get("render", {})),
        )
        if scene.light_sampler is None:
            raise self.error(
                None,
                "the scene has no light: give a material an `emission` "
                "and a mesh that uses it, add a [[point_light]], or a [sky]",
            )
        return scene

    def point_lights(self, specs: list) -> PointLights | None:
        """The ``[[point_light]]`` tables: a position and an intensity (W/sr) each."""
        if not isinstance(specs, list):
            raise self.error(
                "point_light", f"must be an array of tables, each one [[point_light]], got {_shown(specs)}"
            )
        positions, intensities = [], []
        for i, spec in enumerate(specs):
            key = f"point_light[{i}]"
            self.check_keys(spec, key, {"position", "intensity"})
            positions.append(self.point(spec, key, "position"))
            if "intensity" not in spec:
                raise self.error(f"{key}.intensity", "missing (W/sr: one number or three)")
            intensity = self.colour(
                spec, key, "intensity", default=None, upper=MAX_RADIANCE, why="float32 radiance"
            )
            if not intensity.max() > 0:
                raise self.error(
                    f"{key}.intensity", "must not be 0 in every channel: such a light gives no light"
                )
            intensities.append(intensity)
        return PointLights(positions, intensities) if positions else None

    def sky(self, spec: dict) -> Sky | None:
        """The ``[sky]`` table: the radiance that escaping rays see (None if it is black)."""
        self.check_keys(spec, "sky", {"radiance"})
        if "radiance" not in spec:
            raise self.error("sky.radiance", "missing (linear RGB radiance: one number or three)")
        radiance = self.colour(
            spec, "sky", "radiance", default=None, upper=MAX_RADIANCE, why="float32 radiance"
        )
        return Sky(radiance) if radiance.max() > 0 else None

    def render_defaults(self, spec: dict) -> RenderDefaults:
        """The ``[render]`` table: ``res`` (N or [width, height]) and ``max_depth``."""
        self.check_keys(spec, "render", {"res", "max_depth"})
        res = spec.get("res")
        if res is not None:
            sizes = [res, res] if is_integer(res) else res
            if not (
                isinstance(sizes, list)
                and len(sizes) == 2
                and all(map(is_integer, sizes))
                and all(1 <= n <= MAX_RESOLUTION for n in sizes)
            ):
                raise self.error(
                    "render.res",
                    f"must be an integer or [width, height], from 1 to {MAX_RESOLUTION}, got {_shown(res)}",
                )
            res = (int(sizes[0]), int(sizes[1]))
        max_depth = spec.get("max_depth")
        if max_depth is not None and not (is_integer(max_depth) and 0 <= max_depth <= MAX_DEPTH):
            raise self.error(
                "render.max_depth", f"must be an integer from 0 to {MAX_DEPTH}, got {_shown(max_depth)}"
            )
        return RenderDefaults(res=res, max_depth=max_depth)

    def check_keys(self, table: dict, key: str | None, allowed: set[str]) -> None:
        if not isinstance(table, dict):
            raise self.error(key, f"must be a table, got {_shown(table)}")
        for name in table:
            if name not in allowed:
                full = name if key is None else f"{key}.{name}"
                raise self.error(full, f"unknown key (expected one of: {', '.join(sorted(allowed))})")

    def vector(self, table: dict, key: str, name: str, default=None) -> np.ndarray:
        full = f"{key}.{name}"
        if name not in table:
            if default is None:
                raise self.error(full, "missing")
            return np.asarray(default, dtype=np.float64)
        value = table[name]
        if not isinstance(value, list) or len(value) != 3 or not all(map(_is_number, value)):
            raise self.error(full, f"must be a list of 3 numbers, got {_shown(value)}")
        numbers = [_as_float(x) for x in value]
        if None in numbers:
            raise self.error(full, f"must be finite, got {_shown(value)}")
        return np.asarray(numbers, dtype=np.float64)

    def point(self, table: dict, key: str, name: str) -> np.ndarray:
        """A position in the scene: a vector within +-MAX_COORDINATE."""
        point = self.vector(table, key, name)
        if np.abs(point).max() > MAX_COORDINATE:
            raise self.error(
                f"{key}.{name}",
                f"must lie within +-{MAX_COORDINATE:g} of the origin (float32 rays), got {point.tolist()}",
            )
        return point

    def number(self, table: dict, key: str, name: str, default: float | None = None) -> float:
        full = f"{key}.{name}"
        if name not in table:
            if default is None:
                raise self.error(full, "missing")
            return default
        value = table[name]
        number = _as_float(value) if _is_number(value) else None
        if number is None:
            raise self.error(full, f"must be a finite number, got {_shown(value)}")
        return number

    def colour(
        self, table: dict, key: str, name: str, default, upper: float = 1.0, why: str = "energy conservation"
    ) -> np.ndarray:
        """One number (a grey) or three, each from 0 to ``upper``."""
        full = f"{key}.{name}"
        value = table.get(name, default)
        if _is_number(value):
            value = [value] * 3
        if not isinstance(value, list):
            raise self.error(full, f"must be a colour: one number or a list of 3, got {_shown(value)}")
        colour = self.vector({name: value}, key, name)
        if np.any(colour < 0):
            raise self.error(full, f"must not be negative, got {colour.tolist()}")
        if np.any(colour > upper):
            raise self.error(full, f"must be at most {upper:g} ({why}), got {colour.tolist()}")
        return colour

    def camera(self, spec: dict) -> Camera:
        key = "camera"
        self.check_keys(spec, key, {"position", "look_at", "direction", "up", "fov"})
        position = self.point(spec, key, "position")
        if ("look_at" in spec) == ("direction" in spec):
            raise self.error(key, "give exactly one of `look_at` and `direction`")
        if "look_at" in spec:
            forward = self.point(spec, key, "look_at") - position
            if not forward.any():
                raise self.error(f"{key}.look_at", "is the camera's position: the camera looks nowhere")
        else:
            forward = self.vector(spec, key, "direction")
            if not forward.any():
                raise self.error(f"{key}.direction", "must not be zero")
        up = self.vector(spec, key, "up", default=(0.0, 1.0, 0.0))
        fov = self.number(spec, key, "fov", default=40.0)
        if not 0 < fov < 180:
            raise self.error(f"{key}.fov", f"must be between 0 and 180 degrees, got {fov}")
        forward = _scaled_to_one(forward)
        forward = forward / np.linalg.norm(forward)
        if not up.any():
            raise self.error(f"{key}.up", "must not be zero")
        up = _scaled_to_one(up)
        if np.linalg.norm(np.cross(forward, up / np.linalg.norm(up))) < 1e-6:
            raise self.error(f"{key}.up", "must not be parallel to the viewing direction")
        return Camera.look_at(position, position + forward, up, fov)

    def material(self, key: str, spec: dict) -> Material:
        if not isinstance(spec, dict):
            raise self.error(key, f"must be a table, got {_shown(spec)}")
        kind = spec.get("type")
        known = ", ".join(MATERIAL_KEYS)
        if kind is None:
            raise self.error(f"{key}.type", f"missing (known types: {known})")
        if not isinstance(kind, str) or kind not in MATERIAL_KEYS:
            raise self.error(f"{key}.type", f"unknown material type {_shown(kind)} (known types: {known})")
        self.check_keys(spec, key, {"type", "emission"} | MATERIAL_KEYS[kind])
        emission = self.colour(spec, key, "emission", default=0.0, upper=MAX_RADIANCE, why="float32 radiance")
        try:
            material = self.build_material(kind, key, spec)
        except ValueError as error:
            raise self.error(key, str(error)) from None
        material.emission = emission if emission.max() > 0 else None
        return material

    def build_material(self, kind: str, key: str, spec: dict) -> Material:
        """The material of one ``[materials.NAME]`` table (its keys already checked)."""
        if kind == "diffuse":
            if isinstance(spec.get("albedo"), dict):
                return Diffuse(albedo=self.checkerboard(f"{key}.albedo", spec["albedo"]))
            return Diffuse(albedo=self.colour(spec, key, "albedo", default=0.8))
        if kind == "mirror":
            return Mirror(
                reflectance=self.colour(spec, key, "reflectance", 1.0),
                fresnel=self.flag(spec, key, "fresnel", default=False),
            )
        if kind == "dielectric":
            return Dielectric(
                eta=self.number(spec, key, "eta", default=1.5),
                transmittance=self.colour(spec, key, "transmittance", 1.0),
            )
        f0 = spec.get("f0", "gold")
        if not isinstance(f0, str):
            f0 = self.colour(spec, key, "f0", default=None)
        options = {name: self.number(spec, key, name) for name in ("roughness", "alpha") if name in spec}
        sampling = spec.get("sampling", "vndf")
        if not isinstance(sampling, str):
            raise self.error(f"{key}.sampling", f"must be a string, got {_shown(sampling)}")
        return Microfacet(
            f0=f0,
            kd=self.colour(spec, key, "kd", 0.0),
            ks=self.colour(spec, key, "ks", 1.0),
            sampling=sampling,
            **options,
        )

    def checkerboard(self, key: str, spec: dict) -> Checkerboard:
        """``{ checkerboard = [COLOUR, COLOUR], scale = 5 }``: Homework 5's floor texture."""
        self.check_keys(spec, key, {"checkerboard", "scale"})
        colours = spec.get("checkerboard")
        if not isinstance(colours, list) or len(colours) != 2:
            raise self.error(f"{key}.checkerboard", f"must be a list of two colours, got {_shown(colours)}")
        pair = [
            self.colour({"colour": c}, f"{key}.checkerboard[{i}]", "colour", None)
            for i, c in enumerate(colours)
        ]
        scale = self.number(spec, key, "scale", default=5.0)
        if not 0 < scale <= MAX_COORDINATE:
            raise self.error(
                f"{key}.scale", f"must be a positive number of squares per unit of uv, got {scale:g}"
            )
        return Checkerboard(pair, scale)

    def flag(self, table: dict, key: str, name: str, default: bool) -> bool:
        value = table.get(name, default)
        if not isinstance(value, bool):
            raise self.error(f"{key}.{name}", f"must be true or false, got {_shown(value)}")
        return value

    def mesh(
        self, key: str, spec: dict, material_names: list[str]
    ) -> tuple[np.ndarray, np.ndarray | None, int, str]:
        """The triangles of one ``[[mesh]]``, their texture coordinates (or None), its
        material's index, and the key they came from."""
        self.check_keys(spec, key, {"file", "sphere", "quad", "material", "scale"})
        if not isinstance(spec.get("material"), str):
            raise self.error(f"{key}.material", "missing, or not a string")
        if spec["material"] not in material_names:
            raise self.error(
                f"{key}.material",
                f"no material named {_shown(spec['material'])} (defined: {', '.join(material_names)})",
            )
        shapes = [name for name in ("file", "sphere", "quad") if name in spec]
        if len(shapes) != 1:
            raise self.error(key, "give exactly one of `file`, `sphere` and `quad`")
        if "scale" in spec and "file" not in spec:
            raise self.error(
                f"{key}.scale", "scales a mesh `file` only (give a sphere its radius, a quad its corners)"
            )
        material = material_names.index(spec["material"])
        shape_key = f"{key}.{shapes[0]}"
        if "sphere" in spec:
            return self.sphere(shape_key, spec["sphere"]), None, material, shape_key
        if "quad" in spec:
            return *self.quad(shape_key, spec["quad"]), material, shape_key
        scale = self.number(spec, key, "scale", default=1.0)
        if not 0 < scale <= MAX_COORDINATE:
            raise self.error(f"{key}.scale", f"must be a positive number, got {scale:g}")
        triangles, uv = self.mesh_file(shape_key, spec["file"], scale)
        return triangles, uv, material, shape_key

    def mesh_file(self, key: str, name: object, scale: float) -> tuple[np.ndarray, np.ndarray | None]:
        """A mesh file's triangles (times ``scale``) and texture coordinates (or None)."""
        if not isinstance(name, str):
            raise self.error(key, f"must be a string, got {_shown(name)}")
        mesh_path = self.path.parent / name
        try:
            kind = path_kind(mesh_path)
        except PtlabError as error:
            raise self.error(key, str(error)) from None
        if kind is None:
            raise self.error(key, f"mesh file not found: {mesh_path}")
        if kind == "folder":
            raise self.error(key, f"{mesh_path} is a folder, not a mesh file")
        if kind != "file":
            raise self.error(key, f"{mesh_path} is not a regular file (a device or a pipe?)")
        triangles, uv = read_mesh(mesh_path, f"{self.path}: {key}", MAX_COORDINATE / scale)
        if scale == 1:
            return triangles, uv
        triangles = triangles * scale
        kept = has_area(triangles)
        if not kept.any():
            raise self.error(key, f"scaled by {scale:g}, every triangle has zero area")
        return triangles[kept], None if uv is None else uv[kept]

    def quad(self, key: str, spec: dict) -> tuple[np.ndarray, np.ndarray]:
        """Two triangles from ``{corners = [P0, P1, P2, P3], uv = [[u, v] x 4]}``: (P0, P1,
        P3) and (P1, P2, P3), as Homework 5 splits its floor; uv defaults to the unit square
        (0, 0), (1, 0), (1, 1), (0, 1)."""
        self.check_keys(spec, key, {"corners", "uv"})
        corners = spec.get("corners")
        if not isinstance(corners, list) or len(corners) != 4:
            raise self.error(f"{key}.corners", f"must be a list of 4 points, got {_shown(corners)}")
        points = np.array(
            [self.point({"corner": c}, f"{key}.corners[{i}]", "corner") for i, c in enumerate(corners)]
        )
        uv = spec.get("uv", [[0, 0], [1, 0], [1, 1], [0, 1]])
        if not (
            isinstance(uv, list)
            and len(uv) == 4
            and all(isinstance(c, list) and len(c) == 2 and all(map(_is_number, c)) for c in uv)
        ):
            raise self.error(f"{key}.uv", f"must be 4 pairs [u, v], one per corner, got {_shown(uv)}")
        values = [[_as_float(x) for x in c] for c in uv]
        if any(x is None for c in values for x in c):
            raise self.error(f"{key}.uv", f"must be finite, got {_shown(uv)}")
        corners_of = np.array([[0, 1, 3], [1, 2, 3]])
        triangles, uvs = points[corners_of], np.array(values)[corners_of]
        kept = has_area(triangles)
        if not kept.any():
            raise self.error(f"{key}.corners", "the quad has zero area")
        return triangles[kept], uvs[kept]

    def sphere(self, key: str, spec: dict) -> np.ndarray:
        """An icosphere (trimesh) from ``{center = [x, y, z], radius = r, subdivisions = 4}``."""
        import trimesh

        self.check_keys(spec, key, {"center", "radius", "subdivisions"})
        center = self.point(spec, key, "center")
        radius = self.number(spec, key, "radius")
        subdivisions = spec.get("subdivisions", 4)
        if radius < MIN_RADIUS:
            raise self.error(f"{key}.radius", f"must be at least {MIN_RADIUS:g}, got {radius:g}")
        if np.abs(center).max() + radius > MAX_COORDINATE:
            raise self.error(
                f"{key}.radius",
                f"the sphere reaches beyond +-{MAX_COORDINATE:g} (float32 rays), radius {radius:g}",
            )
        if not (is_integer(subdivisions) and 0 <= subdivisions <= 7):
            raise self.error(
                f"{key}.subdivisions", f"must be an integer from 0 to 7, got {_shown(subdivisions)}"
            )
        mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
        triangles = drop_zero_area(mesh.vertices[mesh.faces] + center)
        if len(triangles) == 0:
            raise self.error(
                f"{key}.radius",
                f"{radius:g} is too small for a sphere centred "
                f"{np.abs(center).max():g} from the origin: its "
                f"triangles have zero area",
            )
        return triangles

    def check_extent(self, triangles: list[np.ndarray], keys: list[str]) -> None:
        """The whole scene's size and place, against MIN_SCENE_SIZE and MAX_DISTANCE_IN_SIZES."""
        boxes = [bounds(t) for t in triangles]  # (each mesh's: no copy of them all)
        lows, highs = zip(*boxes, strict=True)
        size = float((np.max(highs, axis=0) - np.min(lows, axis=0)).max())
        if size < MIN_SCENE_SIZE:
            raise self.error(
                "mesh",
                f"the scene is only {size:g} wide; float32 rays need at "
                f"least {MIN_SCENE_SIZE:g}: use smaller units",
            )
        farthest = [float(max(-low.min(), high.max())) for low, high in boxes]
        i = int(np.argmax(farthest))
        if farthest[i] > MAX_DISTANCE_IN_SIZES * size:
            raise self.error(
                keys[i],
                f"a vertex lies {farthest[i]:g} from the origin, more "
                f"than {MAX_DISTANCE_IN_SIZES:g} times the scene's width "
                f"({size:g}): rays would leave surfaces "
                f"{OFFSET_SCALE * farthest[i]:g} off them; move the scene "
                f"nearer the origin",
            )

    def check_light_power(
        self,
        triangles: np.ndarray,
        material_ids: np.ndarray,
        materials: list[Material],
        point_lights: PointLights | None,
    ) -> None:
        """The lights' total power (area x radiance, and 4 pi x intensity), which light
        sampling divides by in float32, must be a normal float32 number.

        ``triangles``: (T, 3, 3), ``material_ids``: (T,) their materials' indices."""
        emission = np.array([m.emission if m.emission is not None else np.zeros(3) for m in materials])
        lit = np.flatnonzero(emission.any(axis=1).take(material_ids))
        power = float(
            np.sum(area_times_radiance(triangle_areas(triangles[lit]), emission[material_ids[lit]]))
        )
        float32 = np.finfo(np.float32)
        if power > 0 and not float32.tiny <= power <= float32.max:
            raise self.error(
                None,
                f"the lights' total power (area x radiance) is {power:g}, "
                f"outside float32's range: change the emission or the units",
            )
        if point_lights is not None and not point_lights.power <= float32.max:
            raise self.error(
                "point_light",
                f"the point lights' total power (4 pi x intensity) "
                f"is {point_lights.power:g}, beyond float32's range",
            )
