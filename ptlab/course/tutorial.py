"""The command line every tutorial script (``docs/tutorials/NN_name.py``) shares.

Each tutorial renders its chapter's pictures at settings that take well under 30 seconds,
and takes ``--res``, ``--spp`` and ``--out`` so that a reader can change them and the tests
can run every tutorial small (``--res 32 --spp 1``).

Each is a notebook too (jupytext's percent format: ``# %%`` starts a cell). In a notebook
there is no command line: the options are the defaults, or those in the environment
variable ``PTLAB_TUTORIAL_ARGS`` (``"--res 32 --spp 1"``), and the pictures are shown
below the last cell (``show_pictures``).
"""

from __future__ import annotations

import argparse
import os
import shlex
import time
from pathlib import Path

from ptlab.rendering.display import in_notebook

#: When ``tutorial_options`` ran: the pictures written since are this run's.
_started = time.time()


def tutorial_options(
    doc: str, res: int, spp: int, spp_help: str = "samples per pixel"
) -> tuple[argparse.Namespace, Path]:
    """Parse ``--res N --spp N --out DIR`` with these defaults; return them and the output
    folder (created). ``doc``'s first line is the ``--help`` description."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--res", type=int, default=res, help=f"image size (default {res})")
    parser.add_argument("--spp", type=int, default=spp, help=f"{spp_help} (default {spp})")
    parser.add_argument("--out", default=".", help="output folder (default here)")
    given = shlex.split(os.environ.get("PTLAB_TUTORIAL_ARGS", "")) if in_notebook() else None
    args = parser.parse_args(given)  # (None: the command line's)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    global _started
    _started = time.time()
    return args, out


def show_pictures(folder: Path) -> None:
    """In a notebook, show the PNG pictures this run wrote to ``folder``; a script has
    printed where they are, and does nothing here."""
    if not in_notebook():
        return
    from IPython.display import Image, display

    # (In the order the run wrote them, as the text tells of them: the right picture first.)
    for path in sorted(Path(folder).glob("*.png"), key=lambda p: (p.stat().st_mtime_ns, p.name)):
        if path.stat().st_mtime >= _started - 1:
            print(path.name)
            display(Image(filename=str(path)))
