"""OBJ material files (``.mtl``): each material's diffuse colour and image, and what else
it says, which ptlab does not use.

A material file is a list of ``newmtl NAME`` blocks, each of statements ``keyword values``
(Wavefront's "MTL material format", Alias|Wavefront 1995). ptlab's materials from mesh files
are Lambertian, so it reads the diffuse part only:

* ``Kd r g b``: the diffuse reflectance (one number: a grey);
* ``map_Kd [options] file``: an image of it; the specification multiplies it by ``Kd``, so the
  colour is the image times ``Kd`` where both are given (the image alone where ``Kd`` is not).

Every other statement that changes how the surface looks (specular colour and exponent,
transparency, emission, bump and other maps, the PBR extension's roughness and metallic) is
named in the material's ``unused`` list; statements that do not (``Ka``, ``illum``, a black
``Ks`` or ``Ke``, an opaque ``d``) are skipped quietly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ptlab.meshes.base import FileMaterial

#: What ptlab calls each statement it does not use (the first word of its line).
IGNORED = {
    "Ks": "specular colour (Ks)",
    "Ns": "specular exponent (Ns)",
    "Ke": "emission (Ke)",
    "d": "transparency (d)",
    "Tr": "transparency (Tr)",
    "Tf": "transmission filter (Tf)",
    "Ni": "index of refraction (Ni)",
    "map_Ks": "specular map (map_Ks)",
    "map_Ns": "specular exponent map (map_Ns)",
    "map_d": "transparency map (map_d)",
    "map_Ke": "emission map (map_Ke)",
    "map_Bump": "bump map (map_Bump)",
    "map_bump": "bump map (map_bump)",
    "bump": "bump map (bump)",
    "norm": "normal map (norm)",
    "disp": "displacement map (disp)",
    "decal": "decal map (decal)",
    "refl": "reflection map (refl)",
    "Pr": "roughness (Pr)",
    "Pm": "metallic (Pm)",
    "Ps": "sheen (Ps)",
    "Pc": "clearcoat (Pc)",
    "Pcr": "clearcoat roughness (Pcr)",
    "aniso": "anisotropy (aniso)",
    "anisor": "anisotropy rotation (anisor)",
    "map_Pr": "roughness map (map_Pr)",
    "map_Pm": "metallic map (map_Pm)",
    "map_Ps": "sheen map (map_Ps)",
}
#: Statements that say nothing a Lambertian surface could show: ambient colour and map (no
#: ambient light in a path tracer), the illumination model (ptlab's is its own), sharpness.
QUIET = {"Ka", "map_Ka", "illum", "sharpness"}
#: Statements whose values, when these, change nothing: black specular and emission, opaque.
NEUTRAL = {"Ks": 0.0, "Ke": 0.0, "Tr": 0.0, "d": 1.0, "Tf": 1.0}
#: Statements that change nothing on an opaque surface, said only of a material that lets
#: light through (``d`` below 1, ``Tr`` above 0): the index of refraction (every exporter
#: writes one, e.g. Blender's ``Ni 1.45``).
OF_TRANSPARENCY = {"Ni"}
#: The options a texture statement may give before its file, and how many values each
#: takes: words (on/off, a channel) or up to that many numbers (``-o``, ``-s``, ``-t``).
WORD_OPTIONS = {"-blendu", "-blendv", "-clamp", "-cc", "-imfchan", "-type"}
NUMBER_OPTIONS = {"-boost": 1, "-mm": 2, "-o": 3, "-s": 3, "-t": 3, "-texres": 1, "-bm": 1}


def read_mtl(path: Path) -> list[tuple[FileMaterial, list[str]]]:
    """Each material of a material file, with what ptlab does not use of it; ``ValueError``
    naming the file and line of a statement ptlab cannot read (a ``Kd`` that is not 1 or 3
    numbers, a ``map_Kd`` without a file)."""
    text = path.read_bytes().decode("utf-8", errors="replace")
    found: list[tuple[FileMaterial, list[str]]] = []
    of_transparency: dict[int, list[str]] = {}  # (material -> its ``OF_TRANSPARENCY`` statements)
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.split(None, 1)
        if not words or words[0].startswith("#"):
            continue
        keyword, rest = words[0], words[1].strip() if len(words) > 1 else ""
        where = f"{path.name}, line {number}"
        if keyword == "newmtl":
            found.append((FileMaterial(rest, None, None, where), []))
        elif found and keyword in OF_TRANSPARENCY:
            of_transparency.setdefault(len(found) - 1, []).append(keyword)
        elif found:  # (statements before any newmtl belong to no material)
            _read_statement(path, where, keyword, rest, *found[-1])
    for k, keywords in of_transparency.items():
        unused = found[k][1]
        if any(phrase.startswith("transparency") for phrase in unused):
            for keyword in keywords:
                _add(unused, IGNORED[keyword])
    return found


def _read_statement(
    path: Path, where: str, keyword: str, rest: str, material: FileMaterial, unused: list[str]
) -> None:
    """One statement ``keyword rest`` of material file ``path`` (at ``where``): into
    ``material`` what ptlab uses, into ``unused`` what it does not."""
    if keyword == "Kd" and rest.split()[:1] in (["spectral"], ["xyz"]):
        _add(unused, f"diffuse colour given as {rest.split()[0]} (Kd)")
    elif keyword == "Kd":
        material.albedo = _colour(rest, where)
    elif keyword == "map_Kd":
        file, options = _texture_file(rest, where)
        material.texture = path.parent / file
        if not material.texture.exists() and "\\" in file:  # (written on Windows)
            material.texture = path.parent / file.replace("\\", "/")
        if options:
            _add(unused, f"texture options of map_Kd ({' '.join(options)})")
    elif keyword in IGNORED and not _neutral(keyword, rest):
        _add(unused, IGNORED[keyword])
    elif keyword not in IGNORED and keyword not in QUIET:
        _add(unused, f"`{keyword}`")


def _add(unused: list[str], phrase: str) -> None:
    """Add ``phrase`` to ``unused`` once."""
    if phrase not in unused:
        unused.append(phrase)


def _numbers(text: str) -> list[float] | None:
    """The numbers of ``text``, or None if it holds something else."""
    try:
        return [float(word) for word in text.split()]
    except ValueError:
        return None


def _colour(text: str, where: str) -> np.ndarray:
    """(3,) the colour ``r g b`` (or one grey number) of a ``Kd`` statement."""
    values = _numbers(text)
    if values is None or len(values) not in (1, 3) or not np.isfinite(values).all():
        raise ValueError(f"{where}: `Kd` needs 1 or 3 numbers (r g b), got {text!r}")
    return np.array(values * 3 if len(values) == 1 else values, dtype=np.float64)


def _neutral(keyword: str, text: str) -> bool:
    """Whether a statement's values change nothing (``NEUTRAL``: ``Ks 0 0 0``, ``d 1``)."""
    values = _numbers(text)
    return keyword in NEUTRAL and bool(values) and all(v == NEUTRAL[keyword] for v in values or [])


def _texture_file(text: str, where: str) -> tuple[str, list[str]]:
    """The file name of a texture statement's arguments ``[options] file``, and the options
    given before it (ptlab uses none). A name may hold spaces; quotes around it are taken off."""
    words = text.split()
    options = []
    while words and (words[0] in WORD_OPTIONS or words[0] in NUMBER_OPTIONS):
        option = [words.pop(0)]
        if option[0] in WORD_OPTIONS:
            option += words[:1]
            words = words[1:]
        else:
            # (Up to the option's count of numbers; the last word is the file, even a number.)
            while len(words) > 1 and len(option) <= NUMBER_OPTIONS[option[0]] and _numbers(words[0]):
                option.append(words.pop(0))
        options.append(" ".join(option))
    name = " ".join(words)
    quote = name[:1]
    if quote in ('"', "'"):
        if len(name) < 2 or not name.endswith(quote):
            raise ValueError(f"{where}: `map_Kd` {name}: the quotation mark is not closed at the name's end")
        name = name[1:-1]
    if not name:
        raise ValueError(f"{where}: `map_Kd` names no image file")
    return name, options
