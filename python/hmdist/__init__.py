"""hmdist for numpy: harmonic mean distance (HMD) images of triangle-mesh scenes, and H at
the points you choose.

    import hmdist, numpy as np
    s = hmdist.Scene.builtin("cube")            # or Scene.load("room.glb"), Scene.from_arrays(V, F)
    H, report = s.render(method="gather", rays=256, size=(256, 256))
    h = s.hmd_at(points, normals, rays=1024)    # float32 [n]
    t = s.cast(origins, directions)             # float32 [n], inf for misses

Conventions (as the Rust library's): distances in scene units; H is NaN for background
pixels and +inf where every ray escaped; a point's normal says which side it is seen from.
Bad arrays and parameters raise ValueError, unreadable files OSError, GPU failures
hmdist.DeviceError. The GIL is released while hmdist works, and Ctrl-C stops a render, an
`hmd_at` or a `cast` within a fraction of a second with KeyboardInterrupt. Points and vectors
may be lists, tuples or numpy arrays (`Camera([0, 1, 2], np.zeros(3))`).
"""

import numpy as np

from . import _hmdist
from ._hmdist import Camera, DeviceError, __version__

__all__ = ["Scene", "Camera", "DeviceError", "f_diff", "read_exr", "__version__"]


def _vectors(name, array, rows=None):
    """`array` as a C-contiguous float64 [n, 3] array, or ValueError naming `name`."""
    a = np.asarray(array)
    if a.dtype.kind != "f":
        raise ValueError(f"{name} must hold floats (float32 or float64), not {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape [n, 3], not {list(a.shape)}")
    if rows is not None and a.shape[0] != rows:
        raise ValueError(f"{name} has {a.shape[0]} rows, expected {rows}")
    if not np.all(np.isfinite(a)):
        bad = int(np.argwhere(~np.isfinite(a))[0][0])
        raise ValueError(f"{name}[{bad}] is not finite: {a[bad].tolist()}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _integers(name, array, shape):
    """`array` as a C-contiguous uint64 array of `shape` (None: any length), or ValueError."""
    a = np.asarray(array)
    if a.dtype.kind not in "iu":
        raise ValueError(f"{name} must hold integers, not {a.dtype}")
    if a.ndim != len(shape) or any(s is not None and s != d for s, d in zip(shape, a.shape)):
        want = ", ".join("n" if s is None else str(s) for s in shape)
        raise ValueError(f"{name} must have shape [{want}], not {list(a.shape)}")
    if a.size and a.min() < 0:
        raise ValueError(f"{name} must not be negative")
    return np.ascontiguousarray(a, dtype=np.uint64)


class Scene:
    """A triangle scene with its camera and light; its BVH is built at the first `hmd_at` or
    `cast`."""

    def __init__(self, inner):
        self._inner = inner

    @classmethod
    def load(cls, path):
        """A scene from a file: OBJ, PLY, glTF/GLB or a TOML scene description."""
        return cls(_hmdist.Scene.load(str(path)))

    @classmethod
    def builtin(cls, name):
        """A built-in scene: cube, hall, sphere, slab or dome."""
        return cls(_hmdist.Scene.load(name))

    @classmethod
    def from_arrays(cls, vertices, faces, name="arrays"):
        """Triangles from vertices [n, 3] (floats) and faces [m, 3] (vertex indices)."""
        v = _vectors("vertices", vertices)
        f = _integers("faces", faces, (None, 3))
        return cls(_hmdist.Scene.from_arrays(v, f, name))

    @property
    def info(self):
        """Name, triangles, bounds, l_diag, camera, light and display scale."""
        return self._inner.info

    def render(self, camera=None, method="gather", *, progress=False, aov=None, **params):
        """H per pixel (float32 [height, width]) and the report (a dict with the JSON
        sidecar's keys). `camera` defaults to the scene's own (then `size=(w, h)`, default
        1024 × 1024); `params` are `hmdist render`'s flags with underscores: the render's own
        (size, seed, threads, max_distance, bvh) and the method's (gather: rays, weighting,
        rounds, ao_radius, backend; cubemap: cube_res, ...; photon1/photon2: photons,
        nearest (or its older name gather), source, photon_map, ...). A name the method does
        not read is a ValueError. With `aov` (names: relerr, rays, dmin, ao, escaped) a third
        value is returned: a dict of float32 [height, width] arrays by name.

        Ctrl-C stops the render within a fraction of a second and raises KeyboardInterrupt;
        the scene stays usable."""
        if camera is not None and not isinstance(camera, Camera):
            raise ValueError(f"camera must be a hmdist.Camera, not {type(camera).__name__}")
        names = [] if aov is None else ([aov] if isinstance(aov, str) else [str(a) for a in aov])
        image, report, aovs = self._inner.render(camera, method, params, bool(progress), names)
        return (image, report) if aov is None else (image, report, aovs)

    def primary_hits(self, camera=None, size=(1024, 1024)):
        """Each pixel's first hit, row-major: a dict of `points`, `normals` (facing the
        camera) and `point_errors` (float32 [n, 3]; NaN for background) and `triangles`
        (int64 [n], -1 for background): what `hmd_at` needs to give the image's H exactly."""
        if camera is not None and not isinstance(camera, Camera):
            raise ValueError(f"camera must be a hmdist.Camera, not {type(camera).__name__}")
        return self._inner.primary_hits(camera, tuple(size))

    def hmd_at(self, points, normals, rays=64, seed=1, keys=None, weighting="cosine",
               max_distance=None, triangles=None, errors=None, backend="auto"):
        """H at each point (float32 [n]) from `rays` gather rays around its normal; point
        i's random numbers are keyed by keys[i] (default i), as pixel i's are in an image.
        `triangles` (the triangle each point lies on) and `errors` (its floating-point error
        bound [n, 3]), as `primary_hits` gives them, start the rays exactly as the image's.
        `backend` ("auto", "gpu", "gpu-software", "cpu") says where the rays are cast, as
        render's does."""
        p = _vectors("points", points)
        n = _vectors("normals", normals, rows=p.shape[0])
        k = None if keys is None else _integers("keys", keys, (p.shape[0],))
        t = None if triangles is None else _integers("triangles", triangles, (p.shape[0],))
        e = None if errors is None else _vectors("errors", errors, rows=p.shape[0])
        return self._inner.hmd_at(p, n, int(rays), int(seed), k, weighting, max_distance, t, e,
                                  backend)

    def cast(self, origins, directions):
        """Distance to the first hit along each ray (float32 [n]; inf for a miss)."""
        o = _vectors("origins", origins)
        d = _vectors("directions", directions, rows=o.shape[0])
        return self._inner.cast(o, d)

    def __repr__(self):
        return repr(self._inner)


def f_diff(reference, test, l_diag):
    """SPEC §4's f_diff: mean |ΔH| over pixels finite in both images, in percent of l_diag."""
    r, t = np.asarray(reference), np.asarray(test)
    if r.ndim != 2 or r.shape != t.shape:
        raise ValueError(f"images must be 2-D and of one shape, not {list(r.shape)} and {list(t.shape)}")
    as64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)
    return _hmdist.f_diff(as64(r), as64(t), float(l_diag))


def read_exr(path, channel="Y"):
    """One channel of an EXR file as float32 [height, width]: `Y` is H, AOVs have their own
    names (relerr, rays, dmin, ao, escaped)."""
    return _hmdist.read_exr(str(path), channel)
