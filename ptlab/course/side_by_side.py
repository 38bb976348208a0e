"""``ptlab exercise render``: a scene rendered with a student's functions in place of the
library's, beside the library's own render of it, and a picture of their difference.

The student's file is imported as ``ptlab exercise check`` imports it (``ptlab.course.sandbox``:
a fresh interpreter in its sandbox, with the chapter's kit, as the student user when run as
root, sending back plain data only); the renders run in this process, which calls the student's
functions there, with one worker (the student's functions are stand-ins of this process,
which worker processes would not have). Each chapter says what it renders
(``Chapter.render``: its scene, its options, and the render's pieces made of the student's
functions: those of the chapter's render check). The library's render
comes first, before any of the student's code runs.

Both renders take the same seed: where the student's code draws the same random numbers as
the library's (the pieces of chapters 1-5, 8 and 10 draw none of their own), a right answer
gives the same picture, and the difference is black; elsewhere it shows noise too.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ptlab.course.chapter import Chapter, CheckFailed, grading_seed, new_grading_seed
from ptlab.course.messages import language, text
from ptlab.errors import PtlabError
from ptlab.rendering.pieces import Pieces

#: The width of a render that names no ``--res`` (its height: the scene's own aspect ratio).
DEFAULT_WIDTH = 256
#: Samples per pixel of a render that names no ``--spp``.
DEFAULT_SPP = 16
#: Seconds the student's process may take for its whole render, unless told otherwise.
TIME_LIMIT = 900.0
#: A pixel differs when its colour is off by more than this share of the library's mean.
DIFFERS = 0.01


@dataclass
class Pictures:
    """The two renders of one scene, (H, W, 3) linear RGB each, and how they were made;
    ``nonfinite``: the student's had NaN or infinite samples (left out of its image)."""

    yours: np.ndarray
    library: np.ndarray
    scene: str
    options: dict
    nonfinite: bool = False

    def difference(self) -> np.ndarray:
        """(H, W, 3) in [0, 1]: red where the student's pixel is brighter than the
        library's, blue where it is darker, black where they agree; full where the mean of
        the colours differs by the library's mean brightness or more."""
        scale = max(float(self.library.mean()), 1e-12)
        signed = np.clip((self.yours - self.library).mean(axis=2) / scale, -1, 1)
        picture = np.zeros((*signed.shape, 3))
        picture[..., 0] = np.maximum(signed, 0)
        picture[..., 2] = np.maximum(-signed, 0)
        return picture

    def differing(self) -> float:
        """The share of pixels whose colour differs by more than ``DIFFERS`` of the
        library's mean brightness (in any channel)."""
        threshold = DIFFERS * max(float(self.library.mean()), 1e-12)
        return float((np.abs(self.yours - self.library).max(axis=2) > threshold).mean())

    def summary(self) -> str:
        """One line: how much of the picture differs, and how bright the student's is."""
        ratio = float(self.yours.mean()) / max(float(self.library.mean()), 1e-12)
        summary = text("show.summary", share=self.differing(), ratio=ratio)
        return summary + (text("show.sentences") + text("show.nonfinite") if self.nonfinite else "")

    def write(self, folder: Path, stem: str) -> list[Path]:
        """Write ``stem-yours.png``, ``stem-library.png`` and ``stem-difference.png`` to
        ``folder``; return their paths."""
        from ptlab.image import write_image

        pictures = {"yours": self.yours, "library": self.library, "difference": self.difference()}
        return [write_image(folder / f"{stem}-{name}.png", image) for name, image in pictures.items()]


def render_with_pieces(scene, options: dict, pieces: Pieces | None = None) -> np.ndarray:
    """``ptlab.render(scene, **options)`` in this process (one worker), made of ``pieces``
    (the library's if None), on the NumPy backend if they include BVH pieces."""
    import ptlab
    from ptlab.course.renders import backend_for

    if pieces is not None:
        options = dict(options, backend=backend_for(pieces, options.get("backend", "auto")))
    return ptlab.render(scene, **dict(options, workers=1), pieces=pieces)


def render_with_materials(
    scene, options: dict, replaces: Callable, material_for: Callable, missing: str
) -> np.ndarray:
    """``scene`` rendered in this process (one worker) with every material ``m`` for which
    ``replaces(m)`` replaced by ``material_for(m)`` (``ptlab.course.renders.replace_materials``);
    ``CheckFailed`` with ``missing`` if the scene has none."""
    from ptlab.course.renders import replace_materials

    if not any(replaces(m) for m in scene.materials):
        raise CheckFailed(missing)
    replaced = replace_materials(scene, lambda m: material_for(m) if replaces(m) else None)
    return render_with_pieces(replaced, options)


