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
may be lists, tuples or numpy arrays of floats or integers (`Camera([0, 1, 2], np.zeros(3))`);
one point of shape [3] gives one value. A Scene is read-only: threads may share it, and it
pickles (as does a Camera) for multiprocessing.

On Linux without XDG_RUNTIME_DIR, importing hmdist points that variable at a private empty
folder, removed at exit, as the CLI does: Mesa's Vulkan driver otherwise prints "error:
XDG_RUNTIME_DIR is invalid or not set" whenever hmdist looks for a GPU.
"""

from __future__ import annotations

import atexit
import operator
import os
import shutil
import sys
import tempfile
from typing import TYPE_CHECKING, Any, Iterable, SupportsIndex, Union

import numpy as np
import numpy.typing as npt


def _quiet_headless_vulkan() -> None:
    """On Linux without XDG_RUNTIME_DIR, point it at a private empty folder (removed at exit),
    as the CLI does: the Vulkan driver's Wayland probe otherwise prints "error:
    XDG_RUNTIME_DIR is invalid or not set" at each GPU probe."""
    if sys.platform.startswith("linux") and not os.environ.get("XDG_RUNTIME_DIR"):
        folder = tempfile.mkdtemp(prefix="hmdist-runtime-")
        os.environ["XDG_RUNTIME_DIR"] = folder
        atexit.register(shutil.rmtree, folder, True)


_quiet_headless_vulkan()

from . import _hmdist  # noqa: E402
from ._hmdist import (BUILTIN_SCENES, DEFAULT_RAYS, DEFAULT_SEED, DEFAULT_SIZE,  # noqa: E402
                      Camera, DeviceError, __version__)

__all__ = ["Scene", "Camera", "DeviceError", "f_diff", "read_exr", "BUILTIN_SCENES", "__version__"]

if TYPE_CHECKING:
    import os as _os

    PathLike = Union[str, _os.PathLike[str]]
else:
    PathLike = Any

#: Points, normals, origins, directions: an [n, 3] (or [3], or [..., 3]) array of numbers, or
#: anything numpy makes one of (lists, tuples).
Vectors = npt.ArrayLike
FloatImage = npt.NDArray[np.float32]
#: A count or seed: an int, a numpy integer, or a float with no fraction.
Count = Union[SupportsIndex, float]


def _vectors(name: str, array: Vectors, like: tuple[int, ...] | None = None
             ) -> tuple[npt.NDArray[np.float64], tuple[int, ...]]:
    """`array` ([..., 3] numbers: floats or integers) as a C-contiguous float64 [n, 3] array and
    its leading shape (() for one point of shape [3]), or ValueError naming `name`. With
    `like`, its leading shape must be that (another array's, as this returned it)."""
    a = np.asarray(array)
    if a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must hold numbers (floats or integers), not {a.dtype}")
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{name} must have shape [n, 3] (or [3]), not {list(a.shape)}")
    if like is not None and a.shape[:-1] != like:
        if a.ndim == 2 and len(like) == 1:
            raise ValueError(f"{name} has {a.shape[0]} rows, expected {like[0]}")
        raise ValueError(f"{name} has shape {list(a.shape)}, expected {[*like, 3]}")
    flat = a.reshape(-1, 3)
    if not np.all(np.isfinite(flat)):
        bad = int(np.argwhere(~np.isfinite(flat))[0][0])
        raise ValueError(f"{name}[{bad}] is not finite: {flat[bad].tolist()}")
    return np.ascontiguousarray(flat, dtype=np.float64), tuple(a.shape[:-1])


def _shaped(values: npt.NDArray[np.float32], lead: tuple[int, ...]) -> Any:
    """Per-point results in the points' leading shape: a float32 scalar for one point [3]."""
    return values.reshape(lead)[()]


def _integers(name: str, array: npt.ArrayLike, shape: tuple[int | None, ...]
              ) -> npt.NDArray[np.uint64]:
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


