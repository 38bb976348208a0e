"""Errors that are the user's to fix (a bad scene file, an absurd option).

The command line prints these as one line and exits with code 2, without a traceback;
anything else that goes wrong is a bug in ptlab and keeps its traceback.
"""


class PtlabError(Exception):
    """A problem with the user's input, described in one line."""


class SceneError(PtlabError):
    """A scene file or one of its meshes is missing or malformed.

    The message names the file, the key (where there is one) and the problem.
    """

    def __init__(self, file: object, problem: str, key: str | None = None):
        where = f"{file}" if key is None else f"{file}: {key}"
        super().__init__(f"{where}: {problem}")
