"""Embree + Intel Open Image Denoise: the peer a user who knows denoisers would build
(`compare.sh --accuracy` runs it on each Embree image). OIDN comes from PyPI's `pyoidn`
(its library and trained weights); it is a benchmark peer, not a dependency of hmdist.

Usage: python3 oidn_filter.py POINTS SIDE HMD_IN HMD_OUT

POINTS is gather_rays' points file (per surface pixel: origin, camera-facing normal, pixel
index), HMD_IN the peer's H per point (little-endian f32, in the points' order). The image
filtered is S = 1/H, the per-pixel mean of 1/t that Embree's gather sums (what hmdist's
--denoise filters too), as OIDN's RT filter takes it: a colour image (S in all three
channels, HDR), with the normals as a guide and a white albedo (OIDN takes a normal only
beside an albedo), quality high. Background pixels are 0 in every image. Writes H = 1/S per
point to HMD_OUT and prints `oidn_s SECONDS`: the filter's execute alone (the device and
the filter's set-up, which a renderer pays once, are not counted).
"""

import struct
import sys
import time

import numpy as np
import pyoidn


def read_points(path):
    data = open(path, "rb").read()
    assert data[:4] == b"HMDP", "not a points file"
    (count,) = struct.unpack_from("<I", data, 8)
    records = np.frombuffer(data, dtype=np.dtype([("origin", "<f4", 3), ("normal", "<f4", 3), ("pixel", "<u4")]),
                            count=count, offset=12)
    return records["normal"], records["pixel"]


def main():
    points, side, hmd_in, hmd_out = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
    normals, pixels = read_points(points)
    h = np.fromfile(hmd_in, dtype="<f4")
    assert h.size == pixels.size, "one H per point"
    s = np.where(np.isfinite(h) & (h > 0), 1.0 / h, 0.0).astype(np.float32)
    colour = np.zeros((side * side, 3), np.float32)
    colour[pixels] = s[:, None]
    normal = np.zeros((side * side, 3), np.float32)
    normal[pixels] = normals
    albedo = np.zeros((side * side, 3), np.float32)
    albedo[pixels] = 1.0
    output = np.zeros_like(colour)
    shape = (side, side, 3)
    colour, normal, albedo, output = (a.reshape(shape) for a in (colour, normal, albedo, output))

    device = pyoidn.Device()
    device.commit()
    oidn = pyoidn.Filter(device, "RT")
    for name, image in (("color", colour), ("normal", normal), ("albedo", albedo), ("output", output)):
        oidn.set_image(name, image, pyoidn.OIDN_FORMAT_FLOAT3)
    oidn.set_bool("hdr", True)
    oidn.set_quality(pyoidn.OIDN_QUALITY_HIGH)
    oidn.commit()
    start = time.perf_counter()
    oidn.execute()
    seconds = time.perf_counter() - start
    error = device.get_error()
    if error and error[0]:
        sys.exit(f"oidn_filter: {error}")

    filtered = output.reshape(-1, 3)[pixels, 0]
    with np.errstate(divide="ignore"):
        h_out = np.where(filtered > 0, 1.0 / filtered, np.inf).astype("<f4")
    h_out.tofile(hmd_out)
    print(f"oidn_s {seconds:.6f}")


if __name__ == "__main__":
    main()
