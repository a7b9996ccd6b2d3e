"""Casts hmdist's gather rays with Open3D's RaycastingScene (Embree 4 inside), for
benches/embree/compare.sh.

    python open3d_cast.py SCENE.obj RAYS.hmdr THREADS

Times the build (add_triangles plus the first query, which commits the scene) and the
casting calls only; rays go in chunks of about 1 M. Open3D has no tnear, and from hmdist's
origins (offset off the surface by its rounding-error bound only) Embree 4 finds the surface
a ray leaves again at t ≈ 0 for about a third of the rays, which then stop at once. So each
origin is moved along its ray by the spec's d_min (1e-6 of the diagonal), as the C peer's tnear
does; `self_hits` counts the hits still closer than d_min. Prints one line in the format of
gather_rays.rs."""
import sys
import time

import numpy as np
import open3d as o3d


def read_obj(path):
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    return np.array(vertices, np.float32), np.array(faces, np.uint32)


def read_rays(path):
    data = np.fromfile(path, np.uint8)
    assert bytes(data[:4]) == b"HMDR"
    _, pixels, n = np.frombuffer(data[4:16].tobytes(), "<u4")
    records = np.frombuffer(data[16:].tobytes(), "<f4").reshape(pixels, 4 + 3 * n)
    origins = records[:, :3]
    directions = records[:, 4:].reshape(pixels, n, 3)
    rays = np.empty((pixels, n, 6), np.float32)
    rays[:, :, :3] = origins[:, None, :]
    rays[:, :, 3:] = directions
    return rays.reshape(-1, 6)


def main():
    obj, rays_path, threads = sys.argv[1], sys.argv[2], int(sys.argv[3])
    vertices, faces = read_obj(obj)
    rays = read_rays(rays_path)
    d_min = 1e-6 * float(np.linalg.norm(vertices.max(0) - vertices.min(0)))
    rays[:, :3] += d_min * rays[:, 3:]
    start = time.perf_counter()
    scene = o3d.t.geometry.RaycastingScene(nthreads=threads)
    scene.add_triangles(o3d.core.Tensor(vertices), o3d.core.Tensor(faces))
    scene.cast_rays(o3d.core.Tensor(rays[:1]), nthreads=threads)
    build = time.perf_counter() - start
    chunks = [o3d.core.Tensor(rays[i : i + (1 << 20)]) for i in range(0, len(rays), 1 << 20)]
    start = time.perf_counter()
    t_hits = [scene.cast_rays(c, nthreads=threads)["t_hit"] for c in chunks]
    seconds = time.perf_counter() - start
    t = np.concatenate([t.numpy() for t in t_hits])
    escaped = int(np.isinf(t).sum())
    self_hits = int((t < d_min).sum())
    with np.errstate(divide="ignore"):  # a hit at t = 0 (self-intersection) counts as inf
        mean_inverse = float(np.where(np.isinf(t), 0.0, 1.0 / t.astype(np.float64)).mean())
    print(
        f"open3d build_s {build:.3f} trace_s {seconds:.3f} mrays_per_s {len(rays) / seconds / 1e6:.3f} "
        f"rays {len(rays)} escaped {escaped} mean_inverse {mean_inverse:.6f} self_hits {self_hits}"
    )


if __name__ == "__main__":
    main()
