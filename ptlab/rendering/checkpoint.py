"""Checkpoints: a render's film saved to disk, so that it can be resumed.

A checkpoint is a NumPy ``.npz`` file holding the film's float64 sums (of the samples, and
of the even ones less the odd ones), the samples taken per tile and per pixel, a noise-target pass under way
(``Film.plan``) and the render's identity: its options (``RenderOptions.record``) but the number
of workers, with the scene's fingerprint and the sampler's identity. Resuming adds the
missing passes in the same order an uninterrupted render would, so the finished image is
bit-identical to one. Settings that change the image (scene, resolution, crop window, seed,
estimator, sampler, tiles, backend) must match;
a resume that asks for more samples per pixel than the checkpoint's render simply goes on
(the stratified sampler, whose pattern depends on spp, excepted).

Files are written atomically (a temporary file, then a rename).
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from ptlab.atomic import path_kind, write_atomically
from ptlab.errors import PtlabError
from ptlab.rendering.film import Film

FORMAT_VERSION = 4
#: Older formats that load: 3 had no differences, counts or plan (a render without a noise target).
READABLE_VERSIONS = (3, FORMAT_VERSION)


def scene_digest(scene) -> str:
    """A fingerprint of the scene's geometry, materials, lights and camera."""
    digest = hashlib.sha256()
    for array in (
        scene.triangles,
        scene.material_ids,
        scene.camera.position,
        scene.camera.forward,
        scene.camera.up,
    ):
        digest.update(np.ascontiguousarray(array).tobytes())
    # (Only where there are some: a scene without them keeps the fingerprint it had before
    # scenes had them, and so do its checkpoints.)
    for optional in (scene.uvs, scene.normals):
        if optional is not None:
            digest.update(np.ascontiguousarray(optional).tobytes())
    lights = [repr(light) for light in (scene.point_lights, scene.sky) if light is not None]
    digest.update(repr((scene.camera.fov_y, [repr(m) for m in scene.materials], *lights)).encode())
    return digest.hexdigest()[:16]


def save_checkpoint(path: str | Path, film: Film, identity: dict, command: dict | None = None) -> None:
    """Write the film and the render's identity to ``path``, atomically; ``command`` is kept
    beside them, not compared: what ``ptlab render --resume FILE`` needs that the options do
    not say (the scene and the output)."""

    def write(temporary: str) -> None:
        arrays: dict[str, Any] = _feature_arrays(film)
        with open(temporary, "wb") as out:
            np.savez(
                out,
                **arrays,
                sums=film.sums,
                differences=film.differences,
                counts=film.counts,
                plan=film.plan if film.plan is not None else np.zeros((0, 0), np.int64),
                plan_done=film.plan_done,
                adaptive_passes=np.int64(film.adaptive_passes),
                estimate=np.float64(np.nan if film.estimate is None else film.estimate),
                passes=np.asarray(film.passes, dtype=np.int64),
                passes_done=film.passes_done,
                rays=np.int64(film.rays),
                query_seconds=np.float64(film.query_seconds),
                sampler_seconds=np.float64(film.sampler_seconds),
                nonfinite=np.int64(film.nonfinite),
                identity=json.dumps(dict(identity, format=FORMAT_VERSION)),
                command=json.dumps(command or {}),
            )

    write_atomically(path, write)


def read_checkpoint(path: str | Path) -> tuple[dict, dict, dict[str, np.ndarray]]:
    """The identity, the command (``save_checkpoint``; {} in older checkpoints) and the
    arrays of the checkpoint at ``path``."""
    path = Path(path)
    if path_kind(path) != "file":
        raise PtlabError(f"{path}: no such checkpoint file")
    try:
        with open(path, "rb") as file, np.load(file, allow_pickle=False) as data:
            saved = json.loads(str(data["identity"]))
            command = json.loads(str(data["command"])) if "command" in data else {}
            arrays = {
                k: data[k]
                for k in ("sums", "passes", "passes_done", "rays", "query_seconds", "sampler_seconds")
            }
            # (checkpoints written before the count was kept have none: 0)
            arrays["nonfinite"] = data["nonfinite"] if "nonfinite" in data else np.int64(0)
            for name in (
                "differences",
                "counts",
                "plan",
                "plan_done",
                "adaptive_passes",
                "estimate",
                "features",
                "feature_differences",
            ):
                if name in data:
                    arrays[name] = data[name]
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as error:
        raise PtlabError(f"{path}: not a ptlab checkpoint ({error})") from None
    if not isinstance(saved, dict) or saved.get("format") not in READABLE_VERSIONS:
        version = saved.get("format") if isinstance(saved, dict) else None
        raise PtlabError(f"{path}: checkpoint format {version} is not {FORMAT_VERSION}")
    if not isinstance(command, dict):
        raise PtlabError(f"{path}: not a ptlab checkpoint (its command is not a table)")
    return saved, command, arrays


