"""Running a student's code where it cannot touch the verdict: student code only computes,
trusted code judges.

The graders (``ptlab grade``, ``ptlab exercise check``) never import a student's file.
A ``Submission`` imports it in a process of its own, started from a fork server, with
resource limits and a session of its own; the grader's checks run in the grader's process
and get ``submission.module``, a stand-in whose functions run in the student's process::

    with ProcessGuard() as guard:
        with Submission("06_diffuse.py", guard, time_limit=30) as submission:
            material = submission.module.Lambertian((0.8, 0.5, 0.2))   # built there
            f = material.eval(wo, wi, n)                                  # computed there
            ...                                                           # judged here

What crosses back is plain data only (JSON and ``.npy`` arrays, ``plain_data``), never a
pickle; a reply that is late, missing or malformed ends the check (``SubmissionFailed``).
The ``ProcessGuard`` keeps every process the student's code starts, even one in a session
of its own, where it can be ended, and ends them all before the grader writes a result.
What this cannot stop without an operating-system boundary (another user, a container) is
written down in docs/grading-security.md.

Modules: ``submission`` (the grader's side), ``child`` (the student's process), ``proxies``
(stand-ins), ``plain_data`` (the reply schema), ``channel`` (messages on pipes),
``processes`` (the subreaper), ``ownership`` (is a name the student's code or ptlab's?).
"""

from __future__ import annotations

from ptlab.untrusted.child import GradeLoadError, Limits
from ptlab.untrusted.processes import ProcessGuard
from ptlab.untrusted.proxies import (
    RemoteFunction,
    RemoteModule,
    RemoteObject,
    StudentError,
    submission_of,
)
from ptlab.untrusted.submission import (
    ImportFailed,
    Submission,
    SubmissionFailed,
    UnreadableResultError,
    library_answer,
)

__all__ = ["GradeLoadError", "ImportFailed", "Limits", "ProcessGuard", "RemoteFunction",
           "RemoteModule", "RemoteObject", "StudentError", "Submission", "SubmissionFailed",
           "UnreadableResultError", "library_answer", "submission_of"]
