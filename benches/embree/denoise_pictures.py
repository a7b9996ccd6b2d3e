"""The picture `compare.sh --accuracy` makes of each scene: what the filter does, where.

Usage: denoise_pictures.py REFERENCE.exr EMBREE.exr DENOISED.exr SCALE OUT.png

Top row: the reference H, Embree at 256 rays, hmdist at 64 rays with --denoise, each grey =
clamp(SCALE · H) (the scene's display scale, spec §4's picture). Bottom row, under each of
the last two: its difference from the reference, 1 − clamp(10 · SCALE · |ΔH|) (white: no
difference); background pixels blue.
"""

import sys

import numpy as np
import OpenEXR
from PIL import Image, ImageDraw, ImageFont


def read(path):
    return np.array(OpenEXR.File(path).channels()["Y"].pixels, dtype=np.float32)


def grey(values):
    v = np.nan_to_num(np.clip(values, 0, 1), nan=0.0)
    rgb = np.repeat((v * 255 + 0.5).astype(np.uint8)[..., None], 3, axis=2)
    rgb[np.isnan(values)] = (60, 90, 160)
    return Image.fromarray(rgb)


def main():
    ref_path, embree_path, ours_path, scale, out = sys.argv[1:6]
    scale = float(scale)
    ref, embree, ours = read(ref_path), read(embree_path), read(ours_path)
    tiles = [
        (grey(scale * ref), "reference (8,192 rays)"),
        (grey(scale * embree), "Embree, 256 rays"),
        (grey(scale * ours), "hmdist, 64 rays + --denoise"),
        (None, f"right: 1 - clamp(10 s |H - H_ref|),\ns = {scale:g}, white: no difference"),
        (grey(1 - 10 * scale * np.abs(embree - ref)), "|H - H_ref|, Embree 256"),
        (grey(1 - 10 * scale * np.abs(ours - ref)), "|H - H_ref|, hmdist 64 + --denoise"),
    ]
    h, w = ref.shape
    label = 24
    sheet = Image.new("RGB", (3 * w, 2 * (h + label)), "white")
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=15)
    for i, (tile, text) in enumerate(tiles):
        x, y = (i % 3) * w, (i // 3) * (h + label)
        if tile is not None:
            sheet.paste(tile, (x, y + label))
            draw.text((x + 4, y + 4), text, fill="black", font=font)
        else:
            draw.multiline_text((x + 4, y + label + 8), text, fill="black", font=font, spacing=6)
    sheet.save(out)


if __name__ == "__main__":
    main()
