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

A mesh may be placed by a transform (``scale``, ``rotate``, ``translate`` or ``matrix``:
``ptlab.transforms``), given as arrays (``vertices`` and ``faces``), and take its mesh file's
own materials when it names none.

``load_scene`` finds the file (a path, a folder holding ``scene.toml``, or the name of a
built-in scene), checks every value and flattens every mesh into the ``Scene``'s one array
of triangles. ``load_dict`` reads the same tables from a Python dict (Mitsuba 3's
``load_dict``), through the same reader. Anything wrong raises a ``SceneError`` that names
the file (or "scene dict"), the key and the problem; what a mesh file brings that ptlab does
not use is said in one warning per mesh.
"""

from __future__ import annotations

import math
import os
import reprlib
import tomllib
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ptlab.atomic import path_kind
from ptlab.camera import Camera
from ptlab.errors import PtlabError, SceneError, is_integer
from ptlab.lights import PointLights, Sky, area_times_radiance, triangle_areas, triangle_normals
from ptlab.materials import Dielectric, Diffuse, Material, Microfacet, Mirror
from ptlab.meshes import UV_LIMIT, FileMaterial, MeshData, drop_zero_area, has_area, read_mesh_data
from ptlab.scene import OFFSET_SCALE, RenderDefaults, Scene, bounds
from ptlab.textures import Checkerboard, ImageTexture, Texture
from ptlab.transforms import Transform, rotation

SCENE_FILE_NAME = "scene.toml"

#: The keys each material type takes in a scene file (besides ``type`` and ``emission``).
MATERIAL_KEYS = {
    "diffuse": {"albedo"},
    "microfacet": {"f0", "roughness", "alpha", "kd", "ks", "sampling"},
    "mirror": {"reflectance", "fresnel"},
    "dielectric": {"eta", "transmittance"},
}
#: What a ``[[mesh]]`` is made of: exactly one of these per mesh.
SHAPES = ("file", "sphere", "quad", "vertices", "trimesh")
#: The keys of a mesh given as arrays, beside ``vertices``, and the shapes each goes with (a
#: trimesh's table may give its normals, which ptlab does not take from it, and replace its uv).
ARRAY_KEYS = {"faces": ("vertices",), "normals": ("vertices", "trimesh"), "uv": ("vertices", "trimesh")}
#: The keys that place a mesh (``ptlab.transforms``): ``matrix``, or any of the other three.
TRANSFORM_KEYS = ("scale", "rotate", "translate", "matrix")
#: The albedo of a mesh file's faces that have no material (a diffuse material's default).
DEFAULT_ALBEDO = 0.8
#: What errors and warnings name as the source of a scene built in Python.
DICT_SOURCE = "scene dict"

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
    name = path.parent.name if path.name == SCENE_FILE_NAME else path.stem
    return _SceneReader(path, path.parent, name).read(data)


def load_dict(scene: dict, folder: str | Path = ".", name: str = "scene") -> Scene:
    """A scene built in Python (Mitsuba 3's ``load_dict``): a dict of the scene file's tables.

    The keys and values are a scene file's (``docs/scene-format.md``), read by the same
    reader, so ``load_dict(tomllib.load(file), folder)`` is ``load_scene(file)``. A notebook
    may also give NumPy arrays, tuples and NumPy numbers where the file has lists and
    numbers, ``pathlib`` paths where it has file names, and::

        {"vertices": (V, 3), "faces": (F, 3), "normals": (V, 3), "uv": (V, 2), ...}

    as a mesh (arrays or nested lists; normals and uv optional), ``{"trimesh": mesh}`` (a
    ``trimesh.Trimesh``), a ``ptlab.materials.Material`` in place of a material's table or
    of a mesh's material name (used as it is, not copied), and a ``ptlab.textures.Texture``
    as a diffuse albedo.

    Args:
        scene: the tables: ``camera``, ``materials``, ``mesh`` (a list), and optionally
            ``point_light`` (a list), ``sky``, ``render``, ``description``.
        folder: where the mesh and image files that the dict names are.
        name: the scene's name (in messages, and a render's default file name).

    Raises ``SceneError`` naming "scene dict", the key and the problem, as a file's do.
    """
    if not isinstance(scene, dict):
        raise SceneError(DICT_SOURCE, f"must be a dict of the scene file's tables, got {_shown(scene)}")
    if not isinstance(name, str):
        raise SceneError(DICT_SOURCE, f"the scene's name must be text, got {_shown(name)}")
    if not isinstance(folder, str | os.PathLike):
        raise SceneError(DICT_SOURCE, f"folder must be a path, got {_shown(folder)}")
    try:
        data = {key: _plain(value) for key, value in scene.items() if key != "mesh"}
        if "mesh" in scene:
            meshes = scene["mesh"]
            data["mesh"] = (
                [_plain_mesh(m) for m in meshes] if isinstance(meshes, list | tuple) else _plain(meshes)
            )
    except RecursionError:
        raise SceneError(DICT_SOURCE, "nested too deeply (does it contain itself?)") from None
    return _SceneReader(DICT_SOURCE, Path(folder), name).read(data)


def _plain(value: object) -> object:
    """``value`` with the Python and NumPy types a notebook writes turned into the scene
    file's: tuples and arrays into lists, NumPy numbers into Python's, paths into text.
    Anything else (a ``Material``, a ``Texture``) is left for the reader to take or refuse."""
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(item) for item in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return value


def _plain_mesh(spec: object) -> object:
    """One mesh of a scene dict made plain (``_plain``), but for its arrays (``vertices``,
    ``faces``, ``normals``, ``uv``) and its ``trimesh``, which the reader takes as they are
    (a million vertices as Python lists would take seconds)."""
    if not isinstance(spec, dict):
        return _plain(spec)
    kept = {"vertices", "trimesh", *ARRAY_KEYS}
    return {key: value if key in kept else _plain(value) for key, value in spec.items()}


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


@dataclass
class _MeshPart:
    """One ``[[mesh]]`` as the scene takes it: (T, 3, 3) triangles, their (T, 3, 2) uv and
    (T, 3, 3) corner normals (or None), (T,) indices into the scene's materials, and the key
    it came from."""

    triangles: np.ndarray
    uv: np.ndarray | None
    normals: np.ndarray | None
    material_ids: np.ndarray
    key: str


def _joined_uv(parts: list[_MeshPart]) -> np.ndarray:
    """(T, 3, 2) every mesh's uv, one mesh after another (0 for a mesh without)."""
    return np.concatenate([p.uv if p.uv is not None else np.zeros((len(p.triangles), 3, 2)) for p in parts])


