"""The ``ptlab`` command: renders, writes images with metadata, and fails cleanly."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from ptlab import cli
from ptlab.cli import main
from ptlab.image import encode_srgb8, read_image, write_image
from ptlab.materials import Diffuse


def test_render_writes_png_in_the_current_folder_and_says_where(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["render", "cornell-box", "--spp", "1", "--res", "16"]) == 0
    out = capsys.readouterr().out
    assert (tmp_path / "cornell-box.png").is_file()
    assert str(tmp_path / "cornell-box.png") in out
    assert "16x16" in out
    assert "1 spp" in out
    assert "samples/s" in out


def test_render_says_how_many_samples_were_nan_and_writes_the_count(tmp_path, monkeypatch, capsys):
    # A Lambertian whose f_r is NaN near grazing angles: those samples are left out, counted
    # in the image's header and said after the render, even with --quiet.
    original = Diffuse.eval

    def broken(self, wo, wi, n):
        f = np.array(original(self, wo, wi, n))
        f[(wi * n).sum(axis=1) < 0.2] = np.nan
        return f

    monkeypatch.setattr(Diffuse, "eval", broken)
    out = tmp_path / "box.exr"
    args = ["render", "cornell-box", "--spp", "2", "--res", "16", "--workers", "1", "--out", str(out)]
    assert main([*args, "--quiet"]) == 0
    message = (
        r"ptlab: (\d+) samples were NaN or infinite and were left out of the image; "
        r"the first at pixel \((\d+), (\d+)\), depth (\d+)\n"
    )
    said = re.fullmatch(message, capsys.readouterr().err)
    assert said
    assert int(said[1]) > 0
    assert 0 <= int(said[2]) < 16
    assert 0 <= int(said[3]) < 16
    assert read_image(out)[1]["nonfinite"] == int(said[1])


def test_render_exr_is_linear_float_with_metadata(tmp_path):
    out = tmp_path / "box.exr"
    assert (
        main(
            [
                "render",
                "cornell-box",
                "--spp",
                "2",
                "--res",
                "24x16",
                "--seed",
                "7",
                "--out",
                str(out),
                "--quiet",
            ]
        )
        == 0
    )
    image, metadata = read_image(out)
    assert image.shape == (16, 24, 3)
    assert image.max() > 1.0  # linear: the light is far above 1
    assert metadata["spp"] == 2
    assert metadata["seed"] == 7
    assert metadata["scene"] == "cornell-box"
    assert "seconds" in metadata
    assert "version" in metadata


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        (["render", "cornell-box", "--spp", "0"], "spp"),
        (["render", "cornell-box", "--res", "-5"], "resolution"),
        (["render", "cornell-box", "--rr", "2"], "roulette"),
        (["render", "cornell-box", "--rr", "sometimes"], "roulette"),
        (["render", "cornell-box", "--integrator", "whitted", "--strategy", "mis"], "whitted"),
        (["render", "no-such-scene"], "no-such-scene"),
        (["render", "cornell-box", "--out", "image.bmp"], "format"),
        (["render", "cornell-box", "--backend", "optix"], "backend"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_no_output(tmp_path, monkeypatch, capsys, args, problem):
    monkeypatch.chdir(tmp_path)
    code = exit_code(args)
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1, err
    assert problem in err, err
    assert "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []


def exit_code(args: list[str]) -> int:
    """main()'s exit code, whether it returns it or argparse exits with it."""
    try:
        return main(args)
    except SystemExit as exit:
        return exit.code


@pytest.mark.subprocess
def test_installed_command_reports_scene_errors_without_traceback(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text("[camera\n")
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    result = subprocess.run(
        [sys.executable, "-m", "ptlab.cli", "render", str(scene), "--out", str(tmp_path / "x.png")],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
    )
    assert result.returncode == 2
    assert "malformed TOML" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "x.png").exists()


