"""sdftrace: signed distance fields, baked from meshes and scenes and ray traced (docs/python.md).

The C++ core (the tape, the grids, the bakers and the tracers) is the extension module
`sdftrace._sdftrace`; this package adds the parts that are plain numpy.
"""
import json as _json
import os as _os

import numpy as _np

from ._sdftrace import (Field, Grid, MeshQuery, Scene, __version__, bake, build_info, gpu_info,
                        render, render_options, srgb, write_image)

__all__ = ["Field", "Grid", "MeshQuery", "Scene", "bake", "build_info", "gpu_info", "render", "render_options",
           "srgb", "write_image", "slice_points", "slice_field", "colorize_distance",
           "__version__"]


def _scene_from_dict(description, base_dir="."):
    """A scene from a dict with the scene file's schema (docs/scene-format.md): the same checks
    and the same one-line errors as a file, raised as ValueError naming the JSON path.

    description: the scene as a dict (camera, lights, materials, objects, ...).
    base_dir: where relative file paths in it (meshes, grids, textures) start."""
    if not isinstance(description, dict):
        raise ValueError("Scene.from_dict: expected a dict with the scene file's schema, got %s"
                         % type(description).__name__)
    try:
        text = _json.dumps(description, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise ValueError("Scene.from_dict: not JSON data: %s" % e) from None
    return Scene._from_text(text, "<dict>", _os.fspath(base_dir))


Scene.from_dict = staticmethod(_scene_from_dict)


def slice_points(bounds, axis="z", at=None, resolution=256):
    """The points of an axis-aligned slice through `bounds` ((x0, y0, z0), (x1, y1, z1)) as an
    H x W x 3 array: `axis` is the slice's normal, `at` its coordinate (default: the middle),
    `resolution` pixels along the longer side. Rows run from the top (high coordinate) down."""
    axes = {"x": 0, "y": 1, "z": 2}
    if axis not in axes:
        raise ValueError("slice_points: axis = %r: expected 'x', 'y' or 'z'" % (axis,))
    lo, hi = _np.asarray(bounds[0], _np.float64), _np.asarray(bounds[1], _np.float64)
    if lo.shape != (3,) or hi.shape != (3,) or not _np.all(hi > lo):
        raise ValueError("slice_points: bounds: expected ((x0, y0, z0), (x1, y1, z1)) with x0 < x1, "
                         "y0 < y1, z0 < z1")
    if int(resolution) < 2:
        raise ValueError("slice_points: resolution: expected an integer >= 2")
    n = axes[axis]
    u, v = [a for a in range(3) if a != n]
    ext = hi - lo
    scale = int(resolution) / max(ext[u], ext[v])
    w, h = max(2, int(round(ext[u] * scale))), max(2, int(round(ext[v] * scale)))
    uu = lo[u] + (_np.arange(w) + 0.5) / w * ext[u]
    vv = hi[v] - (_np.arange(h) + 0.5) / h * ext[v]
    pts = _np.empty((h, w, 3), _np.float32)
    pts[..., u] = uu[None, :]
    pts[..., v] = vv[:, None]
    pts[..., n] = (lo[n] + hi[n]) / 2 if at is None else float(at)
    return pts


def slice_field(field, axis="z", at=None, resolution=256, bounds=None):
    """Distances on a slice (H x W float32) of a Field or Grid.

    field: the Field or Grid to sample.
    axis: the slice's normal, 'x', 'y' or 'z'.
    at: the slice's coordinate along the axis (default: the middle of the bounds).
    resolution: pixels along the slice's longer side.
    bounds: ((x0, y0, z0), (x1, y1, z1)) to slice (default: the grid's box, or the field's
    bounds)."""
    if bounds is None:
        bounds = field.info["bounds"] if isinstance(field, Grid) else field.bounds
        if bounds is None:
            raise ValueError("slice_field: the field is unbounded; give bounds=")
    pts = slice_points(bounds, axis, at, resolution)
    flat = pts.reshape(-1, 3)
    values = field.sample(flat) if isinstance(field, Grid) else field.evaluate(flat)
    return _np.asarray(values).reshape(pts.shape[:2])


def colorize_distance(distances, scale=None):
    """Signed distances (H x W) to an 8-bit picture of the field: orange outside, blue inside,
    contour bands every `scale` / 2 (default: a tenth of the largest |distance|), white at the
    surface (Inigo Quilez's convention)."""
    d = _np.asarray(distances, _np.float64)
    if d.ndim != 2:
        raise ValueError("colorize_distance: expected an H x W array of distances")
    finite = _np.isfinite(d)
    if scale is None:
        scale = 0.1 * (_np.max(_np.abs(d[finite])) if finite.any() else 1.0) or 1.0
    s = d / scale
    col = _np.where(s[..., None] > 0, _np.array([0.9, 0.6, 0.3]), _np.array([0.65, 0.85, 1.0]))
    col = col * (1.0 - _np.exp(-2.0 * _np.abs(s)))[..., None]
    col = col * (0.8 + 0.2 * _np.cos(4.0 * _np.pi * s))[..., None]
    edge = _np.clip(1.0 - _np.abs(s) / 0.08, 0.0, 1.0)[..., None]
    col = col * (1 - edge) + edge
    col[~finite] = 0
    return (_np.clip(col, 0, 1) * 255 + 0.5).astype(_np.uint8)