def _whole(name: str, value: Any, most: int) -> int:
    """A whole number from 0 to `most`: an int, a numpy integer or a float with no fraction;
    anything else (2.7, -1, "16") is a ValueError naming `name`."""
    try:
        whole = operator.index(value)
    except TypeError:
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            whole = int(value)
        else:
            raise ValueError(f"{name} must be a whole number, not {value!r}") from None
    if not 0 <= whole <= most:
        raise ValueError(f"{name} must be between 0 and {most}, not {whole}")
    return whole


def _size(value: Any) -> tuple[int, int]:
    """(width, height) from any 2 positive whole numbers (tuple, list, numpy array)."""
    try:
        width, height = (_whole("size", v, 2**32 - 1) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"size must be two positive integers (width, height), not {value!r}") from None
    if width == 0 or height == 0:
        raise ValueError(f"size must be two positive integers (width, height), not {value!r}")
    return width, height


def _parameter(name: str, value: Any) -> Any:
    """A render keyword's value as the Rust side reads it: numpy scalars as Python's."""
    if name == "size":
        return _size(value)
    if name in ("seed", "threads"):
        return _whole(name, value, 2**64 - 1)
    if isinstance(value, np.generic):
        return value.item()
    return value


class Scene:
    """A triangle scene with its camera and light; its BVH is built at the first `hmd_at` or
    `cast`. Read-only once made: threads may share one and render it at once. Picklable (for
    multiprocessing): the triangles, camera and light travel, the BVH is built again."""

    def __init__(self, inner: _hmdist.Scene) -> None:
        self._inner = inner

    @classmethod
    def load(cls, path: PathLike) -> Scene:
        """A scene from a file: OBJ, PLY, glTF/GLB, a TOML scene description, a pbrt-v4
        scene (`.pbrt`, `.pbrt.gz`) or a Mitsuba 3 scene (`.xml`), the last two with their
        camera and film size."""
        return cls(_hmdist.Scene.load(os.fspath(path)))

    @classmethod
    def builtin(cls, name: str) -> Scene:
        """A built-in scene: cube, hall, sphere, slab or dome (`BUILTIN_SCENES`)."""
        if name not in BUILTIN_SCENES:
            raise ValueError(f"no built-in scene {name!r}: the built-in scenes are {', '.join(BUILTIN_SCENES)}")
        return cls(_hmdist.Scene.load(name))

    @classmethod
    def from_arrays(cls, vertices: Vectors, faces: npt.ArrayLike, name: str = "arrays") -> Scene:
        """Triangles from vertices [n, 3] (numbers) and faces [m, 3] (vertex indices)."""
        v, _ = _vectors("vertices", vertices)
        f = _integers("faces", faces, (None, 3))
        return cls(_hmdist.Scene.from_arrays(v, f, name))

    @property
    def info(self) -> dict[str, Any]:
        """Name, triangles, bounds, l_diag, camera, light and display scale."""
        return self._inner.info

    def render(self, camera: Camera | None = None, method: str = "gather", *, progress: bool = False,
               aov: str | Iterable[str] | None = None, **params: Any) -> Any:
        """H per pixel (float32 [height, width]) and the report (a dict with the JSON
        sidecar's keys). `camera` defaults to the scene's own; `size=(w, h)` (default the
        camera's, else the scene file's own, as a pbrt Film's, else 1024 × 1024) sets the
        image's size. `params` are `hmdist render`'s flags with underscores: the render's own
        (size, seed, threads, max_distance, bvh) and the
        method's (gather: rays, weighting, rounds, ao_radius, backend; cubemap: cube_res, ...;
        photon1/photon2: photons, nearest (or its older name gather), source, photon_map, ...;
        irradiance: see `irradiance`). `denoise=True` filters H with its neighbours' rays
        (gather, adaptive, cubemap; `denoise_passes`, `denoise_radius`, `denoise_edge` as the
        CLI's `--denoise-*`). A name the method does not read is a ValueError. With
        `aov` (names: relerr, rays, dmin, ao, escaped; E_direct for irradiance) a third value
        is returned: a dict of float32 [height, width] arrays by name.

        Ctrl-C stops the render within a fraction of a second and raises KeyboardInterrupt;
        the scene stays usable."""
        if camera is not None and not isinstance(camera, Camera):
            raise ValueError(f"camera must be a hmdist.Camera, not {type(camera).__name__}")
        params = {name: _parameter(name, value) for name, value in params.items()}
        if camera is not None and "size" in params:
            camera = Camera(camera.eye, camera.target, camera.up, camera.fov_y_deg, params.pop("size"), camera.mirrored)
        names = [] if aov is None else ([aov] if isinstance(aov, str) else [str(a) for a in aov])
        image, report, aovs = self._inner.render(camera, method, params, bool(progress), names)
        return (image, report) if aov is None else (image, report, aovs)

    def irradiance(self, camera: Camera | None = None, *, progress: bool = False,
                   aov: str | Iterable[str] | None = None, **params: Any) -> Any:
        """One-bounce indirect irradiance E per pixel (float32 [height, width]) from the
        scene's spot light, and the report: `render(camera, "irradiance", ...)`. Its `params`
        are gather's rays, weighting and sampler, the surfaces' absorption (reflectance 1 −
        absorption, 0.2 by default) and the render's own; `aov="E_direct"` adds the direct
        irradiance at each pixel's point. A scene without a spot light is a ValueError."""
        return self.render(camera, "irradiance", progress=progress, aov=aov, **params)

    def cache(self, camera: Camera | None = None, *, progress: bool = False, oracle: npt.ArrayLike | None = None,
              reference: npt.ArrayLike | None = None, **params: Any) -> Any:
        """An irradiance cache, as `hmdist cache` builds it: E per pixel (float32 [height,
        width]), the report (a dict with the JSON's keys) and the records (a dict of arrays:
        `pixel`, `e`, `radius`, `level`, and per pixel `used` and, with `reference`,
        `relative_error`). `params`: `accuracy` (Ward's a, 0.2), `spacing` ("hmd",
        "hmd:METHOD[:NAME=VALUE,...]", "min", "min10", "oracle"), `clamp_pixels` and
        `clamp_scene` ((lo, hi)), `neighbour_clamp` and `gradients` (bools), the records' irradiance (rays, weighting, sampler,
        absorption) and the render's own (size, seed, threads, max_distance, bvh). `oracle`:
        an image of H for spacing "oracle"; `reference`: an image of E to measure the cache's
        error against (both float32 [height, width], as `render` and `irradiance` give)."""
        if camera is not None and not isinstance(camera, Camera):
            raise ValueError(f"camera must be a hmdist.Camera, not {type(camera).__name__}")
        params = {name: _parameter(name, value) for name, value in params.items()}
        if camera is not None and "size" in params:
            camera = Camera(camera.eye, camera.target, camera.up, camera.fov_y_deg, params.pop("size"), camera.mirrored)
        for clamp in ("clamp_pixels", "clamp_scene"):
            if params.get(clamp) is not None:
                params[clamp] = tuple(float(v) for v in params[clamp])

        def image(name: str, value: npt.ArrayLike | None) -> npt.NDArray[np.float32] | None:
            if value is None:
                return None
            array = np.ascontiguousarray(value, dtype=np.float32)
            if array.ndim != 2:
                raise ValueError(f"{name} must be an image, [height, width], not of shape {array.shape}")
            return array

        return self._inner.cache(camera, params, bool(progress), image("oracle", oracle), image("reference", reference))

    def primary_hits(self, camera: Camera | None = None, size: Any = None) -> dict[str, npt.NDArray[Any]]:
        """Each pixel's first hit, row-major: a dict of `points`, `normals` (facing the
        camera) and `point_errors` (float32 [n, 3]; NaN for background) and `triangles`
        (int64 [n], -1 for background): what `hmd_at` needs to give the image's H exactly.
        `size` (default the camera's, else the scene file's own, else 1024 × 1024) sets the
        image's size."""
        if camera is not None and not isinstance(camera, Camera):
            raise ValueError(f"camera must be a hmdist.Camera, not {type(camera).__name__}")
        if camera is not None and size is not None:
            camera = Camera(camera.eye, camera.target, camera.up, camera.fov_y_deg, _size(size), camera.mirrored)
        default = self.info["size"] or DEFAULT_SIZE
        return self._inner.primary_hits(camera, default if size is None else _size(size))

    def hmd_at(self, points: Vectors, normals: Vectors, rays: Count = DEFAULT_RAYS, seed: Count = DEFAULT_SEED,
               keys: npt.ArrayLike | None = None, weighting: str = "cosine",
               max_distance: float | None = None, triangles: npt.ArrayLike | None = None,
               errors: Vectors | None = None, backend: str = "auto", sampler: str = "sobol") -> Any:
        """H at each point (float32 [n]; [...] for points [..., 3], a float32 scalar for one
        point [3]) from `rays` gather rays around its normal; point i's random numbers are
        keyed by keys[i] (default i), as pixel i's are in an image. `triangles` (the triangle
        each point lies on) and `errors` (its floating-point error bound [n, 3]), as
        `primary_hits` gives them, start the rays exactly as the image's. `backend` ("auto",
        "gpu", "gpu-software", "cpu") says where the rays are cast, and `sampler` ("sobol" or
        "grid") how the directions fill the hemisphere, as render's do."""
        p, lead = _vectors("points", points)
        n, _ = _vectors("normals", normals, like=lead)
        count = p.shape[0]
        k = None if keys is None else _integers("keys", np.reshape(keys, -1), (count,))
        t = None if triangles is None else _integers("triangles", np.reshape(triangles, -1), (count,))
        e = None if errors is None else _vectors("errors", errors, like=lead)[0]
        h = self._inner.hmd_at(p, n, _whole("rays", rays, 2**32 - 1), _whole("seed", seed, 2**64 - 1),
                               k, weighting, None if max_distance is None else float(max_distance),
                               t, e, backend, sampler)
        return _shaped(h, lead)

    def cast(self, origins: Vectors, directions: Vectors) -> Any:
        """Distance to the first hit along each ray (float32 [n]; inf for a miss); [...] for
        origins [..., 3], a float32 scalar for one ray [3]."""
        o, lead = _vectors("origins", origins)
        d, _ = _vectors("directions", directions, like=lead)
        return _shaped(self._inner.cast(o, d), lead)

    def __reduce__(self) -> tuple[Any, ...]:
        return (Scene, (self._inner,))

    def __repr__(self) -> str:
        return repr(self._inner)


def f_diff(reference: npt.ArrayLike, test: npt.ArrayLike, l_diag: float) -> float:
    """spec §4's f_diff: mean |ΔH| over pixels finite in both images, in percent of l_diag
    (positive and finite, else ValueError)."""
    r, t = np.asarray(reference), np.asarray(test)
    if r.ndim != 2 or r.shape != t.shape:
        raise ValueError(f"images must be 2-D and of one shape, not {list(r.shape)} and {list(t.shape)}")
    return _hmdist.f_diff(np.ascontiguousarray(r, dtype=np.float64),
                          np.ascontiguousarray(t, dtype=np.float64), float(l_diag))


def read_exr(path: PathLike, channel: str = "Y") -> FloatImage:
    """One channel of an EXR file as float32 [height, width]: `Y` is H, AOVs have their own
    names (relerr, rays, dmin, ao, escaped)."""
    return _hmdist.read_exr(os.fspath(path), channel)
