"""Throughput of the Python module's batch evaluation (docs/python.md), medians of 5 runs:
points per second through Field.evaluate and Grid.sample, one call of 10^6 points against 1000
calls of 10^3 (the binding's per-call cost), and a numpy expression of the same sphere field as a
baseline in the same process.

    PYTHONPATH=build/release/python python3 bench/python_evaluate_bench.py
"""
import statistics
import time

import numpy as np

import sdftrace


def median_seconds(fn, reps=5):
    times = []
    for _ in range(reps):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main():
    rng = np.random.default_rng(0)
    pts = rng.uniform(-3, 3, (1_000_000, 3)).astype(np.float32)
    small = [pts[i * 1000:(i + 1) * 1000] for i in range(1000)]
    sphere = sdftrace.Scene.from_dict({"objects": [{"type": "sphere", "radius": 1.0}]}).field
    demo = sdftrace.Scene.demo()
    cases = [
        ("sphere, tape", sphere.evaluate),
        ("sphere, numpy (baseline)", lambda p: np.linalg.norm(p, axis=1) - 1.0),
        ("demo, the field's definition", demo.field.evaluate),
        ("demo, culled (the tracer's tape)", demo.compile(bounds_culling=True).evaluate),
        ("demo, with gradients", lambda p: demo.field.evaluate(p, gradients=True)),
    ]
    grid = sdftrace.bake(*_cube(), resolution=128)
    cases.append(("cube grid 128, Grid.sample", grid.sample))
    print("| case | 1 call of 10^6 points | 1000 calls of 10^3 |")
    print("| --- | --- | --- |")
    for name, fn in cases:
        big = median_seconds(lambda: fn(pts))
        many = median_seconds(lambda: [fn(p) for p in small], reps=3)
        print("| %s | %.1f M points/s | %.1f M points/s |" % (name, 1.0 / big, 1.0 / many))


def _cube():
    v = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], np.float32)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return v, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], np.int32)


if __name__ == "__main__":
    main()
