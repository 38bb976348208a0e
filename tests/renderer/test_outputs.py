"""Output paths that cannot be written (``ptlab inspect --json``, ``--plot``): one line and
exit 2 before the work (the render, the inspection), nothing written; and ``ptlab``'s
top-level names.

Every bad path here fails for root too (root ignores permissions): a folder that does not
exist, a regular file where a folder should be, a folder where the file should be, and /proc
(where nobody may create a file).
"""

from __future__ import annotations

from pathlib import Path

import pytest

import ptlab
from ptlab.cli import main
from ptlab.errors import PtlabError


def bad_outputs(tmp_path: Path, suffix: str) -> dict[str, tuple[Path, str]]:
    """{case: (path, what the one line says)}, each path one that cannot be written."""
    (tmp_path / "a-file").write_text("not a folder\n")
    (tmp_path / f"a-folder{suffix}").mkdir()
    return {
        "no such folder": (tmp_path / "nowhere" / f"out{suffix}", "does not exist"),
        "under a file": (tmp_path / "a-file" / f"out{suffix}", "is not a folder"),
        "a folder": (tmp_path / f"a-folder{suffix}", "is a folder"),
        "in /proc": (Path(f"/proc/ptlab-out{suffix}"), "cannot write in /proc"),
    }


def written_in(tmp_path: Path) -> set[str]:
    """Every path below ``tmp_path`` (an output, or a temporary file left behind)."""
    return {str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*")}


@pytest.mark.parametrize("case", ["no such folder", "under a file", "a folder", "in /proc"])
@pytest.mark.parametrize(("option", "suffix"), [("--json", ".json"), ("--plot", ".png")])
def test_inspect_refuses_an_output_it_cannot_write_before_inspecting(tmp_path, capsys, case, option, suffix):
    path, said = bad_outputs(tmp_path, suffix)[case]
    before = written_in(tmp_path)
    code = main(["inspect", "cornell-box", "--res", "16", "--spp", "1", "--pixel", "8,8", option, str(path)])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""  # (the inspection's table comes first: it did not run)
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("ptlab: error: "), lines
    assert said in lines[0], lines
    assert str(path) in lines[0]
    assert written_in(tmp_path) == before
    assert not Path(f"/proc/ptlab-out{suffix}").exists()


def test_a_plot_drawn_by_the_api_refuses_its_path_before_drawing(tmp_path):
    found = ptlab.inspect_pixel("cornell-box", (8, 8), res=16, spp=1, workers=1)
    with pytest.raises(PtlabError, match="does not exist"):
        found.plot(tmp_path / "nowhere" / "paths.png")


def test_dir_shows_the_public_api_only():
    names = dir(ptlab)
    assert names == sorted(ptlab.__all__)
    for machinery in ("TYPE_CHECKING", "annotations", "_HOMES", "__getattr__"):
        assert machinery not in names
    for name in names:  # (each one a name the package gives)
        assert getattr(ptlab, name) is not None


def test_a_device_is_not_an_output_file(tmp_path):
    # As root, a rename onto /dev/null would replace the device with a file: refused first.
    from ptlab.atomic import check_writable_file
    from ptlab.errors import PtlabError

    with pytest.raises(PtlabError, match="not a regular file"):
        check_writable_file("/dev/null")
    (tmp_path / "plain").write_text("x")
    with pytest.raises(PtlabError, match="is not a folder"):
        check_writable_file(tmp_path / "plain" / "out.png")
    assert check_writable_file(tmp_path / "out.png") == tmp_path / "out.png"
