"""Every tutorial script of docs/tutorials runs, at reduced settings, and writes its pictures,
as a script and as a notebook that reads as prose and code; the command line they share
(``ptlab.course.tutorial``) takes those settings; the README's notebook command writes the
notebook where the user is."""

from __future__ import annotations

import itertools
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ptlab.image import read_image

ROOT = Path(__file__).parents[2]
TUTORIALS = sorted((ROOT / "docs" / "tutorials").glob("[0-9][0-9]_*.py"))


def test_there_is_a_tutorial_per_chapter():
    from ptlab.course import all_chapters

    assert [p.stem for p in TUTORIALS] == [c.stem for c in all_chapters()]


def test_every_tutorial_takes_res_spp_and_out_and_makes_the_folder(tmp_path, monkeypatch):
    from ptlab.course.tutorial import tutorial_options

    out = tmp_path / "pictures" / "chapter 7"
    monkeypatch.setattr(sys, "argv", ["07_path_tracing.py", "--res", "32", "--out", str(out)])
    args, folder = tutorial_options("Chapter 7's pictures.\n\nMore.", res=256, spp=64)
    assert (args.res, args.spp) == (32, 64)
    assert folder == out
    assert out.is_dir()


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("script", TUTORIALS, ids=lambda p: p.stem)
def test_tutorial_runs_at_reduced_settings(script, tmp_path):
    run = subprocess.run(
        [sys.executable, str(script), "--res", "32", "--spp", "1", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert list(tmp_path.glob("*.png")), f"{script.name} wrote no picture"
    # A picture of the chapter's typical mistake shows it: it differs from the right one (or,
    # where it is itself a difference, as chapter 8's, it is not black).
    for wrong in tmp_path.glob("*-wrong.png"):
        right = wrong.with_name(wrong.name.replace("-wrong", ""))
        shown = read_image(wrong)[0]
        changed = np.any(shown != (read_image(right)[0] if right.exists() else 0), axis=2).mean()
        assert changed > 0.01, f"{wrong.name} shows no mistake: {changed:.1%} of its pixels differ"


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("script", TUTORIALS, ids=lambda p: p.stem)
def test_tutorial_runs_as_a_notebook_in_a_fresh_kernel(script, tmp_path, monkeypatch):
    """Each tutorial script is a notebook too (jupytext's percent format), and reads as one:
    a title, then prose between small code cells, each step's results below its own cell.
    Executed in a fresh kernel (nbclient) at small settings, it writes its pictures and
    shows them."""
    import jupytext
    from nbclient import NotebookClient

    notebook = jupytext.read(script)
    kinds = "".join(cell.cell_type[0] for cell in notebook.cells)  # (m: markdown, c: code)
    assert notebook.cells[0].cell_type == "markdown", "no title and introduction"
    assert notebook.cells[0].source.startswith("# Chapter "), notebook.cells[0].source[:80]
    assert kinds.count("m") >= 4, f"{script.name} is code with little prose: {kinds}"
    longest_code_run = max(len(list(run)) for kind, run in itertools.groupby(kinds) if kind == "c")
    assert longest_code_run <= 2, f"{script.name} has {longest_code_run} code cells without prose between"
    monkeypatch.setenv("PTLAB_TUTORIAL_ARGS", f"--res 32 --spp 1 --out '{tmp_path}'")
    NotebookClient(
        notebook, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    ).execute()
    written = sorted(tmp_path.glob("*.png"))
    assert written, f"{script.name} wrote no picture"
    shown = [
        output
        for cell in notebook.cells
        for output in cell.get("outputs", [])
        if "image/png" in output.get("data", {})
    ]
    assert len(shown) == len(written), f"{script.name} showed {len(shown)} of its {len(written)} pictures"
    printing = [
        cell for cell in notebook.cells if any("text" in output for output in cell.get("outputs", []))
    ]
    assert len(printing) >= 2, f"{script.name} prints everything in one cell, away from the prose"


@pytest.mark.subprocess
def test_the_readmes_notebook_command_writes_the_notebook_where_the_user_is(tmp_path):
    """The README's `jupytext --to notebook SCRIPT -o NAME.ipynb`, run with the real jupytext
    from a folder other than the script's, writes there the notebook that the README's
    `jupyter notebook` line opens, with the tutorial's prose, and nothing beside the script."""
    import nbformat

    lines = [line.split("#")[0].strip() for line in (ROOT / "README.md").read_text().splitlines()]
    convert = shlex.split(next(line for line in lines if line.startswith("jupytext ")))
    opened = shlex.split(next(line for line in lines if line.startswith("jupyter notebook ")))[2]
    shown = next(word for word in convert if word.endswith(".py"))  # (relative to the checkout)
    script = tmp_path / "checkout" / shown  # (a copy: a wrong command writes nothing in ours)
    script.parent.mkdir(parents=True)
    script.write_bytes((ROOT / shown).read_bytes())
    here = tmp_path / "here"
    here.mkdir()
    run = subprocess.run(
        [sys.executable, "-m", *[str(script) if word == shown else word for word in convert]],
        cwd=here,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert (here / opened).is_file(), f"{opened} is not where the user is: {list(here.iterdir())}"
    assert list(script.parent.iterdir()) == [script]
    cells = nbformat.read(here / opened, as_version=4).cells
    assert [cell.cell_type for cell in cells[:2]] == ["markdown", "code"]


#: The tutorial that is no chapter's: what a denoiser buys and what it costs (docs/denoising.md).
DENOISING = ROOT / "docs" / "tutorials" / "denoising.py"
DENOISING_PICTURES = {
    f"denoising-{name}.png" for name in ("cornell-box", "error-time", "veach-mis", "games101-hw5")
}


def _check_denoising_run(printed: str, folder: Path) -> None:
    """The denoising tutorial wrote its pictures, denoised the Cornell box at 1 spp into a far
    cleaner image, and printed a row of its estimates' table per scene."""
    assert {path.name for path in folder.glob("*.png")} == DENOISING_PICTURES
    # The ladder's row: spp, plain seconds and relMSE, denoised seconds, OIDN's, relMSE, ...
    rung = re.search(r"^ +1 +[\d.]+ +([\d.]+) +[\d.]+ +[\d.]+ +([\d.]+) ", printed, re.MULTILINE)
    assert rung, printed[-3000:]
    noisy, denoised = map(float, rung.groups())
    assert denoised < noisy / 3, f"denoising took the relMSE from {noisy} to only {denoised}"
    estimates = printed.partition("beside the true error:")[2]
    says = r"(refused: .+|[\d.]+( \([\d.]+x the true error\))?)"
    for scene in ("cornell-box", "veach-mis", "games101-hw5"):
        row = rf"^ +{scene} +\d+ +-?[\d.]+ +{says}$"
        assert re.search(row, estimates, re.MULTILINE), f"no row for {scene}:\n{estimates}"


@pytest.mark.slow
@pytest.mark.subprocess
def test_denoising_tutorial_runs_at_reduced_settings(tmp_path):
    run = subprocess.run(
        [sys.executable, str(DENOISING), "--res", "32", "--spp", "1", "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
        env=dict(os.environ, PTLAB_CACHE=str(tmp_path / "references")),  # (rendered, not the user's)
    )
    assert run.returncode == 0, run.stderr[-2000:]
    _check_denoising_run(run.stdout, tmp_path / "out")


@pytest.mark.slow
@pytest.mark.subprocess
def test_denoising_tutorial_runs_as_a_notebook_in_a_fresh_kernel(tmp_path, monkeypatch):
    import jupytext
    from nbclient import NotebookClient

    notebook = jupytext.read(DENOISING)
    assert sum(cell.cell_type == "markdown" for cell in notebook.cells) >= 5  # (a tutorial: prose and code)
    out = tmp_path / "out"
    monkeypatch.setenv("PTLAB_TUTORIAL_ARGS", f"--res 32 --spp 1 --out '{out}'")
    monkeypatch.setenv("PTLAB_CACHE", str(tmp_path / "references"))
    NotebookClient(
        notebook, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    ).execute()
    outputs = [output for cell in notebook.cells for output in cell.get("outputs", [])]
    assert not [output for output in outputs if output.get("output_type") == "error"]
    printed = "".join(output.get("text", "") for output in outputs if output.get("name") == "stdout")
    _check_denoising_run(printed, out)
    shown = [output for output in outputs if "image/png" in output.get("data", {})]
    assert len(shown) == len(DENOISING_PICTURES), (
        f"showed {len(shown)} of its {len(DENOISING_PICTURES)} pictures"
    )


def test_a_notebook_shows_the_pictures_in_the_order_they_were_made(tmp_path, monkeypatch, capsys):
    # The text tells of the right picture first, then the mistakes: alphabetical order would
    # put "path-tracing.png" after "no-cosine.png".
    import os

    from ptlab.course import tutorial

    monkeypatch.setattr(tutorial, "in_notebook", lambda: True)
    monkeypatch.setattr(tutorial, "_started", 0.0)
    for k, name in enumerate(("path-tracing.png", "no-cosine.png", "a-mistake.png")):
        path = tmp_path / name
        path.write_bytes(b"\x89PNG\r\n\x1a\n")
        os.utime(path, ns=(10**18 + k * 10**9, 10**18 + k * 10**9))
    tutorial.show_pictures(tmp_path)
    named = [line for line in capsys.readouterr().out.splitlines() if line.endswith(".png")]
    assert named == ["path-tracing.png", "no-cosine.png", "a-mistake.png"]
