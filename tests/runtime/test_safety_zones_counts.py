"""The zones' per-scan point counts test a polygon only against the points within its reach
(safety_zones.py ``Shape.count`` with squared distances): the counts equal the ray test over
every point, for convex and concave polygons and circles, with points on vertices, on edges,
on the rim of the reach and far away."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.safety_zones import Shape


def polygon(rng: np.random.Generator) -> np.ndarray:
    k = int(rng.integers(3, 9))
    angles = np.sort(rng.uniform(0, 2 * math.pi, k))
    radii = rng.uniform(0.05, 1.5, k)  # star-shaped: concave as often as not
    centre = rng.uniform(-0.3, 0.3, 2) * rng.integers(0, 2)
    return np.column_stack([centre[0] + radii * np.cos(angles), centre[1] + radii * np.sin(angles)])


@pytest.mark.parametrize("seed", range(20))
def test_counts_within_reach_equal_the_ray_test_over_every_point(seed):
    rng = np.random.default_rng(seed)
    vertices = polygon(rng)
    shapes = [Shape(vertices=vertices), Shape(vertices=np.round(vertices, 1)), Shape(radius=float(rng.uniform(0.1, 1)))]
    for shape in shapes:
        pts = [rng.uniform(-3, 3, (400, 2)), rng.uniform(-0.5, 0.5, (200, 2))]
        if shape.vertices is not None:
            v = shape.vertices
            pts.append(v)  # the vertices themselves
            t = rng.uniform(0, 1, (len(v), 1))
            pts.append(v + t * (np.roll(v, 1, axis=0) - v))  # points on the edges
            far = int(np.argmax(np.hypot(v[:, 0], v[:, 1])))
            pts.append(v[far] * (1 + rng.choice([-1e-12, 0.0, 1e-12, 1e-10, 1e-8], (20, 1))))  # the rim
        xy = np.concatenate(pts)
        x, y = xy[:, 0].copy(), xy[:, 1].copy()
        d2 = x * x + y * y
        assert shape.count(x, y, d2) == int(np.count_nonzero(shape.inside(x, y)))
        assert shape.count(x, y) == shape.count(x, y, d2)
        assert shape.count(x[:0], y[:0], d2[:0]) == 0