def _joined_normals(parts: list[_MeshPart]) -> np.ndarray | None:
    """(T, 3, 3) every mesh's corner normals, one mesh after another, with the flat normal
    at each corner of a mesh that has none; None where no mesh has any (all flat)."""
    if all(p.normals is None for p in parts):
        return None
    return np.concatenate(
        [
            p.normals
            if p.normals is not None
            else np.repeat(triangle_normals(p.triangles)[:, None], 3, axis=1)
            for p in parts
        ]
    )


class _SceneReader:
    """Turns the tables of one scene (a file's parsed TOML, or a dict) into a ``Scene``,
    checking every value.

    Args:
        source: what messages name: the scene file, or ``DICT_SOURCE``.
        folder: where the file names in the tables start.
        name: the scene's name.
    """

    def __init__(self, source: str | Path, folder: Path, name: str):
        self.source = source
        self.folder = folder
        self.name = name
        #: The scene's materials and their names: the named ones first, then those that
        #: meshes bring (their files' materials, ``Material`` objects of a dict's meshes).
        self.materials: list[Material] = []
        self.material_names: list[str] = []
        self.table_size = 0  # (how many of them are named)
        #: What the meshes bring that ptlab does not use, one line per mesh, said at the end.
        self.warnings: list[str] = []

    def error(self, key: str | None, problem: str) -> SceneError:
        return SceneError(self.source, problem, key)

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
        self.table_size = len(materials_table)
        for name, spec in materials_table.items():
            if not isinstance(name, str):
                raise self.error("materials", f"a material's name must be text, got {_shown(name)}")
            self.materials.append(self.material(f"materials.{name}", spec))
            self.material_names.append(name)
        meshes = data.get("mesh", [])
        if not isinstance(meshes, list):
            raise self.error("mesh", f"must be an array of tables, each one [[mesh]], got {_shown(meshes)}")
        if not meshes:
            raise self.error("mesh", "no meshes: add a [[mesh]] section")
        parts = [self.mesh(f"mesh[{i}]", spec) for i, spec in enumerate(meshes)]
        self.check_extent([part.triangles for part in parts], [part.key for part in parts])
        all_triangles = np.concatenate([part.triangles for part in parts])
        material_of_triangle = np.concatenate([part.material_ids for part in parts])
        point_lights = self.point_lights(data.get("point_light", []))
        sky = self.sky(data["sky"]) if "sky" in data else None
        self.check_light_power(all_triangles, material_of_triangle, self.materials, point_lights)
        scene = Scene(
            triangles=all_triangles,
            material_ids=material_of_triangle,
            materials=self.materials,
            camera=camera,
            name=self.name,
            material_names=self.material_names,
            point_lights=point_lights,
            sky=sky,
            uvs=_joined_uv(parts) if any(m.textured for m in self.materials) else None,
            normals=_joined_normals(parts),
            defaults=self.render_defaults(data.get("render", {})),
        )
        if scene.light_sampler is None:
            raise self.error(
                None,
                "the scene has no light: give a material an `emission` "
                "and a mesh that uses it, add a [[point_light]], or a [sky]",
            )
        for message in self.warnings:  # (stacklevel 3: the line that called load_scene or load_dict)
            warnings.warn(message, UserWarning, stacklevel=3)
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

    def material(self, key: str, spec: dict | Material) -> Material:
        """The material of one ``[materials.NAME]`` table, or a dict's ``Material`` object."""
        if isinstance(spec, Material):
            return self.material_object(key, spec)
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
            albedo = spec.get("albedo")
            if isinstance(albedo, Texture):  # (a dict's)
                if isinstance(albedo, Checkerboard):  # (its colours, as a file's are checked)
                    for i, colour in enumerate(albedo.colours):
                        self.colour({"colour": colour.tolist()}, f"{key}.albedo.colours[{i}]", "colour", None)
                return Diffuse(albedo=albedo)
            if isinstance(albedo, dict):
                return Diffuse(albedo=self.texture(f"{key}.albedo", albedo))
            return Diffuse(albedo=self.colour(spec, key, "albedo", default=DEFAULT_ALBEDO))
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

    def material_object(self, key: str, material: Material) -> Material:
        """A dict's ``Material``, taken as it is once its emission is checked as a file's."""
        emission = material.emission
        if emission is not None:
            emission = np.asarray(emission)
            if not (
                emission.shape == (3,)
                and np.isfinite(emission).all()
                and (emission >= 0).all()
                and (emission <= MAX_RADIANCE).all()
            ):
                raise self.error(
                    f"{key}.emission",
                    f"must be 3 numbers from 0 to {MAX_RADIANCE:g} (float32 radiance), "
                    f"got {_shown(emission)}",
                )
        return material

    def texture(self, key: str, spec: dict) -> Texture:
        """A diffuse albedo's texture: ``{ image = FILE }`` or ``{ checkerboard = ... }``."""
        if "image" in spec:
            self.check_keys(spec, key, {"image"})
            name = spec["image"]
            if not isinstance(name, str):
                raise self.error(f"{key}.image", f"must be the image's file name, got {_shown(name)}")
            return self.image(f"{key}.image", self.folder / name)
        if "checkerboard" in spec:
            return self.checkerboard(key, spec)
        raise self.error(
            key, "must be a colour, { image = FILE } or { checkerboard = [COLOUR, COLOUR], scale = S }"
        )

    def image(self, key: str, source: Path | np.ndarray, name: str = "") -> ImageTexture:
        """An image texture from a file or, for an image a mesh file holds (a GLB's), from
        its pixels (``name`` says whose)."""
        if isinstance(source, np.ndarray):
            return ImageTexture.from_array(source, name)
        try:
            return ImageTexture(source)
        except PtlabError as error:  # (a missing or unreadable file, named)
            raise self.error(key, f"{name}: {error}" if name else str(error)) from None

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

    def mesh(self, key: str, spec: dict) -> _MeshPart:
        """One ``[[mesh]]``: its shape read, placed by its transform, and its materials."""
        self.check_keys(spec, key, {*SHAPES, *ARRAY_KEYS, *TRANSFORM_KEYS, "material"})
        shapes = [name for name in SHAPES if name in spec]
        if len(shapes) != 1:
            raise self.error(
                key,
                "give exactly one of `file`, `sphere` and `quad` (or `vertices` with `faces`, or `trimesh`)",
            )
        shape = shapes[0]
        for name, shapes_with in ARRAY_KEYS.items():
            if name in spec and shape not in shapes_with:
                raise self.error(f"{key}.{name}", f"goes with {' or '.join(shapes_with)}, not {shape}")
        # (The cheap checks first: a typo is found before a large file is read.)
        named = self.named_material(f"{key}.material", spec["material"]) if "material" in spec else None
        if named is None and shape not in ("file", "trimesh"):
            raise self.error(f"{key}.material", "missing: the name of one of the scene's materials")
        transform = self.transform(key, spec)
        shape_key = f"{key}.{shape}"
        data, shown = self.shape(key, shape, spec, transform.is_identity)
        data = self.placed(shape_key, data, transform, shown)
        unused = list(data.unused)
        if named is None:
            material_ids = self.file_materials(shape_key, data)
        else:
            material_ids = np.full(len(data.triangles), named, dtype=np.intp)
            if data.materials:
                unused.append(f"its materials (the scene's `{self.material_names[named]}` is used)")
        if unused:
            self.warnings.append(f"{self.source}: {shape_key}: {shown}: ptlab ignores {'; '.join(unused)}")
        for material in np.unique(material_ids):
            if self.materials[material].textured and data.uv is None:
                raise self.error(
                    shape_key,
                    f"material {self.material_names[material]!r} is textured, but this mesh has no "
                    f"texture coordinates (a `quad`'s `uv`, `vt` lines in an OBJ file, or `uv`)",
                )
        return _MeshPart(data.triangles, data.uv, data.normals, material_ids, shape_key)

    def shape(self, key: str, shape: str, spec: dict, untransformed: bool) -> tuple[MeshData, str]:
        """Mesh ``key``'s ``shape``, as it is given (before its transform), and what messages
        call it."""
        shape_key = f"{key}.{shape}"
        # (Untransformed, the coordinates are checked as they are read; else once transformed.)
        limit = MAX_COORDINATE if untransformed else math.inf
        if shape == "file":
            return self.mesh_file(shape_key, spec["file"], limit), f"mesh {Path(spec['file']).name}"
        if shape == "trimesh":
            return self.trimesh_mesh(key, spec, limit), "the trimesh"
        if shape == "vertices":
            return self.arrays(key, spec, limit), "the arrays"
        if shape == "quad":
            triangles, uv = self.quad(shape_key, spec["quad"])
            return MeshData(triangles, uv, None, None, [], []), "the quad"
        return MeshData(self.sphere(shape_key, spec["sphere"]), None, None, None, [], []), "the sphere"

    def named_material(self, key: str, value: object) -> int:
        """The index of a mesh's ``material``: a name from the scene's materials or, in a
        dict, a ``Material`` object (added to them, once, under the name ``key``)."""
        if isinstance(value, Material):
            for index, material in enumerate(self.materials):
                if material is value:
                    return index
            return self.added(key, self.material_object(key, value))
        if not isinstance(value, str):
            raise self.error(key, f"must be the name of one of the scene's materials, got {_shown(value)}")
        names = self.material_names[: self.table_size]
        if value not in names:
            defined = ", ".join(names) or "none: add a [materials.NAME] table"
            raise self.error(key, f"no material named {_shown(value)} (defined: {defined})")
        return self.material_names.index(value)

    def added(self, name: str, material: Material) -> int:
        """Add ``material`` to the scene's, named ``name``; its index."""
        self.materials.append(material)
        self.material_names.append(name)
        return len(self.materials) - 1

    def file_materials(self, key: str, data: MeshData) -> np.ndarray:
        """(T,) the scene's indices of the materials a mesh file gives its triangles, each
        made a ``Diffuse`` (``file_material``) and added to the scene's; faces without one
        (or every face, where the file has none) get a diffuse DEFAULT_ALBEDO grey."""
        count = len(data.triangles)
        ids = data.material_ids if data.material_ids is not None else np.full(count, -1, dtype=np.intp)
        # One scene index per material the faces use, the last for the faces with none (-1).
        scene_index = np.zeros(len(data.materials) + 1, dtype=np.intp)
        for k in np.unique(ids):
            if k < 0:
                scene_index[-1] = self.added(f"{key}: no material", Diffuse(albedo=DEFAULT_ALBEDO))
            else:
                found = data.materials[k]
                material = self.file_material(key, found)
                scene_index[k] = self.added(f"{key}: {found.name}", material)
        return scene_index[ids]

    def file_material(self, key: str, found: FileMaterial) -> Diffuse:
        """A mesh file's material as ptlab's: a ``Diffuse`` of its colour (OBJ ``Kd``, glTF
        ``baseColorFactor``), or of its image (``map_Kd``, ``baseColorTexture``) times that
        colour, as both formats define it; DEFAULT_ALBEDO where it gives neither."""
        shown = f"material {found.name!r}" + (f" ({found.defined_in})" if found.defined_in else "")
        albedo = None
        if found.albedo is not None:
            albedo = np.asarray(found.albedo, dtype=np.float64)
            if not (albedo.shape == (3,) and ((albedo >= 0) & (albedo <= 1)).all()):
                raise self.error(
                    key,
                    f"{shown}: its colour must be 3 numbers from 0 to 1 (energy conservation), "
                    f"got {_shown(albedo.tolist())}",
                )
        if found.texture is None:
            return Diffuse(albedo=DEFAULT_ALBEDO if albedo is None else albedo)
        texture = self.image(key, found.texture, shown)
        if albedo is not None and (albedo != 1).any():
            texture = texture.tinted(albedo)
        return Diffuse(albedo=texture)

    def transform(self, key: str, spec: dict) -> Transform:
        """A mesh's ``matrix``, or its ``scale``, ``rotate`` and ``translate`` composed
        (scale first, then each rotation in turn, then the translation: ``ptlab.transforms``)."""
        if "matrix" in spec:
            others = [name for name in TRANSFORM_KEYS if name in spec and name != "matrix"]
            if others:
                raise self.error(
                    f"{key}.{others[0]}", "give either a `matrix` or `scale`, `rotate` and `translate`"
                )
            return self.matrix(f"{key}.matrix", spec["matrix"])
        scale = spec.get("scale", 1.0)
        if _is_number(scale):
            scale = [scale] * 3
        if not isinstance(scale, list):
            raise self.error(f"{key}.scale", f"must be a number or a list of 3, got {_shown(scale)}")
        factors = self.vector({"scale": scale}, key, "scale")
        if not factors.all():
            raise self.error(
                f"{key}.scale", f"must not be 0: it would flatten the mesh, got {factors.tolist()}"
            )
        rotate = spec.get("rotate", [])
        steps = rotate if isinstance(rotate, list) else [rotate]
        many = isinstance(rotate, list)
        rotations = [
            self.rotation(f"{key}.rotate[{i}]" if many else f"{key}.rotate", step)
            for i, step in enumerate(steps)
        ]
        translate = self.vector(spec, key, "translate", default=(0.0, 0.0, 0.0))
        return Transform.compose(factors, rotations, translate)

    def rotation(self, key: str, spec: object) -> np.ndarray:
        """(3, 3) the rotation of ``{ axis = [x, y, z], angle = DEGREES }``."""
        if not isinstance(spec, dict):
            raise self.error(
                key, f"must be {{ axis = [x, y, z], angle = DEGREES }} or a list of them, got {_shown(spec)}"
            )
        self.check_keys(spec, key, {"axis", "angle"})
        axis = self.vector(spec, key, "axis")
        if not axis.any():
            raise self.error(f"{key}.axis", "must not be zero")
        return rotation(axis, self.number(spec, key, "angle"))

    def matrix(self, key: str, value: object) -> Transform:
        """A row-major 4 x 4 affine ``matrix``: last row [0, 0, 0, 1], invertible."""
        if not (
            isinstance(value, list)
            and len(value) == 4
            and all(isinstance(row, list) and len(row) == 4 and all(map(_is_number, row)) for row in value)
        ):
            raise self.error(key, f"must be 4 rows of 4 numbers, got {_shown(value)}")
        numbers = [[_as_float(x) for x in row] for row in value]
        if any(x is None for row in numbers for x in row):
            raise self.error(key, f"must be finite, got {_shown(value)}")
        matrix = np.array(numbers)
        if (matrix[3] != [0, 0, 0, 1]).any():
            raise self.error(
                key, f"its last row must be [0, 0, 0, 1] (an affine transform), got {matrix[3].tolist()}"
            )
        transform = Transform.from_matrix(matrix)
        # (Relative to the matrix's size: a matrix of tiny numbers may be well conditioned.)
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            condition = np.linalg.cond(transform.linear)
        if not condition * np.finfo(np.float64).eps < 1:
            raise self.error(key, "is singular (or nearly): it would flatten the mesh")
        return transform

    def placed(self, key: str, data: MeshData, transform: Transform, shown: str) -> MeshData:
        """A mesh transformed, then checked: every coordinate within +-MAX_COORDINATE, and
        the triangles that the transform left without area dropped. (An untransformed mesh
        was checked as it was read.)"""
        if transform.is_identity:
            return data
        triangles, uv, normals = transform.mesh(data.triangles, data.uv, data.normals)
        if not np.abs(triangles).max() <= MAX_COORDINATE:  # (NaN too)
            beyond = ~(np.abs(triangles) <= MAX_COORDINATE).all(axis=2)
            raise self.error(
                key,
                f"{shown}, transformed, has a vertex at {triangles[beyond][0].tolist()}: every "
                f"coordinate must lie within +-{MAX_COORDINATE:g} (float32 rays)",
            )
        data = replace(data, triangles=triangles, uv=uv, normals=normals)
        kept = has_area(triangles)
        if not kept.any():
            raise self.error(key, f"{shown}, transformed, has only zero-area triangles")
        return data if kept.all() else data.taken(kept)

    def mesh_file(self, key: str, name: object, limit: float) -> MeshData:
        """What a mesh file holds (``read_mesh_data``); its coordinates within +-``limit``."""
        if not isinstance(name, str):
            raise self.error(key, f"must be a string, got {_shown(name)}")
        mesh_path = self.folder / name
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
        return read_mesh_data(mesh_path, f"{self.source}: {key}", limit)

    def arrays(self, key: str, spec: dict, limit: float) -> MeshData:
        """A mesh given as arrays: ``vertices`` (V, 3) within +-``limit``, ``faces`` (F, 3)
        indices into them (from 0), and optionally unit ``normals`` (V, 3) and ``uv`` (V, 2)
        per vertex."""
        vertices = self.array(spec, key, "vertices", 3, float)
        if "faces" not in spec:
            raise self.error(f"{key}.faces", "missing: (F, 3) indices of the vertices, three per triangle")
        faces = self.array(spec, key, "faces", 3, int)
        uv = self.array(spec, key, "uv", 2, float) if "uv" in spec else None
        normals = self.array(spec, key, "normals", 3, float) if "normals" in spec else None
        return self.indexed(key, vertices, faces, normals, uv, limit)

    def indexed(
        self,
        key: str,
        vertices: np.ndarray,
        faces: np.ndarray,
        normals: np.ndarray | None,
        uv: np.ndarray | None,
        limit: float,
    ) -> MeshData:
        """The triangles (and uv, normals) of an indexed mesh, checked: faces within the
        vertices, every coordinate within +-``limit``, normals not zero; triangles of zero
        area dropped."""
        count = len(vertices)
        if not np.abs(vertices).max() <= limit:
            vertex = vertices[~(np.abs(vertices) <= limit).all(axis=1)][0]
            raise self.error(
                f"{key}.vertices",
                f"has a vertex at {vertex.tolist()}: every coordinate must lie within "
                f"+-{limit:g} (float32 rays)",
            )
        for name, values in (("normals", normals), ("uv", uv)):
            if values is not None and len(values) != count:
                raise self.error(
                    f"{key}.{name}", f"has {len(values)} rows for {count} vertices: give one per vertex"
                )
        outside = faces[(faces < 0) | (faces >= count)]
        if len(outside):
            raise self.error(
                f"{key}.faces", f"refers to vertex {int(outside[0])}, but there are {count} vertices"
            )
        if normals is not None:
            # (Made unit length by the Scene, as a file's are; a zero normal, which trimesh
            # gives a vertex no face uses, becomes its face's there.)
            normals = normals[faces]
        data = MeshData(vertices[faces], None if uv is None else uv[faces], normals, None, [], [])
        kept = has_area(data.triangles)
        if not kept.any():
            raise self.error(f"{key}.faces", "every triangle has zero area")
        return data if kept.all() else data.taken(kept)

    def array(self, spec: dict, key: str, name: str, width: int, kind: type) -> np.ndarray:
        """A mesh's array ``name``: (N, ``width``) finite numbers (integers if ``kind`` is
        int), N >= 1, from a NumPy array or nested lists."""
        full = f"{key}.{name}"
        value = spec[name]
        what = "integers" if kind is int else "numbers"
        try:
            array = np.asarray(value)
        except (ValueError, TypeError):  # (ragged lists)
            array = None
        allowed = "iu" if kind is int else "iuf"
        if array is None or array.dtype.kind not in allowed or array.ndim != 2 or array.shape[1] != width:
            shape = "" if array is None else f" of shape {array.shape} and type {array.dtype}"
            raise self.error(full, f"must be an (N, {width}) array of {what}, got {_shown(value)}{shape}")
        if len(array) == 0:
            raise self.error(full, "is empty")
        array = array.astype(np.intp if kind is int else np.float64)
        if kind is float and not np.isfinite(array).all():
            raise self.error(full, "must be finite (a value is NaN or infinite)")
        return array

    def trimesh_mesh(self, key: str, spec: dict, limit: float) -> MeshData:
        """Mesh ``key``'s ``trimesh.Trimesh``: its triangles, its uv if it has any, and the
        ``normals`` and ``uv`` the mesh's table gives beside it. (Not the trimesh's vertex
        normals: trimesh computes them whenever they are asked for, so that normals a file
        gave it and normals it made up look the same; a smooth mesh gives them as
        ``normals = mesh.vertex_normals``.)"""
        import trimesh

        mesh = spec["trimesh"]
        if not isinstance(mesh, trimesh.Trimesh):
            raise self.error(f"{key}.trimesh", f"must be a trimesh.Trimesh, got {_shown(mesh)}")
        arrays = {"vertices": np.asarray(mesh.vertices), "faces": np.asarray(mesh.faces)}
        uv = getattr(mesh.visual, "uv", None)
        if uv is not None:
            arrays["uv"] = np.asarray(uv)[:, :2]
        arrays.update({name: spec[name] for name in ("normals", "uv") if name in spec})
        return self.arrays(key, arrays, limit)

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
        if any(x is None or abs(x) > UV_LIMIT for c in values for x in c):
            raise self.error(f"{key}.uv", f"must be finite, within +-{UV_LIMIT:.4g}, got {_shown(uv)}")
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