@pytest.mark.subprocess
def test_a_reader_that_stops_early_is_not_an_error(tmp_path):
    # 'ptlab exercise list | head -1': the pipe closes before ptlab writes.
    child = subprocess.Popen(
        [sys.executable, "-m", "ptlab.cli", "exercise", "list"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=tmp_path,
    )
    child.stdout.close()
    errors = child.stderr.read().decode()
    assert child.wait(timeout=60) == 0
    assert errors == ""


@pytest.mark.subprocess
def test_listing_and_help_import_none_of_the_heavy_libraries():
    # Start-up time: what 'ptlab scenes' and '--help' do must not wait for the grading
    # harness, Embree, SciPy, trimesh, colour-science, matplotlib or OpenImageIO.
    heavy = (
        "scipy",
        "matplotlib",
        "trimesh",
        "colour",
        "embreex",
        "OpenImageIO",
        "ptlab.grading",
        "ptlab.course.sandbox",
        "ptlab.course",
    )
    code = (
        "import sys, contextlib, io\n"
        "from ptlab.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['scenes'])\n"
        "    try:\n"
        "        main(['render', '--help'])\n"
        "    except SystemExit:\n"
        "        pass\n"
        f"print([m for m in {heavy!r} if m in sys.modules])\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"


@pytest.mark.subprocess
def test_the_command_imports_no_numpy_before_it_can_start_the_workers_server():
    # ``ptlab render`` starts the workers' fork server first, so that its imports run
    # alongside the command's; a heavy import at the top of ptlab, ptlab.rendering or
    # ptlab.cli would put them back in a row.
    code = "import sys\nimport ptlab.cli, ptlab.rendering.executors\nprint('numpy' in sys.modules)\n"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"


@pytest.mark.parametrize(
    ("args", "starts"),
    [
        (["render", "cornell-box", "--workers", "2"], True),
        (["render", "cornell-box", "--res", "784", "--workers", "2"], True),
        (["render", "cornell-box", "--res", "64", "--spp", "32", "--workers", "2"], True),  # 2 passes
        (["render", "cornell-box", "--workers", "1"], False),
        (["render", "cornell-box", "--res", "16", "--spp", "1", "--workers", "2"], False),  # one job
        (["render", "cornell-box", "--res", "100x128", "--workers", "2"], False),
        (["render", "cornell-box", "--workers", "2", "--scheduler", "tcp://host:8786"], False),
        (["render", "--help"], False),
        (["render", "cornell-box", "--workers", "two"], False),
        (["render", "cornell-box", "--spp", ""], False),
        (["render", "cornell-box", "--res"], False),
    ],
)
def test_render_starts_the_workers_server_early_only_when_it_will_use_it(monkeypatch, capsys, args, starts):
    import ptlab.rendering.executors as executors

    started = []
    monkeypatch.setattr(executors, "start_worker_server", lambda: started.append(True))
    cli._start_workers_early(args)
    assert bool(started) == starts
    assert capsys.readouterr() == ("", "")  # a bad option is the real parser's to report


def test_help_describes_every_render_option(capsys):
    with pytest.raises(SystemExit):
        main(["render", "--help"])
    text = capsys.readouterr().out
    for option in (
        "--spp",
        "--res",
        "--out",
        "--seed",
        "--backend",
        "--sampling",
        "--rr",
        "--max-depth",
        "--strategy",
        "--heuristic",
        "--rr-depth",
        "--workers",
        "--checkpoint",
        "--resume",
        "--preview-every",
        "--scheduler",
        "--integrator",
    ):
        assert option in text


def test_scenes_lists_cornell_box_and_the_homeworks(capsys):
    assert main(["scenes"]) == 0
    assert {"cornell-box", "games101-hw5", "games101-hw6"} <= set(capsys.readouterr().out.split())


LIT_BY_A_POINT = """
[render]
res = [20, 10]

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]

[materials.floor]
type = "diffuse"

[[mesh]]
quad = {{ corners = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]{uv} }}
material = "floor"

[[point_light]]
position = [0, 0, 2]
intensity = {intensity}

[sky]
radiance = {sky}
"""


def point_lit_scene(tmp_path, intensity="1", sky="0.5", uv="") -> str:
    path = tmp_path / "lit.toml"
    path.write_text(LIT_BY_A_POINT.format(intensity=intensity, sky=sky, uv=uv))
    return str(path)


def test_render_takes_the_scene_files_resolution_unless_told(tmp_path):
    scene = point_lit_scene(tmp_path)
    assert main(["render", scene, "--spp", "1", "--out", str(tmp_path / "a.png"), "--quiet"]) == 0
    assert read_image(tmp_path / "a.png")[0].shape == (10, 20, 3)
    assert (
        main(["render", scene, "--spp", "1", "--res", "8", "--out", str(tmp_path / "b.png"), "--quiet"]) == 0
    )
    assert read_image(tmp_path / "b.png")[0].shape == (8, 8, 3)


@pytest.mark.parametrize(
    ("change", "problem"),
    [
        (dict(intensity="[1, -1, 1]"), "point_light[0].intensity: must not be negative"),
        (dict(sky='"blue"'), "sky.radiance: must be a colour"),
        (dict(sky="[0.1, 0.2]"), "sky.radiance: must be a list of 3 numbers"),
        (dict(uv=", uv = [[0, 0], [1, 0]]"), "mesh[0].quad.uv: must be 4 pairs"),
    ],
)
def test_bad_lights_and_uvs_are_one_line_exit_2_and_no_output(tmp_path, monkeypatch, capsys, change, problem):
    scene = point_lit_scene(tmp_path, **change)
    monkeypatch.chdir(tmp_path)
    assert exit_code(["render", scene]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert problem in err, err
    assert "Traceback" not in err, err
    assert [p.name for p in tmp_path.iterdir()] == ["lit.toml"]


def test_png_is_srgb_encoded(tmp_path):
    from ptlab.image import write_image

    linear = np.zeros((2, 2, 3), dtype=np.float32)
    linear[0, 0] = 0.5  # sRGB(0.5) = 0.7354 -> 188 (pow(0.5, 0.6) would give 168)
    linear[0, 1] = 0.0031308 * 0.5  # in the linear toe: 12.92 x -> 5.2%... -> 1
    linear[1, 0] = 2.0  # clipped to white
    linear[1, 1] = np.nan  # never reaches the file as garbage
    write_image(tmp_path / "x.png", linear)
    stored, _ = read_image(tmp_path / "x.png")
    values = np.round(stored * 255).astype(int)
    assert values[0, 0].tolist() == [188] * 3
    assert values[0, 1].tolist() == [5] * 3
    assert values[1, 0].tolist() == [255] * 3
    assert values[1, 1].tolist() == [0] * 3


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"P6\n4 4\n255\n" + bytes(10), "cannot read image: Premature end of file"),
        (b"P5\n2 2\n255\n" + bytes(4), "has 1 channel(s), not the 3 of an RGB image"),
    ],
)
def test_a_cut_short_or_grey_image_is_a_one_line_error(tmp_path, content, message):
    from ptlab.errors import PtlabError

    (tmp_path / "x.ppm").write_bytes(content)
    with pytest.raises(PtlabError, match=re.escape(message)):
        read_image(tmp_path / "x.ppm")


