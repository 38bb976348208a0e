"""The denoised race against Mitsuba (``scripts/against_mitsuba.py --denoise``): its options,
the Mitsuba + OIDN program (``ptlab.measure.mitsuba_denoised``) and the race's table.

Mitsuba's scalar variant renders here (no LLVM needed), as in ``test_mitsuba_export.py``;
where Mitsuba or ``pyoidn`` is not installed the tests that need them are skipped."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import load_script

from ptlab.errors import PtlabError
from ptlab.measure.against_mitsuba import ComparisonOptions, compare
from ptlab.measure.metrics import relative_squared_error
from ptlab.measure.mitsuba_denoised import main as mitsuba_denoised_main
from ptlab.measure.mitsuba_export import write_mitsuba_scene
from ptlab.rendering import render_result
from ptlab.scene_file import load_scene

REPOSITORY = Path(__file__).resolve().parents[2]
#: Mitsuba's CPU variant that needs no LLVM.
VARIANT = "scalar_rgb"


@pytest.fixture(scope="module")
def command():
    """``scripts/against_mitsuba.py`` as a module."""
    return load_script("against_mitsuba")


# -- the options ------------------------------------------------------------------------------


def test_the_denoised_races_options_are_read(command):
    args = command.build_parser().parse_args(
        [
            "--denoise",
            "--target-from-mitsuba-spp",
            "256",
            "--mitsuba-denoise-spp",
            "4",
            "--process-sampler",
            "multijitter",
            "--processes-only",
        ]
    )
    options = command.options_from(args)
    assert options.denoise
    assert options.target_from_mitsuba_spp == 256
    assert options.mitsuba_denoise_spp == 4
    assert options.process_sampler == "multijitter"
    assert not options.in_process
    assert options.time_processes
    options.check()  # (all of them can work together)


def test_without_the_new_options_the_race_is_as_before(command):
    options = command.options_from(command.build_parser().parse_args([]))
    assert not options.denoise
    assert options.target_from_mitsuba_spp is None
    assert options.in_process
    assert options.process_sampler == "independent"  # (the scene file's default, as before)


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--denoise", "--no-process"], "--denoise races whole processes: leave out --no-process"),
        (["--target-from-mitsuba-spp", "64", "--no-process"], "--target-from-mitsuba-spp races whole"),
        (["--no-process", "--processes-only"], "that leaves nothing to time"),
        (
            ["--target-from-mitsuba-spp", "64", "--ptlab-target-error", "0.01"],
            "give one target, not both",
        ),
        (["--target-from-mitsuba-spp", "0"], "--target-from-mitsuba-spp 0: must be from 1 to"),
        (["--denoise", "--mitsuba-denoise-spp", "-3"], "--mitsuba-denoise-spp -3: must be from 1 to"),
        (
            [
                *("--samplers", "independent", "--process-sampler", "stratified"),
                "--target-from-mitsuba-spp",
                "32",
            ],
            "--target-from-mitsuba-spp 32: Mitsuba's stratified sampler needs a square number",
        ),
        (["--ptlab-target-error", "nan"], "--ptlab-target-error nan: must be a positive relMSE"),
    ],
)
def test_a_denoised_race_that_cannot_work_is_exit_code_2_in_one_line(command, argv, says, capsys):
    assert command.main(argv) == 2
    error = capsys.readouterr().err
    assert error.startswith("against_mitsuba.py: error: ")
    assert says in error
    assert error.count("\n") == 1


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--process-sampler", "sobol"], "argument --process-sampler: invalid choice: 'sobol'"),
        (["--target-from-mitsuba-spp", "many"], "argument --target-from-mitsuba-spp: invalid int value"),
    ],
)
def test_an_option_that_does_not_parse_is_exit_code_2_in_one_line(command, argv, says, capsys):
    with pytest.raises(SystemExit) as exit:
        command.main(argv)
    assert exit.value.code == 2
    error = capsys.readouterr().err
    assert error.startswith("against_mitsuba.py: error: ")
    assert says in error
    assert error.count("\n") == 1


def test_denoising_without_pyoidn_says_what_to_install(command, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyoidn", None)  # (an import of it raises ImportError)
    assert command.main(["--denoise"]) == 2
    error = capsys.readouterr().err
    assert "pip install 'ptlab[denoise]'" in error
    assert error.count("\n") == 1


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["{xml}", "{out}", "--spp", "0"], "--spp 0: must be at least 1"),
        (["{xml}", "{out}.png", "--spp", "4"], "the output is an .exr file"),
        (["{folder}/none.xml", "{out}", "--spp", "4"], "no such scene file"),
        (["{xml}", "{out}", "--spp", "4", "--variant", "scalar_spectral"], "use an RGB variant"),
    ],
)
def test_the_mitsuba_denoised_program_refuses_in_one_line(argv, says, tmp_path, capsys):
    xml = tmp_path / "scene.xml"
    xml.write_text("<scene/>")
    names = dict(xml=xml, out=tmp_path / "out.exr", folder=tmp_path)
    assert mitsuba_denoised_main([part.format(**names) for part in argv]) == 2
    error = capsys.readouterr().err
    assert error.startswith("python -m ptlab.measure.mitsuba_denoised: error: ")
    assert says in error
    assert error.count("\n") == 1
    assert not (tmp_path / "out.exr").exists()


# -- Mitsuba + OIDN ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def installed():
    pytest.importorskip("mitsuba", reason="Mitsuba is optional: pip install mitsuba")
    pytest.importorskip("pyoidn", reason="the denoise extra: pip install 'ptlab[denoise]'")


def _layers(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    """The EXR's layers (name -> (H, W, 3); "" is R, G, B) and its ``ptlab:`` header."""
    import OpenImageIO as oiio  # noqa: N813 (the name OpenImageIO documents)

    buffer = oiio.ImageBuf(str(path))
    spec = buffer.spec()
    pixels = buffer.get_pixels(oiio.FLOAT)
    names = list(spec.channelnames)
    layers = {}
    for layer, axes in (("", "RGB"), ("noisy.", "RGB"), ("albedo.", "RGB"), ("normal.", "XYZ")):
        layers[layer.rstrip(".")] = pixels[..., [names.index(layer + axis) for axis in axes]]
    header = {a.name.removeprefix("ptlab:"): a.value for a in spec.extra_attribs}
    return layers, header


