"""The (N, 3) vector helpers: any (..., 3) shape, the column-major layout, no NaN."""

from __future__ import annotations

import numpy as np

from ptlab.vectors import cross, dot, normalize


def test_cross_and_dot_take_any_shape_of_3_vectors():
    rng = np.random.default_rng(0)
    for a_shape, b_shape in [
        ((3,), (3,)),
        ((50, 3), (50, 3)),
        ((50, 4, 3), (50, 4, 3)),
        ((50, 3), (3,)),
        ((50, 1, 3), (4, 3)),
    ]:
        a, b = rng.normal(size=a_shape), rng.normal(size=b_shape)
        np.testing.assert_array_equal(cross(a, b), np.cross(a, b))  # the same arithmetic
        np.testing.assert_allclose(dot(a, b), (a * b).sum(axis=-1), rtol=1e-13, atol=1e-15)


def test_cross_keeps_the_column_major_layout():
    a, b = np.random.default_rng(1).normal(size=(2, 100, 3))
    c = cross(a, b)
    assert c.flags.f_contiguous
    assert c.shape == (100, 3)


def test_normalize_gives_unit_vectors_and_leaves_zero_alone():
    v = np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(normalize(v), [[0.6, 0.8, 0.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(normalize(np.array([0.0, 2.0, 0.0])), [0.0, 1.0, 0.0])
    assert np.isfinite(normalize(np.zeros(3))).all()