def render_options(scene, chapter: Chapter, res: str | None, spp: int | None, seed: int) -> dict:
    """The options of both renders: the chapter's, and ``res`` (default ``DEFAULT_WIDTH``
    wide at the scene's aspect ratio), ``spp`` (default ``DEFAULT_SPP``) and ``seed``."""
    from ptlab.rendering.options import resolution
    from ptlab.rendering.settings import MAX_SPP, check_integer, parse_resolution

    if res is None:
        width, height = resolution(scene)
        size = (DEFAULT_WIDTH, max(1, round(DEFAULT_WIDTH * height / width)))
    else:
        size = parse_resolution(res)
    spp = DEFAULT_SPP if spp is None else check_integer("--spp", spp, 1, MAX_SPP)
    assert chapter.render is not None
    return dict(chapter.render.options, res=size, spp=spp, seed=seed)


def render_side_by_side(
    chapter: Chapter,
    path: str | Path,
    scene_name: str | None = None,
    res: str | None = None,
    spp: int | None = None,
    seed: int = 0,
    progress: bool = False,
    user: str | None = None,
    on_output: Callable[[str], None] | None = None,
    say: Callable[[str], None] | None = None,
    time_limit: float = TIME_LIMIT,
    lang: str | None = None,
) -> Pictures:
    """Render ``scene_name`` (default: the chapter's) with the library's code, then with the
    student's file ``path`` as the render's pieces, isolated as ``check`` runs it.

    Args:
        progress: show a progress bar of each render (``ptlab.render``'s).
        user: the user the student's code runs as (``--student-user``).
        on_output: called with each line the student's code prints.
        say: called with a line before each render.
        time_limit: seconds the student's process may take in all.

    Raises:
        PtlabError: the chapter has no render, no such file, scene or user, bad options.
        CheckFailed: the student's code failed (raised, took too long, returned nonsense):
            the message says how, in one line.
    """
    with language(lang):
        return _render_side_by_side(
            chapter, Path(path), scene_name, res, spp, seed, progress, user, on_output, say, time_limit
        )


def _render_side_by_side(
    chapter, path, scene_name, res, spp, seed, progress, user, on_output, say, time_limit
) -> Pictures:
    import ptlab
    from ptlab.course.grader import described
    from ptlab.course.sandbox import (
        ImportFailed,
        ProcessGuard,
        RefusedSubmission,
        StudentError,
        Submission,
        SubmissionFailed,
        import_nothing_from_here,
        make_undumpable,
        student_user,
        take_in,
    )

    if chapter.render is None:
        raise PtlabError(text("show.no_render", number=chapter.number))
    if not path.is_file():
        raise PtlabError(text("show.no_file", path=path))
    student_user(user)  # (an unknown user: before anything is rendered)
    scene = ptlab.load_scene(scene_name or chapter.render.scene)
    options = render_options(scene, chapter, res, spp, seed)
    say = say or (lambda line: None)
    say(
        text(
            "show.library",
            scene=scene.name,
            width=options["res"][0],
            height=options["res"][1],
            spp=options["spp"],
        )
    )
    library = ptlab.render(scene, progress=progress, **options)
    make_undumpable()
    import_nothing_from_here()
    try:
        taken = take_in(path, with_folder=True)
    except RefusedSubmission as refused:
        raise CheckFailed(str(refused)) from None
    say(text("show.yours"))
    try:
        with (
            ProcessGuard() as guard,
            grading_seed(new_grading_seed()),
            Submission(
                taken, guard, time_limit=time_limit, on_output=on_output, rules=chapter.rules, user=user
            ) as running,
            warnings.catch_warnings(record=True) as caught,  # (said in the summary instead)
        ):
            warnings.simplefilter("always", RuntimeWarning)
            yours = chapter.render.yours(running.module, scene, dict(options, progress=progress))
    except StudentError as error:
        raise CheckFailed(described(error)) from None
    except (ImportFailed, SubmissionFailed) as failure:
        message = str(failure)
        if isinstance(failure, SubmissionFailed) and failure.kind == "timeout":
            message = text("grader.timeout", seconds=time_limit, during=failure.during)
        raise CheckFailed(message) from None
    yours = np.asarray(yours, dtype=np.float64)
    if yours.shape != library.shape:
        raise CheckFailed(text("show.shape", shape=yours.shape, expected=library.shape))
    nonfinite = any(issubclass(w.category, RuntimeWarning) and "NaN" in str(w.message) for w in caught)
    return Pictures(np.nan_to_num(yours), library.astype(np.float64), scene.name, options, nonfinite)
