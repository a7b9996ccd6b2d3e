#!/usr/bin/env python3
"""Tables and plots of the irradiance-cache experiment (run.sh): for each scene, every cache's
error (mean and p95 relative error against the brute-force image of E) against its cost (the
rays of the records' E and of their H; seconds), the Pareto front labelled.

    analyse.py RUNS OUT      (RUNS: run.sh's folder; OUT: where results.md and the SVGs go)
"""
import json
import math
import sys
from pathlib import Path

COLOURS = {
    "hmd": "#1f77b4", "oracle": "#000000", "gather64": "#2ca02c", "cubemap": "#9467bd",
    "photon1": "#8c564b", "photon2": "#e377c2", "pbrt-v2": "#d62728", "mitsuba": "#ff7f0e",
    "hmd-clamped": "#17becf",
}


def runs(folder):
    """Every cache run of a scene's folder: (name, a, report)."""
    found = []
    for path in sorted(folder.glob("*-a*.json")):
        name, a = path.stem.rsplit("-a", 1)
        found.append((name, float(a), json.loads(path.read_text())))
    return found


def pareto(points):
    """The points no other beats in both cost and error, by cost."""
    front, best = [], math.inf
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def panel(found, key, x0, title, width=520, height=360):
    """One SVG panel: `key` error (%) against total rays, log-log, each source a line."""
    left, right, top, bottom = 70, 20, 30, 50
    cost = [r["rays_e"] + r["rays_h"] for _, _, r in found]
    error = [100 * r["reference"][key] for _, _, r in found]
    lx = (math.log10(min(cost)) - 0.1, math.log10(max(cost)) + 0.1)
    ly = (math.log10(min(error)) - 0.1, math.log10(max(error)) + 0.1)
    sx = lambda c: x0 + left + (math.log10(c) - lx[0]) / (lx[1] - lx[0]) * (width - left - right)
    sy = lambda e: top + (ly[1] - math.log10(e)) / (ly[1] - ly[0]) * (height - top - bottom)
    out = [f'<text x="{x0 + width / 2}" y="18" text-anchor="middle" font-size="14">{title}</text>',
           f'<rect x="{x0 + left}" y="{top}" width="{width - left - right}" height="{height - top - bottom}" '
           'fill="none" stroke="#888"/>']
    for k in range(math.ceil(lx[0]), math.floor(lx[1]) + 1):
        x = sx(10 ** k)
        out.append(f'<line x1="{x}" y1="{height - bottom}" x2="{x}" y2="{height - bottom + 5}" stroke="#888"/>')
        out.append(f'<text x="{x}" y="{height - bottom + 18}" text-anchor="middle" font-size="11">1e{k}</text>')
    for e in [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500]:
        if ly[0] <= math.log10(e) <= ly[1]:
            y = sy(e)
            out.append(f'<line x1="{x0 + left - 5}" y1="{y}" x2="{x0 + width - right}" y2="{y}" stroke="#eee"/>')
            out.append(f'<text x="{x0 + left - 8}" y="{y + 4}" text-anchor="end" font-size="11">{e:g} %</text>')
    out.append(f'<text x="{x0 + width / 2}" y="{height - 10}" text-anchor="middle" font-size="12">'
               'rays (records\' E + H)</text>')
    names = sorted({n for n, _, _ in found}, key=list(COLOURS).index)
    for name in names:
        mine = sorted(((r["rays_e"] + r["rays_h"], 100 * r["reference"][key], a) for n, a, r in found if n == name))
        path = " ".join(f"{sx(c):.1f},{sy(e):.1f}" for c, e, _ in mine)
        colour = COLOURS.get(name, "#444")
        dash = ' stroke-dasharray="5,3"' if name == "oracle" else ""
        out.append(f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>')
        for c, e, _ in mine:
            out.append(f'<circle cx="{sx(c):.1f}" cy="{sy(e):.1f}" r="3" fill="{colour}"/>')
    front = pareto([(r["rays_e"] + r["rays_h"], 100 * r["reference"][key], n, a) for n, a, r in found])
    path = " ".join(f"{sx(c):.1f},{sy(e):.1f}" for c, e, _, _ in front)
    out.append(f'<polyline points="{path}" fill="none" stroke="#555" stroke-width="4" stroke-opacity="0.3"/>')
    # Labelled where the front passes to another source (and at its end), so labels do not pile
    # up where the curves meet.
    for i, (c, e, n, a) in enumerate(front):
        if i == 0 or n != front[i - 1][2] or i == len(front) - 1:
            out.append(f'<circle cx="{sx(c):.1f}" cy="{sy(e):.1f}" r="5" fill="none" stroke="#333"/>')
            out.append(f'<text x="{sx(c) + 7:.1f}" y="{sy(e) - 7:.1f}" font-size="11">{n}, a = {a:g}</text>')
    return out, names


def plot(scene, found, noise, path):
    width = 1100
    parts, names = panel(found, "mean_relative_error", 0, f"{scene}: mean relative error of E")
    more, _ = panel(found, "p95_relative_error", 560, f"{scene}: p95 relative error of E")
    parts += more
    y = 380
    for i, name in enumerate(names):
        x = 80 + i * 112
        parts.append(f'<line x1="{x}" y1="{y}" x2="{x + 20}" y2="{y}" stroke="{COLOURS.get(name, "#444")}" '
                     'stroke-width="3"/>')
        parts.append(f'<text x="{x + 24}" y="{y + 4}" font-size="11">{name}</text>')
    parts.append(f'<text x="80" y="{y + 24}" font-size="11">grey band: the Pareto front, circled and labelled where it changes source; '
                 f'the reference\'s own noise: mean {100 * noise["mean_relative_error"]:.2f} %, '
                 f'p95 {100 * noise["p95_relative_error"]:.2f} %</text>')
    svg = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{y + 40}" '
           f'font-family="sans-serif"><rect width="100%" height="100%" fill="white"/>{"".join(parts)}</svg>\n')
    path.write_text(svg)


