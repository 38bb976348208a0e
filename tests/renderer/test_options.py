"""``RenderOptions`` (``ptlab/rendering/options.py``): each option defined once, and the API,
the command line, image headers and checkpoints made from it."""

from __future__ import annotations

import inspect
import re
from dataclasses import fields

import numpy as np
import pytest

import ptlab
from ptlab.accel import BACKENDS
from ptlab.cli import build_parser
from ptlab.errors import PtlabError, is_integer
from ptlab.integrators import INTEGRATORS
from ptlab.integrators.path import HEURISTICS, STRATEGIES, PathSettings
from ptlab.materials.diffuse import SAMPLINGS
from ptlab.rendering import RenderOptions, render_result
from ptlab.samplers import DEFAULT_SAMPLER, SAMPLERS
from ptlab.scene import Scene

OPTIONS = [f.name for f in fields(RenderOptions)]


@pytest.mark.parametrize("function", [ptlab.render, ptlab.render_result])
def test_the_api_takes_every_option_with_its_default(function):
    parameters = inspect.signature(function).parameters
    assert list(parameters)[1 : len(OPTIONS) + 1] == OPTIONS
    for name in OPTIONS:
        assert parameters[name].default == RenderOptions.default(name), name
        assert f"{name}: " in function.__doc__  # and its help


def test_defaults_come_from_the_modules_that_own_them():
    options = RenderOptions()
    assert (options.strategy, options.heuristic, options.rr, options.rr_depth) == (
        PathSettings.strategy,
        PathSettings.heuristic,
        PathSettings.rr,
        PathSettings.rr_depth,
    )
    assert options.sampler == DEFAULT_SAMPLER
    assert options.max_depth is None
    assert INTEGRATORS["whitted"].max_depth == 5
    assert INTEGRATORS["path"].max_depth == PathSettings.max_depth


def test_options_given_by_name_in_order_or_as_one_object_render_alike(cornell):
    by_name = ptlab.render(cornell, spp=2, res=12, seed=3, workers=1)
    in_order = ptlab.render(cornell, 2, 12, 3, 1)
    as_object = ptlab.render(cornell, options=RenderOptions(spp=2, res=12, seed=5), seed=3, workers=1)
    assert np.array_equal(by_name, in_order)
    assert np.array_equal(by_name, as_object)
    with pytest.raises(TypeError):
        ptlab.render(cornell, spp=2, checkpoint="x.npz")  # render_result's, not an option


def test_options_left_open_are_decided_for_the_scene(cornell):
    options = RenderOptions(integrator="whitted").for_scene(cornell)
    assert options.res == (512, 512)
    assert options.max_depth == 5
    assert options.backend in ("embree", "numpy")
    assert options.spp_per_pass == 16
    assert RenderOptions(spp=4).for_scene(cornell).spp_per_pass == 4
    hw5 = ptlab.load_scene("games101-hw5")
    assert RenderOptions().for_scene(hw5).res == hw5.defaults.res


#: (options, their whole one-line error): the messages of the checks before RenderOptions.
BAD = [
    (dict(spp=0), "spp 0: must be an integer from 1 to 1048576"),
    (dict(spp=True), "spp True: must be an integer from 1 to 1048576"),
    (dict(spp=2.0), "spp 2.0: must be an integer from 1 to 1048576"),
    (dict(res=-5), "resolution -5x-5: width and height must be positive"),
    (dict(res="axb"), "resolution 'axb': expected N or WxH, e.g. 512 or 640x480"),
    (dict(res=1.5), "resolution 1.5: expected N or (width, height)"),
    (dict(seed=-1), "seed -1: must be a non-negative integer"),
    (dict(workers=0), "workers 0: must be an integer from 1 to 1024"),
    (dict(backend="optix"), "backend 'optix': choose one of auto, embree, numpy"),
    (dict(integrator="bdpt"), "integrator 'bdpt': choose one of path, whitted, normals, albedo, depth"),
    (dict(sampling="magic"), "sampling 'magic': choose one of cosine, uniform"),
    (
        dict(rr=1.5),
        "russian roulette 1.5: the survival probability must be in [2^-24, 1] "
        "(the uniforms it is drawn against are float32)",
    ),
    (dict(rr="sometimes"), "russian roulette 'sometimes': give 'throughput' or a probability"),
    (dict(max_depth=-1), "max depth -1: must be a non-negative integer"),
    (dict(strategy="all"), "strategy 'all': choose one of nee, bsdf, mis"),
    (dict(heuristic="magic"), "heuristic 'magic': choose one of power, balance"),
    (dict(rr_depth=-1), "russian roulette depth -1: must be a non-negative integer"),
    (dict(sampler=["sobol"]), "sampler ['sobol']: choose one of independent, stratified, sobol"),
    (dict(tile_size=4), "tile size 4: must be an integer from 8 to 4096"),
    (dict(spp_per_pass=0), "spp per pass 0: must be a positive integer"),
    (dict(target_error=0), "target error 0: must be a number above 0"),
    (dict(target_error=float("inf")), "target error inf: must be a number above 0"),
    (dict(target_error="low"), "target error 'low': must be a number above 0"),
    (dict(target_error=0.01, max_spp=0), "max spp 0: must be an integer from 1 to 1048576"),
    (dict(target_error=0.01, time_limit=-2), "time limit -2: must be a number above 0"),
    (
        dict(max_spp=64),
        "max spp and time limit bound a render to a target error: give target_error too",
    ),
    (
        dict(target_error=0.01, spp=15),
        "spp 15: with a target error, the first pass's samples per pixel must be even "
        "(half of them measure the other half's error)",
    ),
    (
        dict(target_error=0.01, sampler="stratified"),
        "sampler 'stratified' lays out a fixed number of samples per pixel; a render to a "
        "target error adds samples as it goes: use sobol or independent",
    ),
    (
        dict(integrator="whitted", strategy="mis"),
        "strategy 'mis' / heuristic 'power': these choose how the path integrator finds light; "
        "'whitted' has no such choice",
    ),
    (dict(denoise="yes"), "denoise: 'yes' is not True or False"),
    (
        dict(crop="1,2,3"),
        "crop '1,2,3': expected X,Y,W,H, four whole numbers (a window of the image in pixels, "
        "from its top-left corner)",
    ),
    (
        dict(denoise=True, integrator="albedo"),
        "denoise: the denoiser is for path-traced images; 'albedo' gathers no albedo and normal "
        "images for it",
    ),
    (
        dict(integrator="normals", heuristic="balance"),
        "strategy 'nee' / heuristic 'balance': these choose how the path integrator finds light; "
        "'normals' has no such choice",
    ),
]


