"""The Python package against closed forms, the CLI and its own contracts (issue #13)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hmdist

REPO = Path(__file__).resolve().parents[2]
CLI = os.environ.get("HMDIST_BIN", str(REPO / "target" / "release" / "hmdist"))


def test_slab_floor_gives_three_halves_height_through_hmd_at():
    h = 1.0
    s = hmdist.Scene.builtin("slab")
    points = np.array([[0.3, 0.0, -0.2], [-1.0, 0.0, 2.0]])
    normals = np.array([[0.0, 1.0, 0.0], [0.0, 3.0, 0.0]])  # made unit length
    H = s.hmd_at(points, normals, rays=65536, seed=7)
    assert H.dtype == np.float32 and H.shape == (2,)
    assert np.all(np.abs(H / (1.5 * h) - 1) < 0.005), H


def test_inside_a_closed_sphere_mean_r_over_h_is_one_through_render():
    s = hmdist.Scene.builtin("sphere")
    r = 2.5
    H, report = s.render(method="gather", rays=1024, size=(24, 24), seed=3)
    assert H.shape == (24, 24) and H.dtype == np.float32
    assert report["escaped_rays"] == 0 and report["method"] == "gather"
    assert abs(np.mean(r / H) - 1) < 0.01, np.mean(r / H)


@pytest.mark.skipif(not Path(CLI).exists(), reason=f"no hmdist binary at {CLI}: cargo build --release")
@pytest.mark.parametrize("method, args", [
    ("gather", ["--rays", "32"]),
    ("photon2", ["--photons", "20000", "--gather", "64"]),
])
def test_render_equals_the_clis_exr_bit_for_bit(tmp_path, method, args):
    exr = tmp_path / "h.exr"
    subprocess.run([CLI, "render", "--quiet", "--scene", "cube", "--method", method,
                    "--size", "40x30", "--seed", "5", "--out", str(exr), *args], check=True)
    params = {"rays": 32} if method == "gather" else {"photons": 20000, "gather": 64}
    H, report = hmdist.Scene.builtin("cube").render(method=method, size=(40, 30), seed=5, **params)
    cli = hmdist.read_exr(exr)
    assert cli.shape == H.shape == (30, 40)
    assert np.array_equal(cli.view(np.uint32), H.view(np.uint32))
    assert report["width"] == 40 and report["height"] == 30 and report["seed"] == 5


def test_hmd_at_on_an_images_own_hits_keyed_by_pixel_equals_the_image():
    s = hmdist.Scene.builtin("cube")
    cam = hmdist.Camera((0.3, 4.3, 4.7), (0.0, 1.6, -1.6), fov_y_deg=60, size=(32, 24))
    H, _ = s.render(cam, method="gather", rays=16, seed=2)
    hits = s.primary_hits(cam)
    keys = np.flatnonzero(hits["triangles"] >= 0)
    h = s.hmd_at(hits["points"][keys], hits["normals"][keys], rays=16, seed=2, keys=keys,
                 triangles=hits["triangles"][keys], errors=hits["point_errors"][keys])
    assert np.array_equal(h.view(np.uint32), H.ravel()[keys].view(np.uint32))
    # Bare points (no triangle, no error bound) start their rays a little further off.
    bare = s.hmd_at(hits["points"][keys], hits["normals"][keys], rays=16, seed=2, keys=keys)
    assert np.median(np.abs(bare / H.ravel()[keys] - 1)) < 1e-4


def test_from_arrays_equals_the_same_triangles_from_an_obj(tmp_path):
    V = np.array([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2], [0, 1.5, 0]], dtype=np.float32)
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    obj = tmp_path / "tent.obj"
    obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in V)
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F))
    a, b = hmdist.Scene.from_arrays(V, F, name="tent"), hmdist.Scene.load(obj)
    assert a.info["triangles"] == b.info["triangles"] == 6
    cam = hmdist.Camera((0.5, 0.7, 0.3), (0.0, 0.0, 0.0), fov_y_deg=80, size=(16, 16))
    Ha, _ = a.render(cam, rays=32)
    Hb, _ = b.render(cam, rays=32)
    assert np.array_equal(Ha.view(np.uint32), Hb.view(np.uint32))


def test_cast_gives_distances_and_inf_for_misses():
    s = hmdist.Scene.builtin("slab")
    origins = np.array([[0, 0.5, 0], [0, 0.5, 0], [0, 2, 0]], dtype=np.float32)
    t = s.cast(origins, np.array([[0, 1, 0], [0, -2, 0], [0, 1, 0]], dtype=float))
    assert t.dtype == np.float32
    assert np.allclose(t[:2], [0.5, 0.5]) and t[2] == np.inf


def test_f_diff_is_the_mean_absolute_difference_in_percent_of_the_diagonal():
    a = np.ones((2, 2), dtype=np.float32)
    b = a.copy()
    b[0, 0] = 3.0
    assert hmdist.f_diff(a, b, l_diag=10.0) == pytest.approx(2.0 / 4 * 100 / 10)


def test_bad_arrays_and_parameters_raise_the_right_exception(tmp_path):
    s = hmdist.Scene.builtin("slab")
    n = np.array([[0.0, 1.0, 0.0]])
    with pytest.raises(ValueError, match="must hold floats"):
        s.hmd_at(np.array([[0, 0, 0]]), n)
    with pytest.raises(ValueError, match=r"shape \[n, 3\]"):
        s.hmd_at(np.zeros((4, 2)), n)
    with pytest.raises(ValueError, match="not finite"):
        s.hmd_at(np.array([[0.0, np.nan, 0.0]]), n)
    with pytest.raises(ValueError, match="normals has 1 rows, expected 2"):
        s.hmd_at(np.zeros((2, 3)), n)
    with pytest.raises(ValueError, match="rays must be at least 1"):
        s.hmd_at(np.zeros((1, 3)), n, rays=0)
    with pytest.raises(ValueError, match="unknown parameter 'ray'"):
        s.render(ray=4, size=(4, 4))
    with pytest.raises(ValueError, match="method"):
        s.render(method="raymarch", size=(4, 4))
    with pytest.raises(ValueError, match="refers to vertex 9"):
        hmdist.Scene.from_arrays(np.zeros((3, 3)), [[0, 1, 9]])
    with pytest.raises(OSError, match="cannot read file"):
        hmdist.Scene.load(tmp_path / "missing.obj")
    assert issubclass(hmdist.DeviceError, Exception)


def test_the_readmes_python_example_runs():
    text = (REPO / "README.md").read_text()
    start = text.index('```python\nimport hmdist, numpy as np\n\ns = hmdist.Scene.builtin("cube")')
    code = text[start + len("```python\n"):text.index("```\n", start + 10)]
    scope = {}
    exec(compile(code, "README.md", "exec"), scope)
    assert scope["H"].shape == (256, 256) and scope["t"][0] == pytest.approx(1.0)


def test_the_example_script_runs_with_or_without_matplotlib(tmp_path):
    script = REPO / "python" / "examples" / "render_cube.py"
    out = subprocess.run([sys.executable, str(script), str(tmp_path / "cube.png")],
                         capture_output=True, text=True, check=True).stdout
    assert "cube: 256x256" in out
    assert "wrote" in out or "pip install matplotlib" in out