def test_bench_prints_speed_of_both_backends_and_the_parallel_speed_up(capsys):
    assert (
        main(
            [
                "bench",
                "--res",
                "16",
                "--spp",
                "1",
                "--estimator",
                "homework",
                "--workers",
                "1",
                "--workers",
                "2",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines()]
    rows = [r for r in rows if len(r) > 2 and r[0] in ("embree", "numpy") and r[1] == "homework"]
    assert {(r[0], r[2], r[3]) for r in rows} == {
        ("embree", "sobol", "1"),
        ("embree", "sobol", "2"),
        ("numpy", "sobol", "1"),
        ("numpy", "sobol", "2"),
    }
    for row in rows:
        # seconds, Msamples/s (a 16 x 16 render may print 0.000); the shares of time in ray
        # queries and in the sampler
        assert float(row[4]) > 0
        assert float(row[5]) >= 0
        assert row[8].endswith("%")
        assert row[9].endswith("%")
        assert 0 < float(row[9].rstrip("%")) < 100
    assert "numpy / embree time" in out
    assert "speed-up of 2 workers over 1" in out


def test_bench_tail_times_bounces_of_batches_kept_full_and_run_dry(capsys):
    import ptlab.integrators.path as path_module
    from ptlab.integrators import INTEGRATORS

    before = path_module.surface_hit, INTEGRATORS["path"], path_module.BATCH_PATHS
    args = ["bench", "--tail", "--res", "96", "--spp", "4", "--repeat", "1", "--estimator", "default"]
    assert main(args) == 0
    out = capsys.readouterr().out
    rows = {
        line.split()[0] + " " + line.split()[1]: line.split()
        for line in out.splitlines()
        if "kept full" in line or "run dry" in line
    }
    full, dry = rows["kept full"], rows["run dry"]
    # 96 x 96 x 4 = 36 864 paths: run dry, one batch dwindles from 36 864 paths, so its
    # bounces below 30 000 are most of them; kept full, the same (one group, one batch).
    assert int(dry[3]) > 5
    for row in (full, dry):
        shares = [float(cell.rstrip("%")) for cell in row[4:7]]
        assert 0 <= shares[0] <= shares[1] <= shares[2] <= 100  # (fewer paths: a subset)
    assert re.search(r"time kept full / run dry: median \d\.\d{3}", out)
    # Nothing of the measurement is left in the library's modules.
    assert (path_module.surface_hit, INTEGRATORS["path"], path_module.BATCH_PATHS) == before


@pytest.mark.subprocess
def test_bench_accuracy_compares_samplers_against_a_reference(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("PTLAB_CACHE", str(tmp_path))
    assert (
        main(
            [
                "bench",
                "--accuracy",
                "--res",
                "16",
                "--spp",
                "4",
                "--repeat",
                "2",
                "--reference-spp",
                "64",
                "--sampler",
                "independent",
                "--sampler",
                "sobol",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    rows = {
        line.split()[0]: line.split()
        for line in out.splitlines()
        if line.split() and line.split()[0] in ("independent", "sobol", "stratified")
    }
    assert set(rows) == {"independent", "sobol"}
    for row in rows.values():
        # relMSE (its range), ..., the share in the sampler (its range)
        assert float(row[1]) > 0
        assert row[-2].endswith("%")
        assert row[-1].endswith("%)")
    assert len(list(tmp_path.glob("*.exr"))) == 1  # the cached reference


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    from ptlab.atomic import write_atomically

    target = tmp_path / "image.exr"
    target.write_text("the previous image")

    def crash(temporary: str) -> None:
        with open(temporary, "w") as half:
            half.write("half an ima")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        write_atomically(target, crash)
    assert target.read_text() == "the previous image"
    assert [p.name for p in tmp_path.iterdir()] == ["image.exr"]


def test_depth_png_is_scaled_to_fit_and_says_by_how_much(tmp_path):
    out = tmp_path / "depth.png"
    assert (
        main(
            [
                "render",
                "cornell-box",
                "--integrator",
                "depth",
                "--spp",
                "1",
                "--res",
                "16",
                "--out",
                str(out),
                "--quiet",
            ]
        )
        == 0
    )
    image, metadata = read_image(out)
    assert 1000 < float(metadata["depth_scale"]) < 2000
    assert image.max() == 1.0
    assert metadata["spp"] == "1"  # PNG keeps metadata as text


@pytest.mark.parametrize("suffix", [".jpg", ".hdr", ".pfm", ".tif"])
def test_render_writes_each_format_openimageio_writes(tmp_path, monkeypatch, suffix):
    monkeypatch.chdir(tmp_path)
    tiny = ["render", "cornell-box", "--res", "32", "--spp", "8", "--workers", "1", "--quiet", "--out"]
    out, exr = tmp_path / f"box{suffix}", tmp_path / "box.exr"
    assert main([*tiny, str(out)]) == 0
    assert main([*tiny, str(exr)]) == 0
    image, _ = read_image(out)
    linear, _ = read_image(exr)
    if suffix == ".jpg":  # 8-bit sRGB, lossy: near the sRGB values, far from the linear ones
        assert np.abs(image - encode_srgb8(linear) / 255).mean() < 0.03
        assert np.abs(image - linear).mean() > 0.1
    elif suffix == ".hdr":  # RGBE: 8 bits of mantissa shared by a pixel's three channels
        assert (np.abs(image - linear) <= linear.max(axis=2, keepdims=True) / 128 + 1e-6).all()
    else:
        assert np.array_equal(image, linear)
    if suffix == ".pfm":  # (the file itself is right: its first row is the image's bottom one)
        header, size, scale, data = out.read_bytes().split(b"\n", 3)
        assert (header, size, float(scale)) == (b"PF", b"32 32", -1.0)
        stored = np.frombuffer(data, dtype="<f4").reshape(32, 32, 3)
        assert np.array_equal(stored[0], linear[-1])


def test_exposure_scales_an_8_bit_image_by_two_to_its_stops(tmp_path):
    image = np.full((2, 2, 3), 0.1, dtype=np.float32)
    write_image(tmp_path / "a.png", image, exposure=1.0)
    write_image(tmp_path / "b.png", image * 2)
    write_image(tmp_path / "c.exr", image, exposure=1.0)
    assert np.array_equal(read_image(tmp_path / "a.png")[0], read_image(tmp_path / "b.png")[0])
    assert np.array_equal(read_image(tmp_path / "c.exr")[0], image)  # (the float formats keep the values)


def test_scenes_lists_each_with_its_description(capsys):
    assert main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "cornell-box              the homework's Cornell box" in lines
    assert all(len(line.split(maxsplit=1)) == 2 for line in lines), lines


def test_the_summary_names_what_the_integrator_uses_and_the_workers_it_had(capsys, tmp_path):
    out = str(tmp_path / "w.png")
    assert (
        main(["render", "cornell-box", "--res", "16", "--spp", "1", "--integrator", "whitted", "--out", out])
        == 0
    )
    summary = capsys.readouterr().out.splitlines()[0]
    assert summary.endswith("sobol sampler, whitted, 1 worker)"), summary  # (one tile: one worker)
    assert "sampling" not in summary


LIT_FROM_BEHIND = """
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]

[materials.floor]
type = "diffuse"

[[mesh]]
quad = { corners = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]] }
material = "floor"

[[point_light]]
position = [0, 0, -2]
intensity = [10, 10, 10]
"""


def test_a_render_that_sees_no_light_warns_in_one_line(tmp_path, capsys):
    scene = tmp_path / "dark.toml"
    scene.write_text(LIT_FROM_BEHIND)  # (the light is behind the only surface the camera sees)
    code = main(
        [
            "render",
            str(scene),
            "--res",
            "8",
            "--spp",
            "1",
            "--workers",
            "1",
            "--quiet",
            "--out",
            str(tmp_path / "dark.png"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 0
    assert err.startswith("ptlab: warning: the image is black"), err
    assert err.count("\n") == 1, err