@pytest.mark.parametrize(("options", "message"), BAD, ids=[str(o) for o, _ in BAD])
def test_each_bad_value_is_its_one_line_error(options, message):
    with pytest.raises(PtlabError, match=f"^{re.escape(message)}$"):
        RenderOptions(**options)


def test_every_option_is_checked():
    assert {name for options, _ in BAD for name in options} == set(OPTIONS)


def test_is_integer_takes_ints_and_numpy_integers_not_bools():
    assert all(map(is_integer, [3, np.int64(3), np.uint8(3)]))
    assert not any(map(is_integer, [True, np.bool_(True), 3.0, "3", None]))


def test_checked_values_are_plain():
    options = RenderOptions(spp=np.int64(4), res="20x10", seed=np.uint32(2), rr="0.5")
    assert options.spp == 4
    assert type(options.spp) is int
    assert options.res == (20, 10)
    assert options.rr == 0.5
    assert type(options.seed) is int


def render_actions(command: str = "render") -> dict:
    parser = build_parser(command)
    commands = next(a for a in parser._actions if a.dest == "command")
    return {action.dest: action for action in commands.choices[command]._actions}


def test_the_commands_options_are_render_options():
    actions = render_actions()
    for name in set(OPTIONS) - {"tile_size", "spp_per_pass"}:
        # An option left out is None, so that --resume can tell it from one given; the
        # render then takes RenderOptions' default, which --help names.
        assert actions[name].default is None, name
        if RenderOptions.default(name) is False:  # (a flag: off unless given, no default said)
            assert "(default" not in actions[name].help, name
            assert actions[name].const is True, name
        elif RenderOptions.default(name) is not None:
            assert f"(default {RenderOptions.default(name)})" in actions[name].help, name
    for name, owner in [
        ("integrator", tuple(INTEGRATORS)),
        ("backend", BACKENDS),
        ("sampling", SAMPLINGS),
        ("strategy", STRATEGIES),
        ("heuristic", HEURISTICS),
        ("sampler", SAMPLERS),
    ]:
        assert tuple(actions[name].choices) == owner, name
    converge = render_actions("converge")
    for name in ("seed", "backend", "workers", "sampler"):
        assert converge[name].choices == actions[name].choices
        assert converge[name].default == RenderOptions.default(name)


def test_a_scene_that_already_samples_so_is_not_rebuilt(cornell, monkeypatch):
    built = []
    original = Scene.__init__
    monkeypatch.setattr(
        Scene, "__init__", lambda scene, *args, **kw: built.append(1) or original(scene, *args, **kw)
    )
    assert cornell.with_sampling("cosine") is cornell
    ptlab.render(cornell, spp=1, res=8, workers=1)
    assert built == []
    ptlab.render(cornell, spp=1, res=8, workers=1, sampling="uniform")
    assert built == [1]


def test_the_header_records_every_option(cornell):
    result = render_result(cornell, spp=2, res=(12, 8), seed=4, workers=1, rr=0.8)
    settings = result.settings
    assert (settings["width"], settings["height"], settings["seed"]) == (12, 8, 4)
    assert settings["rr"] == "0.8"
    assert settings["rr_depth"] == 0
    assert settings["max_depth"] == 100
    assert settings["integrator"] == "path"
    assert set(OPTIONS) - {"res"} <= set(settings)
