"""What a grader asks of a submission: which answers are ptlab's, what its kit leaves out,
what functions may do to their arguments.

A chapter of the exercises (``ptlab.course.chapter.Chapter.rules``) or ``ptlab grade``
makes ``Rules`` and gives them to ``ptlab.course.sandbox.Submission``:

* ``answers``: ptlab's own answers to what the student writes. They are not in the
  student's kit (``ptlab.course.sandbox.kit``), and a file holding a copy of them, names
  changed or not, is refused (``ptlab.course.sandbox.copies``).
* ``also_left_out``: what else in ptlab computes the same thing another way (a module, a
  class, a function); the kit leaves it out too. ``packages``: the installed packages the
  student's process may import (``ptlab.course.sandbox.sandbox``).
* ``arguments``: for each graded function, which of its arguments it writes (``film``: the
  grader takes those changes back) or may use as scratch space; any other argument is
  read-only, and changing it fails the check. Changes made anywhere else never reach the
  grader: it computes its references from arrays the student's code never had.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

from ptlab.course.sandbox.copies import Answers, answers_of
from ptlab.course.sandbox.sandbox import PACKAGES


@dataclass(frozen=True)
class Arguments:
    """What one graded function may do to its arguments (by parameter name).

    Attributes:
        parameters: its parameters in order (to name the positional arguments).
        writes: the arguments it fills in for its caller (changes are copied back).
        scratch: the arguments it may change for its own use (changes are dropped).
    """

    parameters: tuple[str, ...]
    writes: tuple[str, ...] = ()
    scratch: tuple[str, ...] = ()

    def name(self, position: int) -> str:
        """The parameter at ``position`` (0-based), or "argument N" past the known ones."""
        return self.parameters[position] if position < len(self.parameters) else f"argument {position + 1}"


@dataclass(frozen=True)
class Rules:
    """What a grader asks of a submission (see the module docstring).

    Attributes:
        answers: dotted names of ptlab's own answers (a function, or a class whose
            ``eval``, ``pdf``, ``sample`` and ``sample_weight`` are).
        solution: the chapter's answer file, whose functions count as answers too.
        arguments: {function name: Arguments}; a function without an entry has its
            changes to its arguments dropped.
        also_left_out: dotted names of the rest of ptlab that computes what the student
            writes another way (a module, a class or a function), left out of the kit.
        packages: the installed packages (import names) the student's code may import.
        library: the submission is ptlab's own answer file, graded as itself (tests and
            measurements of the graders use this; nothing a student runs can set it).
    """

    answers: tuple[str, ...] = ()
    solution: Path | None = None
    arguments: dict[str, Arguments] = field(default_factory=dict)
    also_left_out: tuple[str, ...] = ()
    packages: tuple[str, ...] = PACKAGES
    library: bool = False

    @cached_property
    def fingerprints(self) -> Answers:
        """The grams of every answer (``ptlab.course.sandbox.copies``); none for ptlab's own file."""
        if self.library:
            return Answers()
        return answers_of(self.answers, self.solution)

    @property
    def left_out(self) -> tuple[str, ...]:
        """What the student's kit leaves out: nothing for ptlab's own file."""
        return () if self.library else self.answers + self.also_left_out
