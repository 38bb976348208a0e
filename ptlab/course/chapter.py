"""What a chapter of the exercises is: its graded checks, and the helpers checks use.

A chapter module (``ptlab.course.chapters.chNN_name``) defines ``CHAPTER = Chapter(...)``:
a list of ``ChapterCheck``s; the library's own answers to what the student writes, which the
student's kit leaves out with everything else that computes them (``ptlab.course.sandbox.kit``),
and whose copies earn nothing; and what each function may do to its arguments
(``Chapter.rules``). A check is a plain function of the student's module (a stand-in for
it, whose functions run in the student's own process: ``ptlab.course.sandbox``): it returns a
short note of what it measured, or raises ``CheckFailed`` with a message for the student.
``ptlab.course.grader`` runs the checks; this module only describes them.
"""

from __future__ import annotations

import ast
import secrets
import shlex
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ptlab.course.messages import aside, text
from ptlab.course.sandbox import Arguments, RemoteModule, Rules, copied_answer, library_answer
from ptlab.course.sandbox.sandbox import PACKAGES

if TYPE_CHECKING:
    from ptlab.scene import Scene

#: The exercises package: templates/ and solutions/ are beside this file.
HERE = Path(__file__).parent
#: Seconds of time limit up to which a check is quick (``ChapterCheck.quick``): the unit
#: checks; the renders take longer.
QUICK_CHECK = 30.0


#: The seed of the grading run under way (``grading_seed``), None outside one.
_GRADING_SEED: ContextVar[int | None] = ContextVar("grading_seed", default=None)


def new_grading_seed() -> int:
    """A fresh grading seed, from the operating system's randomness: nobody can know it
    before the grading starts, so no answer computed beforehand matches its inputs."""
    return secrets.randbits(63)


@contextmanager
def grading_seed(seed: int) -> Iterator[int]:
    """A ``with`` block in which the checks draw their inputs from ``seed``
    (``grading_rng``, ``grading_seed_for``)."""
    if not (isinstance(seed, int) and 0 <= seed < 2**63):
        raise ValueError(f"grading seed {seed!r}: must be an integer in [0, 2**63)")
    token = _GRADING_SEED.set(seed)
    try:
        yield seed
    finally:
        _GRADING_SEED.reset(token)


def active_grading_seed() -> int | None:
    """The seed of the grading under way (``grading_seed``), or None outside one."""
    return _GRADING_SEED.get()


def _current_grading_seed() -> int:
    seed = _GRADING_SEED.get()
    if seed is None:  # a check's inputs would be fixed, and so replayable
        raise RuntimeError("a check's inputs come from a grading seed: run it inside grading_seed(seed)")
    return seed


def grading_rng(stream: int) -> np.random.Generator:
    """The generator of a check's random inputs: stream ``stream`` (a number of its own per
    use within a chapter) of the grading run's seed. The grader computes the references
    from the same inputs, so a fresh seed makes every input, and every answer, new."""
    return np.random.default_rng([_current_grading_seed(), stream, 0])


def grading_seed_for(stream: int) -> int:
    """A render's seed (0 .. 2^32 - 1): stream ``stream`` of the grading run's seed."""
    sequence = np.random.SeedSequence([_current_grading_seed(), stream, 1])  # (not rng's)
    return int(sequence.generate_state(1)[0])


class CheckFailed(Exception):  # noqa: N818 (a verdict, not an error of the grader)
    """A check's verdict that the student's code is wrong; the message says how."""


@dataclass(frozen=True)
class ChapterCheck:
    """One graded check of a chapter.

    Attributes:
        name: what is checked, in a few words ("centre ray", "render").
        points: what it is worth.
        run: ``run(module) -> note``, ``module`` the stand-in for the student's module
            (``RemoteModule``); raises ``CheckFailed`` when the code is wrong.
        timeout: seconds it may take before it counts as hanging.
        requires: the names of earlier checks of the core behaviour this one builds on.
            A check of a secondary property ("unit directions", "parallel rays") that a
            trivial answer also has (every ray forward, every ray missing) scores only
            when they pass; until then it scores 0 and says so (``grader.gated``).
    """

    name: str
    points: int
    run: Callable[[RemoteModule], str]
    timeout: float = 60.0
    requires: tuple[str, ...] = ()

    @property
    def quick(self) -> bool:
        """Cheap enough to run even when it scores nothing: its message may still help."""
        return self.timeout <= QUICK_CHECK


