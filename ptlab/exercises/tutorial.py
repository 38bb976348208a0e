"""The command line every tutorial script (``docs/tutorials/NN_name.py``) shares.

Each tutorial renders its chapter's pictures at settings that take well under 30 seconds,
and takes ``--res``, ``--spp`` and ``--out`` so that a reader can change them and the tests
can run every tutorial small (``--res 32 --spp 1``).
"""

from __future__ import annotations

import argparse
from pathlib import Path


def tutorial_options(
    doc: str, res: int, spp: int, spp_help: str = "samples per pixel"
) -> tuple[argparse.Namespace, Path]:
    """Parse ``--res N --spp N --out DIR`` with these defaults; return them and the output
    folder (created). ``doc``'s first line is the ``--help`` description."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--res", type=int, default=res, help=f"image size (default {res})")
    parser.add_argument("--spp", type=int, default=spp, help=f"{spp_help} (default {spp})")
    parser.add_argument("--out", default=".", help="output folder (default here)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return args, out
