"""What a notebook, a script and a log see of a render: one-line reprs, the image as a PNG,
``ptlab.show``, and progress as lines where there is no terminal."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import ptlab
from ptlab.image import encode_srgb8, read_image
from ptlab.rendering import render_result
from ptlab.rendering.display import png_bytes

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def small():
    return render_result("cornell-box", res=(24, 16), spp=2, workers=1)


def test_a_result_and_a_scene_show_themselves_in_one_line(small, cornell):
    assert repr(small) == f"RenderResult('cornell-box', 24x16, 2 spp, complete, {small.seconds:.2f} s)"
    assert repr(cornell) == "Scene('cornell-box', 32 triangles, 4 materials, 2 emitting triangles)"
    assert "\n" not in repr(ptlab.load_scene("games101-hw5"))


def test_a_result_shows_in_jupyter_as_its_srgb_png(small, tmp_path):
    data = small._repr_png_()
    assert data.startswith(PNG_SIGNATURE)
    (tmp_path / "shown.png").write_bytes(data)
    shown, _ = read_image(tmp_path / "shown.png")
    assert np.array_equal(np.round(shown * 255).astype(np.uint8), encode_srgb8(small.image))


def test_exposure_brightens_what_is_shown(small, tmp_path):
    (tmp_path / "bright.png").write_bytes(png_bytes(small.image, exposure=2))
    bright, _ = read_image(tmp_path / "bright.png")
    assert np.array_equal(np.round(bright * 255).astype(np.uint8), encode_srgb8(small.image * 4))


def test_show_without_a_display_writes_a_png_and_says_where(small, tmp_path, capsys):
    import matplotlib

    matplotlib.use("Agg")
    path = ptlab.show(small, out=tmp_path / "shown.png")
    assert path == tmp_path / "shown.png"
    assert f"wrote {path.resolve()}" in capsys.readouterr().out
    shown, _ = read_image(path)
    assert shown.shape == (16, 24, 3)


def test_show_in_a_notebook_displays_the_image(small, monkeypatch, capsys):
    # In a kernel, IPython's display shows the image; outside one (here) it prints its repr.
    monkeypatch.setattr("ptlab.rendering.display.in_notebook", lambda: True)
    assert ptlab.show(small) is None
    assert "IPython.core.display.Image object" in capsys.readouterr().out


def test_a_render_stopped_before_any_pass_warns():
    with pytest.warns(RuntimeWarning, match="stopped before any tile had a pass"):
        result = render_result("cornell-box", res=8, spp=1, workers=1, stop=lambda: True)
    assert result.spp == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        render_result("cornell-box", res=8, spp=1, workers=1)  # (a finished one does not)


@pytest.mark.subprocess
def test_progress_is_a_line_per_pass_where_stderr_is_not_a_terminal(tmp_path):
    command = [sys.executable, "-m", "ptlab", "render", "cornell-box", "--res", "16", "--spp", "48"]
    result = subprocess.run(
        [*command, "--workers", "1", "--out", str(tmp_path / "box.png")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stderr.splitlines()
    assert [line.split(":")[0] for line in lines] == ["pass 1/3", "pass 2/3", "pass 3/3"], lines
    assert lines[-1].startswith("pass 3/3: 100% of 0.01 M samples")
    quiet = subprocess.run(
        [*command, "--quiet", "--out", str(tmp_path / "q.png")], capture_output=True, text=True
    )
    assert quiet.stderr == ""


@pytest.mark.subprocess
def test_a_terminal_that_reports_no_columns_still_gets_a_bar(tmp_path):
    """Some ptys report 0 columns; tqdm then drew no bar at all. The bar takes 80 there."""
    import fcntl
    import os
    import pty
    import struct
    import termios

    leader, follower = pty.openpty()
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 0, 0, 0))  # 0 columns
    command = [sys.executable, "-m", "ptlab", "render", "cornell-box", "--res", "16", "--spp", "32"]
    env = {key: value for key, value in os.environ.items() if key not in ("COLUMNS", "LINES")}
    process = subprocess.Popen(
        [*command, "--workers", "1", "--out", str(tmp_path / "box.png")],
        stdin=follower,
        stdout=subprocess.DEVNULL,
        stderr=follower,
        env=env,
    )
    os.close(follower)
    output = b""
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:  # (the pty closed: the process ended)
            break
        if not chunk:
            break
        output += chunk
    assert process.wait(timeout=120) == 0
    os.close(leader)
    assert b"pass 2/2" in output
    # A whole meter, to its closing bracket: with no width tqdm cut it, and drew a bar of one
    # character.
    assert b"sample/s]" in output
    assert "█████".encode() in output


@pytest.mark.slow  # (a kernel starts: about 4 s)
@pytest.mark.subprocess
def test_progress_in_a_notebook_shows_the_image_refreshed_after_each_pass(tmp_path):
    """One picture below the cell, updated in place: after the last pass it is the render."""
    import base64

    import nbformat
    from nbclient import NotebookClient

    code = (
        "import numpy as np, ptlab\n"
        "image = ptlab.render('cornell-box', spp=3, res=16, workers=1, spp_per_pass=1, progress=True)\n"
        "np.save('image.npy', image)"
    )
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)])
    NotebookClient(
        notebook, timeout=120, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    ).execute()
    shown = [output for output in notebook.cells[0].outputs if "image/png" in output.get("data", {})]
    assert len(shown) == 1, notebook.cells[0].outputs
    (tmp_path / "shown.png").write_bytes(base64.b64decode(shown[0]["data"]["image/png"]))
    shown_bytes = np.round(read_image(tmp_path / "shown.png")[0] * 255)  # (a PNG reads back as its codes)
    assert np.array_equal(shown_bytes, encode_srgb8(np.load(tmp_path / "image.npy")))


def test_a_kernels_shell_of_a_subclass_counts_as_a_notebook(monkeypatch):
    # Colab's shell subclasses ipykernel's ZMQInteractiveShell: a check of the class's own
    # name would take Colab for a plain Python and parse the kernel's arguments as ours.
    import sys
    import types

    from ptlab.rendering.display import in_notebook

    class ZMQInteractiveShell:
        pass

    class Shell(ZMQInteractiveShell):  # (as google.colab._shell.Shell)
        pass

    for shell, expected in ((Shell(), True), (ZMQInteractiveShell(), True), (object(), False), (None, False)):
        fake = types.SimpleNamespace(get_ipython=lambda shell=shell: shell)
        monkeypatch.setitem(sys.modules, "IPython", fake)
        assert in_notebook() is expected
