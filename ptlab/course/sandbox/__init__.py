"""Running a student's code where it cannot touch the verdict: student code only computes,
trusted code judges.

The graders (``ptlab grade``, ``ptlab exercise check``) never import a student's file.
A ``Submission`` imports it in a fresh interpreter of its own, in a sandbox whose view of
the file system holds Python, NumPy, the student's files and the chapter's kit (ptlab
without the chapter's answers), in namespaces of its own (mount, pid, network), as an
unprivileged user when the grader is root, with resource limits; the grader's checks run
in the grader's process and get ``submission.module``, a stand-in whose functions run in
the student's process::

    with ProcessGuard() as guard:
        with Submission("06_diffuse.py", guard, time_limit=30) as submission:
            material = submission.module.Lambertian((0.8, 0.5, 0.2))   # built there
            f = material.eval(wo, wi, n)                                  # computed there
            ...                                                           # judged here

What crosses back is plain data only (JSON and ``.npy`` arrays, ``plain_data``), never a
pickle; a reply that is late, missing or malformed ends the check (``SubmissionFailed``).
The ``ProcessGuard`` keeps every process the student's code starts, even one in a session
of its own, where it can be ended, and ends them all before the grader writes a result.
What is left open is written down in docs/grading-security.md.

Modules: ``submission`` (the grader's side), ``intake`` (the submission, read once, and its
private folders), ``rules`` (what the grader asks of it), ``kit`` (ptlab without the
chapter's answers), ``sandbox`` (the process's view and namespaces), ``child`` (the
student's process), ``student_user`` (as whom it runs), ``confinement`` (the authorship
hook), ``proxies`` (stand-ins), ``plain_data`` (the reply schema), ``channel`` (messages on
pipes), ``shown`` (what the student controls, as the graders print it), ``processes`` (the
subreaper), ``ownership`` (is a name the student's code or ptlab's?), ``readable`` and
``uses`` (can the grader read, in the files' text, the code that runs for a graded name?),
``code_ran`` (is the code that ran the code the grader compiled from those files?),
``copies`` (is a function a renamed copy of ptlab's?), with ``canonical`` (code put in one
form: ``canonical_names``, ``canonical_syntax``, ``canonical_blocks``, ``syntax_trees``)
and ``fingerprints`` (its tokens and grams).
"""

from __future__ import annotations

from ptlab.course.sandbox.child import GradeLoadError, Limits
from ptlab.course.sandbox.intake import RefusedSubmission, Taken, take_in
from ptlab.course.sandbox.processes import ProcessGuard, make_undumpable
from ptlab.course.sandbox.proxies import (
    ArgumentChanged,
    RemoteFunction,
    RemoteModule,
    RemoteObject,
    StudentError,
)
from ptlab.course.sandbox.rules import Arguments, Rules
from ptlab.course.sandbox.student_user import StudentUser, student_user
from ptlab.course.sandbox.submission import (
    IMPORT_TIME_LIMIT,
    ImportFailed,
    Submission,
    SubmissionFailed,
    UnreadableResultError,
    copied_answer,
    import_nothing_from_here,
    library_answer,
    submission_of,
)

__all__ = [
    "IMPORT_TIME_LIMIT",
    "ArgumentChanged",
    "Arguments",
    "GradeLoadError",
    "ImportFailed",
    "Limits",
    "ProcessGuard",
    "RefusedSubmission",
    "RemoteFunction",
    "RemoteModule",
    "RemoteObject",
    "Rules",
    "StudentError",
    "StudentUser",
    "Submission",
    "SubmissionFailed",
    "Taken",
    "UnreadableResultError",
    "copied_answer",
    "import_nothing_from_here",
    "library_answer",
    "make_undumpable",
    "student_user",
    "submission_of",
    "take_in",
]
