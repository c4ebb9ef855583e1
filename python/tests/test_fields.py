"""Fields from scenes: distances through the tape, gradients, the Lipschitz bound, parallel calls."""
import threading

import numpy as np
import pytest

import sdftrace

SPHERE = {"objects": [{"type": "sphere", "radius": 1.0, "translate": [0.5, 0.0, 0.0]}]}


def random_points(n, lo=-2.0, hi=2.0, seed=1):
    return np.random.default_rng(seed).uniform(lo, hi, (n, 3)).astype(np.float32)


def test_a_sphere_evaluates_to_its_distance():
    field = sdftrace.Scene.from_dict(SPHERE).field
    p = random_points(10000)
    exact = np.linalg.norm(p - [0.5, 0, 0], axis=1) - 1.0
    np.testing.assert_allclose(field.evaluate(p), exact, atol=2e-6)


def test_gradients_match_the_analytic_normal():
    field = sdftrace.Scene.from_dict(SPHERE).field
    p = random_points(5000)
    p = p[np.linalg.norm(p - [0.5, 0, 0], axis=1) > 0.1]
    d, g = field.evaluate(p, gradients=True)
    n = (p - [0.5, 0, 0]) / np.linalg.norm(p - [0.5, 0, 0], axis=1)[:, None]
    assert g.shape == p.shape and d.shape == (len(p),)
    assert np.max(np.abs(g - n)) < 2e-3


def test_the_demo_field_keeps_its_lipschitz_bound():
    field = sdftrace.Scene.demo().field
    p, q = random_points(20000, seed=2), random_points(20000, seed=3)
    q = p + (q - p) * 0.05  # near pairs, where a wrong bound shows
    lhs = np.abs(field.evaluate(p) - field.evaluate(q))
    rhs = field.lipschitz * np.linalg.norm(p - q, axis=1)
    assert np.all(lhs <= rhs * (1 + 1e-4) + 1e-5)
    assert field.lipschitz >= 1.0
    # the tracer's culled bound is a pointwise bound, discontinuous where operands are bounds
    culled = sdftrace.Scene.demo().compile(bounds_culling=True)
    assert np.all(culled.evaluate(p) >= field.evaluate(p) - 1e-6)
    assert np.any(np.abs(culled.evaluate(p) - culled.evaluate(q)) > 1.5 * rhs)


def test_gradients_of_the_demo_are_finite_differences_of_its_values():
    field = sdftrace.Scene.demo().field
    p = random_points(2000, seed=4)
    _, g = field.evaluate(p, gradients=True, h=1e-3)
    e = np.eye(3, dtype=np.float32) * 2e-3
    fd = np.stack([(field.evaluate(p + e[a]) - field.evaluate(p - e[a])) / 4e-3 for a in range(3)], 1)
    # central differences at h and 2h agree to O(h^2) where the field is smooth: most points
    close = np.linalg.norm(g - fd, axis=1) < 1e-2
    assert close.mean() > 0.95


def test_parallel_calls_from_threads_agree_with_one_call():
    field = sdftrace.Scene.demo().field
    p = random_points(300000, seed=5)
    expected = field.evaluate(p)
    results = [None] * 4

    def work(k):
        results[k] = field.evaluate(p)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        np.testing.assert_array_equal(r, expected)


def test_any_float_dtype_and_order_is_accepted():
    field = sdftrace.Scene.from_dict(SPHERE).field
    p = random_points(100).astype(np.float64)
    np.testing.assert_allclose(field.evaluate(p), field.evaluate(np.asfortranarray(p)), atol=1e-6)
    assert field.evaluate(np.zeros((0, 3))).shape == (0,)


def test_bad_points_are_value_errors_naming_the_argument():
    field = sdftrace.Scene.demo().field
    with pytest.raises(ValueError, match=r"evaluate: points: expected an N x 3 array.*\(5, 2\)"):
        field.evaluate(np.zeros((5, 2)))
    with pytest.raises(ValueError, match="point 1 is not finite"):
        field.evaluate(np.array([[0, 0, 0], [np.nan, 0, 0]]))
    with pytest.raises(ValueError, match="evaluate: points"):
        field.evaluate("not points")
    with pytest.raises(ValueError, match="h = "):
        field.evaluate(np.zeros((1, 3)), gradients=True, h=-1.0)


def test_a_field_samples_into_a_grid_that_reads_its_distances():
    field = sdftrace.Scene.from_dict(SPHERE).field
    grid = field.to_grid(resolution=48, dense=True)
    lo, hi = grid.info["bounds"]
    p = np.random.default_rng(6).uniform(lo, hi, (4000, 3)).astype(np.float32)
    exact = np.linalg.norm(p - [0.5, 0, 0], axis=1) - 1.0
    voxel = grid.info["voxel_size"]
    err = np.abs(grid.sample(p) - exact)
    # trilinear interpolation of a sphere's distance: exact along the axes, off by a fraction of
    # a voxel where the curvature is high (near the centre)
    assert np.mean(err) < 0.01 * voxel and np.max(err) < 0.25 * voxel
    with pytest.raises(ValueError, match="unbounded"):
        sdftrace.Scene.from_dict({"objects": [{"type": "plane", "normal": [0, 1, 0]}]}).field.to_grid()
