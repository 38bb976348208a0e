"""``ptlab grade FILE.py:Name``: load a student's material, check it, print the verdict.

    ptlab grade my_material.py:Microfacet --args '{"roughness": 0.3}' --plots plots/

``Name`` is a class (constructed with the ``--args`` JSON object as keyword arguments) or a
ready-made material object in the file. The exit code is 0 when every check passes, 1 when
one fails, 2 when the file or the name cannot be loaded (one line on stderr, no traceback).

``ptlab.cli`` wires it in with ``add_grade_arguments(subparser)`` and the handler
``run_grade(args)``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ptlab.grading.untrusted import GradeLoadError, import_file

REQUIRED_METHODS = ("eval", "pdf", "sample", "sample_weight")


def add_grade_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add ``grade``'s arguments to ``parser`` (the ``ptlab grade`` subparser)."""
    parser.add_argument("target", metavar="FILE.py:Name",
                        help="the Python file and the material class (or object) in it")
    parser.add_argument("--args", default="{}", metavar="JSON",
                        help="keyword arguments for the class, as a JSON object (default {})")
    parser.add_argument("--plots", metavar="DIR",
                        help="write PNG pictures of a failed chi-square test into DIR")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the checks (default 0)")
    parser.add_argument("--samples", type=int, default=1_000_000,
                        help="directions sampled per wo (default 10^6)")
    return parser


def run_grade(args: argparse.Namespace) -> int:
    """Grade the material ``args`` name; print the report. Raises GradeLoadError (exit 2)."""
    from ptlab.grading import check_material, write_plots

    if args.samples < 1000:
        raise GradeLoadError("--samples must be at least 1000")
    material = load_material(args.target, args.args)
    report = check_material(material, seed=args.seed, samples=args.samples)
    print(report)
    if args.plots and not report.passed:
        written = write_plots(report, args.plots)
        if written:
            print(f"wrote {len(written)} chi-square plots to {Path(args.plots).resolve()}")
    return 0 if report.passed else 1


def load_material(target: str, arguments: str = "{}"):
    """The material ``FILE.py:Name`` names, built with the JSON ``arguments`` if a class."""
    file, separator, name = target.rpartition(":")
    if not separator or not file or not name:
        raise GradeLoadError(f"{target!r}: expected FILE.py:Name")
    path = Path(file)
    if not path.is_file():
        raise GradeLoadError(f"{file}: no such file")
    try:
        keywords = json.loads(arguments)
    except json.JSONDecodeError as error:
        raise GradeLoadError(f"--args is not valid JSON: {error}") from None
    if not isinstance(keywords, dict):
        raise GradeLoadError("--args must be a JSON object, e.g. '{\"roughness\": 0.3}'")
    module = import_file(path)
    if not hasattr(module, name):
        raise GradeLoadError(f"{file}: no class or object named {name!r}")
    found = getattr(module, name)
    if isinstance(found, type):
        try:
            found = found(**keywords)
        except Exception as error:  # the student's constructor: report it, do not crash
            raise GradeLoadError(f"{name}(**{keywords}) raised {type(error).__name__}: {error}") from None
    elif keywords:
        raise GradeLoadError(f"{name} is not a class, so --args cannot be applied")
    missing = [m for m in REQUIRED_METHODS if not callable(getattr(found, m, None))]
    if missing:
        raise GradeLoadError(f"{name} is not a material: it has no {', '.join(missing)} "
                             "(subclass ptlab.materials.Material)")
    return found