def table(scene, found, noise):
    lines = [f"### `{scene}`", "",
             f"Reference noise (two brute-force images, seeds 7 and 8): mean "
             f"{100 * noise['mean_relative_error']:.2f} %, p95 {100 * noise['p95_relative_error']:.2f} %.", "",
             "| spacing | a | records | rays E | rays H | seconds | mean error | p95 error |",
             "|---|---|---|---|---|---|---|---|"]
    front = {(n, a) for _, _, n, a in pareto(
        [(r["rays_e"] + r["rays_h"], r["reference"]["mean_relative_error"], n, a) for n, a, r in found])}
    for name, a, r in sorted(found, key=lambda f: (list(COLOURS).index(f[0]) if f[0] in COLOURS else 99, f[1])):
        mark = " ★" if (name, a) in front else ""
        lines.append(f"| {r['spacing']} {name if name != r['spacing'] else ''} | {a:g} | {r['records']} | "
                     f"{r['rays_e']:.3g} | {r['rays_h']:.3g} | {r['seconds']['total']:.2f} | "
                     f"{100 * r['reference']['mean_relative_error']:.2f} %{mark} | "
                     f"{100 * r['reference']['p95_relative_error']:.2f} % |")
    return lines


def rays_to_reach(found, name, target):
    """The rays source `name` needs for a mean error of `target` (a fraction), interpolated
    log-log between its runs (the cheapest crossing); None where no run reaches it."""
    mine = sorted((r["rays_e"] + r["rays_h"], r["reference"]["mean_relative_error"]) for n, _, r in found if n == name)
    if mine and mine[0][1] <= target:
        return mine[0][0], "≤ "  # its cheapest run is already better: at most that
    for (c0, e0), (c1, e1) in zip(mine, mine[1:]):
        if e0 >= target >= e1 and e0 != e1:
            t = (math.log(e0) - math.log(target)) / (math.log(e0) - math.log(e1))
            return math.exp(math.log(c0) + t * (math.log(c1) - math.log(c0))), ""
    return None, ""


def equal_error(scene, found, targets):
    names = sorted({n for n, _, _ in found}, key=lambda n: list(COLOURS).index(n) if n in COLOURS else 99)
    lines = [f"Rays (records' E + H) each source needs for a mean error of "
             + ", ".join(f"{100 * t:g} %" for t in targets) + f" on `{scene}` (log-log between runs; ≤: its "
             "cheapest run is better already; —: no a reached it), and as a multiple of `hmd`'s:", "",
             "| spacing | " + " | ".join(f"{100 * t:g} %" for t in targets) + " |",
             "|---|" + "---|" * len(targets)]
    base = {t: rays_to_reach(found, "hmd", t)[0] for t in targets}
    for name in names:
        cells = []
        for t in targets:
            rays, bound = rays_to_reach(found, name, t)
            cells.append("—" if rays is None else
                         f"{bound}{rays:.3g}" + (f" (×{bound}{rays / base[t]:.2f})" if base[t] else ""))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines


def pictures(runs_dir, out, names, a):
    """One PNG of where the records go: each scene a row, each source a tile (its cache's
    picture, records red), labelled. Needs Pillow; skipped without it."""
    try:
        from PIL import Image, ImageDraw
    except ImportError:
        print("analyse.py: no Pillow, no records picture", file=sys.stderr)
        return
    rows = [d for d in sorted(runs_dir.iterdir()) if (d / f"{names[0]}-a{a}.png").exists()]
    tile = Image.open(rows[0] / f"{names[0]}-a{a}.png").size
    label = 18
    grid = Image.new("RGB", (tile[0] * len(names), (tile[1] + label) * len(rows)), "white")
    draw = ImageDraw.Draw(grid)
    for r, scene in enumerate(rows):
        for c, name in enumerate(names):
            report = json.loads((scene / f"{name}-a{a}.json").read_text())
            x, y = c * tile[0], r * (tile[1] + label)
            grid.paste(Image.open(scene / f"{name}-a{a}.png").convert("RGB"), (x, y + label))
            draw.text((x + 4, y + 3), f"{scene.name} {name}: {report['records']} records, "
                      f"{100 * report['reference']['mean_relative_error']:.1f} %", fill="black")
    grid.save(out / "records.png", optimize=True)


def main():
    runs_dir, out = Path(sys.argv[1]), Path(sys.argv[2])
    text = ["# Irradiance-cache runs", "",
            "Made by `docs/irradiance-cache/run.sh`, tabulated by `analyse.py` (★: on the Pareto front of mean "
            "error against rays).", ""]
    for scene_dir in sorted(p for p in runs_dir.iterdir() if p.is_dir()):
        found = runs(scene_dir)
        if not found:
            continue
        noise = json.loads((scene_dir / "noise.json").read_text())["reference"]
        plot(scene_dir.name, found, noise, out / f"{scene_dir.name}.svg")
        text += table(scene_dir.name, found, noise) + [""]
        targets = [0.08, 0.05, 0.03, 0.02] if scene_dir.name != "hall" else [0.9, 0.6, 0.5]
        text += equal_error(scene_dir.name, found, targets) + [""]
    (out / "results.md").write_text("\n".join(text))
    pictures(runs_dir, out, ["hmd", "hmd-clamped", "mitsuba", "pbrt-v2"], "0.2")


if __name__ == "__main__":
    main()