@dataclass(frozen=True)
class ChapterRender:
    """What ``ptlab exercise render`` renders for a chapter (``ptlab.course.side_by_side``).

    Attributes:
        yours: ``yours(module, scene, options) -> (H, W, 3) image``: ``scene`` rendered in
            this process with the functions of ``module`` (the stand-in for the student's
            module) in place of the library's; ``options``: ``ptlab.render``'s keywords,
            ``progress`` among them.
        scene: the built-in scene rendered when the command names none.
        options: what both renders take beyond the command's options (an integrator, the
            backend that calls the student's pieces).
    """

    yours: Callable[[RemoteModule, Scene, dict], np.ndarray]
    scene: str = "cornell-box"
    options: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Chapter:
    """One chapter of the progression.

    Attributes:
        number: 1, 2, ...
        slug: the file-name part, e.g. ``"cameras"`` (files ``01_cameras.py``, ``01-cameras.md``).
        title: the chapter's title.
        functions: what the student writes (for ``ptlab exercise list`` and the docs).
        checks: the graded checks, in order.
        answers: the library's own answers to ``functions`` (dotted names of functions, or of
            classes whose ``eval``, ``pdf``, ``sample`` and ``sample_weight`` are).
        writes: {function: the arguments it fills in} (the film ``trace_paths`` adds to);
            every other argument of the exercise's functions is read-only.
        scratch: {function: the arguments it may change for its own use}.
        also_left_out: the rest of ptlab that computes what the student writes another way
            (modules, classes, functions): the chapter's kit leaves it out with ``answers``
            (``ptlab.course.sandbox.kit``).
        packages: the installed packages the student's code may import.
        render: how ``ptlab exercise render`` renders a scene with the chapter's functions;
            None for a chapter whose functions no render calls.
    """

    number: int
    slug: str
    title: str
    functions: tuple[str, ...]
    checks: tuple[ChapterCheck, ...]
    answers: tuple[str, ...] = ()
    writes: dict[str, tuple[str, ...]] = field(default_factory=dict)
    scratch: dict[str, tuple[str, ...]] = field(default_factory=dict)
    also_left_out: tuple[str, ...] = ()
    packages: tuple[str, ...] = PACKAGES
    render: ChapterRender | None = None

    def __post_init__(self) -> None:
        earlier: set[str] = set()
        for check in self.checks:
            unknown = set(check.requires) - earlier
            if unknown:
                raise ValueError(
                    f"chapter {self.number}: check {check.name!r} requires {sorted(unknown)}, "
                    f"which are not earlier checks of the chapter"
                )
            earlier.add(check.name)

    @property
    def stem(self) -> str:
        """``NN_slug``: the exercise file's name without ``.py``."""
        return f"{self.number:02d}_{self.slug}"

    @property
    def template(self) -> Path:
        return HERE / "templates" / f"{self.stem}.py"

    @property
    def solution(self) -> Path:
        return HERE / "solutions" / f"{self.stem}.py"

    @cached_property
    def rules(self) -> Rules:
        """What the grader asks of a student's file for this chapter (``ptlab.course.sandbox.rules``):
        the answers, and the arguments of every function of the exercise file, by the
        parameter names the exercise file gives them."""
        tree = ast.parse(self.template.read_bytes())
        arguments = {}
        for node in tree.body:
            if isinstance(node, ast.FunctionDef):
                names = tuple(a.arg for a in node.args.posonlyargs + node.args.args)
                arguments[node.name] = Arguments(
                    names, self.writes.get(node.name, ()), self.scratch.get(node.name, ())
                )
        return Rules(
            answers=self.answers,
            solution=self.solution,
            arguments=arguments,
            also_left_out=self.also_left_out,
            packages=self.packages,
        )

    @property
    def library_rules(self) -> Rules:
        """The rules for grading the library's own answer file (``solution``) as itself."""
        return replace(self.rules, library=True)

    @property
    def doc(self) -> str:
        """The chapter's page, relative to the ``docs`` folder (``ptlab.course.pages``)."""
        return f"{self.number:02d}-{self.slug.replace('_', '-')}.md"


def checked_array(value, name: str, shape: tuple, nan_hint: str = "") -> np.ndarray:
    """What a student's function ``name`` returned, as float64; the check fails if it does
    not have ``shape`` or holds NaN or infinite values (``nan_hint`` says what may cause them)."""
    result = np.asarray(value, dtype=np.float64)
    if result.shape != tuple(shape):
        raise CheckFailed(text("array.shape", name=name, expected=tuple(shape), shape=result.shape))
    if not np.isfinite(result).all():
        raise CheckFailed(text("array.not_finite", name=name, hint=aside(nan_hint)))
    return result


def student_file(module: RemoteModule) -> str:
    """The student's file as a command run where the check runs can name it: relative to the
    current folder when it lies inside it, else absolute; quoted for the shell if need be.

    ``module`` is the grader's stand-in for the student's module (``ptlab.course.sandbox``),
    which knows the file it was imported from."""
    from ptlab.course.sandbox import submission_of

    path = submission_of(module).path.resolve()
    here = Path.cwd().resolve()
    shown = path.relative_to(here) if path.is_relative_to(here) else path
    return shlex.quote(str(shown))


def require(module: RemoteModule, *names: str) -> list[Callable]:
    """The functions ``names`` of the student's module; a clear failure if one is missing,
    is ptlab's own answer under the student's name (``ptlab.course.sandbox.ownership``), or the
    file holds a copy of ptlab's answers with the names changed (``ptlab.course.sandbox.copies``)."""
    missing = [name for name in names if not callable(getattr(module, name, None))]
    if missing:
        raise CheckFailed(text("require.missing", names=", ".join(missing)))
    for name in names:
        origin = library_answer(module, name)
        if origin is not None:
            raise CheckFailed(text("require.library_answer", name=name, origin=origin))
    copied = copied_answer(module)
    if copied is not None:
        raise CheckFailed(text("require.copied", copied=copied))
    return [getattr(module, name) for name in names]