def load_checkpoint(path: str | Path, film: Film, identity: dict) -> None:
    """Fill ``film`` from the checkpoint at ``path``, which must match ``identity``."""
    saved, _, arrays = read_checkpoint(path)
    for key, value in identity.items():
        # Compared as text: checkpoints written before RenderOptions kept rr_depth as text.
        if key == "spp":
            continue
        # (An option newer than the checkpoint is unset there: None, or off.)
        same = str(saved[key]) == str(value) if key in saved else value is None or value is False
        if not same and key not in saved:
            raise PtlabError(
                f"{path}: the checkpoint was made without {key}, this render has {key} = {value!r}"
            )
        if not same:
            raise PtlabError(
                f"{path}: the checkpoint was made with {key} = {saved.get(key)!r}, this render has {value!r}"
            )
    if not _fits(arrays, film):
        raise PtlabError(f"{path}: the checkpoint's film does not fit this render")
    # The passes done must be the first passes of this render's schedule (a render may be
    # resumed with more spp than it was started with, never with other passes).
    done = int(arrays["passes_done"].max(initial=0))
    saved_passes = [int(n) for n in arrays["passes"]]
    if done > len(film.passes) or saved_passes[:done] != film.passes[:done]:
        raise PtlabError(
            f"{path}: the checkpoint's {done} passes (of {saved_passes[0]} spp) are "
            f"not the first passes of a {sum(film.passes)}-spp render: resume "
            f"with the --spp it was started with, {sum(saved_passes)}"
        )
    film.sums[:] = arrays["sums"]
    film.passes_done[:] = arrays["passes_done"]
    if "counts" in arrays:
        film.differences[:] = arrays["differences"]
        film.counts[:] = arrays["counts"]
        if arrays["plan"].size:
            film.plan = arrays["plan"].astype(np.int64)
            film.plan_done[:] = arrays["plan_done"]
            planned, finished = film.plan, film.plan_done
            left = [planned[t.y0 : t.y1, t.x0 : t.x1].sum() for t in film.plan_tiles if not finished[t.index]]
            film.plan_total = film.samples + int(sum(left))
        film.adaptive_passes = int(arrays["adaptive_passes"])
        estimate = float(arrays["estimate"])
        film.estimate = None if np.isnan(estimate) else estimate
    else:  # (format 3: every pixel of a tile has its passes' samples)
        spp_after = np.concatenate([[0], np.cumsum(film.passes, dtype=np.int64)])
        for tile, passes in zip(film.tiles, film.passes_done, strict=True):
            film.counts[tile.y0 : tile.y1, tile.x0 : tile.x1] = spp_after[passes]
    film.rays = int(arrays["rays"])
    film.query_seconds = float(arrays["query_seconds"])
    film.sampler_seconds = float(arrays["sampler_seconds"])
    film.nonfinite = int(arrays["nonfinite"])
    if film.features is not None and film.feature_differences is not None:
        film.features[:] = arrays["features"]
        film.feature_differences[:] = arrays["feature_differences"]


def _feature_arrays(film: Film) -> dict[str, np.ndarray]:
    """The film's feature images' sums, where it gathers them (``Film.features``)."""
    if film.features is None or film.feature_differences is None:
        return {}
    return {"features": film.features, "feature_differences": film.feature_differences}


def _fits(arrays: dict, film: Film) -> bool:
    """Whether a checkpoint's arrays have the shapes and kinds of number this film needs."""
    expected: dict[str, tuple[tuple[int, ...], type]] = {
        "sums": (film.sums.shape, np.floating),
        "passes_done": ((len(film.tiles),), np.integer),
        "rays": ((), np.integer),
        "query_seconds": ((), np.floating),
        "sampler_seconds": ((), np.floating),
    }
    if "counts" in arrays:
        expected |= {
            "differences": (film.sums.shape, np.floating),
            "counts": (film.counts.shape, np.integer),
            "plan_done": ((len(film.plan_tiles),), np.bool_),
            "adaptive_passes": ((), np.integer),
            "estimate": ((), np.floating),
        }
        plan = arrays.get("plan")
        if (
            plan is None
            or plan.shape not in ((0, 0), film.counts.shape)
            or not np.issubdtype(plan.dtype, np.integer)
        ):
            return False
        if np.any(arrays["counts"] < 0) or np.any(plan < 0):
            return False
    if film.features is not None:
        expected |= {
            "features": (film.features.shape, np.floating),
            "feature_differences": (film.features.shape, np.floating),
        }
    passes = arrays["passes"]
    return (
        all(
            name in arrays and arrays[name].shape == shape and np.issubdtype(arrays[name].dtype, kind)
            for name, (shape, kind) in expected.items()
        )
        and passes.ndim == 1
        # (a render to a target error has no fixed passes; any other has some)
        and (len(passes) > 0) == (len(film.passes) > 0)
        and np.issubdtype(passes.dtype, np.integer)
    )