@pytest.mark.subprocess
def test_mitsuba_denoised_is_given_the_right_albedo_and_normal(installed, tmp_path):
    """The Cornell box at 64 x 64, 16 spp, seed 3 (fixed: the test is deterministic). Where all
    256 samples of ptlab's render see one surface (its albedo is a material's, its normal of
    length 1), Mitsuba's albedo and normal images must be that surface's: a layer in the wrong
    channels, the colour in place of the albedo or a normal turned away fails nearly all of
    those ~3000 pixels; a few at the light's edge may see another surface in Mitsuba's 16
    samples, hence 99%. OIDN keeps the picture's brightness (channel means within 3% of the
    noisy ones; 1% seen) and removes most of its noise (relMSE of the pixels that do not see
    the light against ptlab's 256-spp render: 0.016 denoised, 0.08 noisy)."""
    scene = load_scene("cornell-box")
    xml = write_mitsuba_scene(scene, tmp_path, 64, 64)
    out = tmp_path / "denoised.exr"
    done = subprocess.run(
        [
            *(sys.executable, "-m", "ptlab.measure.mitsuba_denoised", str(xml), str(out)),
            *("--spp", "16", "--seed", "3", "--variant", VARIANT, "--aov"),
        ],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    layers, header = _layers(out)
    assert header["denoised"].startswith("Intel Open Image Denoise ")
    assert (header["spp"], header["seed"], header["variant"]) == (16, 3, VARIANT)

    ours = render_result(scene, spp=256, res=64, seed=1, workers=1, features=True)
    albedos = np.array([material.albedo for material in scene.materials], dtype=np.float32)
    one_material = (np.abs(ours.features["albedo"][:, :, None, :] - albedos).max(axis=-1) < 1e-6).any(axis=-1)
    one_surface = one_material & (np.linalg.norm(ours.features["normal"], axis=-1) > 1 - 1e-6)
    assert one_surface.sum() > 2500
    same_albedo = np.abs(layers["albedo"] - ours.features["albedo"]).max(axis=-1) < 1e-5
    same_normal = np.abs(layers["normal"] - ours.features["normal"]).max(axis=-1) < 1e-4
    assert same_albedo[one_surface].mean() > 0.99
    assert same_normal[one_surface].mean() > 0.99

    noisy, denoised = layers["noisy"], layers[""]
    ratio = denoised.reshape(-1, 3).mean(axis=0) / noisy.reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose(ratio, 1.0, atol=0.03)
    unlit = ours.image.max(axis=-1) <= 1.0
    noisy_error = relative_squared_error(noisy, ours.image)[unlit].mean()
    denoised_error = relative_squared_error(denoised, ours.image)[unlit].mean()
    assert denoised_error < noisy_error / 2, (denoised_error, noisy_error)


@pytest.mark.subprocess
def test_the_denoised_race_sets_ptlabs_target_from_mitsuba(installed, command, tmp_path, monkeypatch):
    """One round at 16 x 16 with whole processes only: ptlab's target is Mitsuba's error at 16
    spp, and the second table compares every process with (a) and (b)."""
    monkeypatch.setenv("PTLAB_CACHE", str(tmp_path / "cache"))
    options = ComparisonOptions(
        res=(16, 16),
        spp=4,
        repeat=1,
        samplers=("independent",),
        rr_depths=(5,),
        variant=VARIANT,
        workers=1,
        reference_spp=256,
        denoise=True,
        mitsuba_denoise_spp=4,
        target_from_mitsuba_spp=16,
        in_process=False,
        csv=str(tmp_path / "runs.csv"),
    )
    said: list[str] = []
    assert compare(options, said.append) is True
    lines = "\n".join(said).splitlines()
    target_line = next(line for line in lines if "the median of Mitsuba's" in line)
    assert target_line.endswith("the median of Mitsuba's 1 renders at 16 spp")
    target = float(target_line.split(",")[0].removeprefix("target: "))

    table = lines[lines.index(next(line for line in lines if line.startswith("| process |"))) :]
    header = table[0].split(" | ")
    cells = [row.split(" | ") for row in table[2:] if row.startswith("| ")]
    rows = {row[0].removeprefix("| "): row for row in cells}
    assert list(rows) == [
        "ptlab render sobol nee 4 spp --denoise [process]",
        f"ptlab render sobol nee to {target:.3g} --denoise [process]",
        "mitsuba independent rr_depth 5 4 spp [process]",
        "mitsuba independent rr_depth 5 16 spp [process]",
        "mitsuba independent rr_depth 5 4 spp + OIDN [process]",
    ]
    a, b = header.index("s x relMSE / (a)'s"), header.index("s x relMSE / (b)'s")
    assert rows["mitsuba independent rr_depth 5 16 spp [process]"][a] == "1"
    assert rows["mitsuba independent rr_depth 5 4 spp + OIDN [process]"][b] == "1"
    # The target is Mitsuba's error at 16 spp, not at 4 (the variance falls as 1 / spp: a
    # quarter, give or take the noise of 256 pixels).
    relmse = {label: float(row[header.index("relMSE")]) for label, row in rows.items()}
    assert target < 0.6 * relmse["mitsuba independent rr_depth 5 4 spp [process]"]
    # Every run of the five processes, one round each.
    assert len((tmp_path / "runs.csv").read_text().splitlines()) == 1 + 5


def test_a_target_from_mitsuba_needs_its_command(tmp_path, monkeypatch):
    """Without the mitsuba command, the target cannot be measured: one line, not a skip."""
    from ptlab.measure import against_mitsuba

    commands = against_mitsuba.ProcessCommands(
        ComparisonOptions(target_from_mitsuba_spp=64), tmp_path / "scene.xml", tmp_path
    )
    commands.mitsuba_command = None
    with pytest.raises(PtlabError, match="--target-from-mitsuba-spp 64: no mitsuba command") as error:
        against_mitsuba.mitsuba_error(
            commands, commands.options, np.ones((2, 2, 3)), np.ones((2, 2), bool), print
        )
    assert "\n" not in str(error.value)
