"""A render's pieces (``ptlab.rendering.pieces``): the library's by default, any of them given
in their place and used, none of them patched into the renderer's modules."""

from __future__ import annotations

import numpy as np
import pytest

import ptlab
from ptlab.accel.numpy_bvh import BVHPieces, slab_test
from ptlab.camera import generate_rays
from ptlab.errors import PtlabError
from ptlab.integrators.path import PathPieces, mis_weight
from ptlab.rendering.pieces import LIBRARY, Pieces

SMALL = dict(spp=2, res=24, seed=5, workers=1)


def test_the_librarys_pieces_given_make_the_default_image():
    assert Pieces() == LIBRARY
    default = ptlab.render("cornell-box", **SMALL)
    np.testing.assert_array_equal(ptlab.render("cornell-box", **SMALL, pieces=Pieces()), default)


def test_a_piece_given_is_the_one_the_render_calls():
    calls = []

    def counted_rays(*arguments):
        calls.append(len(arguments[3]))
        return generate_rays(*arguments)

    def half_rays(*arguments):  # the rays of a camera looking the other way
        origins, dirs = generate_rays(*arguments)
        return origins, -dirs

    image = ptlab.render("cornell-box", **SMALL, pieces=Pieces(generate_rays=counted_rays))
    assert sum(calls) == 24 * 24 * 2  # every camera ray came from it
    np.testing.assert_array_equal(image, ptlab.render("cornell-box", **SMALL))
    away = ptlab.render("cornell-box", **SMALL, pieces=Pieces(generate_rays=half_rays))
    assert away.mean() < 0.5 * image.mean()  # the camera's back: the box's open side
    # Nothing of the render stayed in the renderer: the next render is the library's again.
    np.testing.assert_array_equal(ptlab.render("cornell-box", **SMALL), image)


def test_path_pieces_reach_every_step_that_uses_them():
    weights = []

    def weight_one(pdf, other, heuristic="power"):
        weights.append(len(np.atleast_1d(pdf)))
        return np.ones_like(np.asarray(pdf, dtype=np.float32))

    options = dict(SMALL, strategy="mis")
    mis = ptlab.render("cornell-box", **options)
    ones = ptlab.render("cornell-box", **options, pieces=Pieces(path=PathPieces(mis_weight=weight_one)))
    assert len(weights) >= 2  # light samples (direct_light) and emission found (add_emission)
    assert ones.mean() > 1.3 * mis.mean()  # both strategies counted in full: too bright
    same = Pieces(path=PathPieces(mis_weight=mis_weight))
    np.testing.assert_array_equal(ptlab.render("cornell-box", **options, pieces=same), mis)


def test_a_tree_given_pieces_of_its_own_walks_through_them_even_in_a_small_scene():
    entered = []

    def counted_slab_test(*arguments):
        hit, t = slab_test(*arguments)
        entered.append(int(hit.sum()))
        return hit, t

    pieces = Pieces(bvh=BVHPieces(slab_test=counted_slab_test))
    image = ptlab.render("cornell-box", **SMALL, backend="numpy", pieces=pieces)
    assert sum(entered) > 0  # 32 triangles: the library alone tests them one by one
    # The same hits, up to the rounding of the two tests' arithmetic (the walk's Moller-Trumbore
    # against the small scene's plane-first form, ``NumpyBVH._test_every_triangle``).
    library = ptlab.render("cornell-box", **SMALL, backend="numpy")
    np.testing.assert_allclose(image, library, rtol=1e-4, atol=1e-6)


def test_pieces_that_cannot_reach_a_worker_or_a_backend_are_refused_in_one_line():
    lambdas = Pieces(generate_rays=lambda *arguments: generate_rays(*arguments))
    with pytest.raises(PtlabError, match="workers=1"):
        ptlab.render("cornell-box", spp=2, res=96, tile_size=32, workers=2, pieces=lambdas)
    with pytest.raises(ValueError, match="backend='numpy'"):
        ptlab.render("cornell-box", **SMALL, backend="embree", pieces=Pieces(bvh=BVHPieces(slab_test=len)))
