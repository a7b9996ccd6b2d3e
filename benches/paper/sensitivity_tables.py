#!/usr/bin/env python3
"""Markdown tables from fdiff_sensitivity's CSV (one or more files): per scene, f_diff of each
method at the chosen N, its ratio to ours, and its steps per doubling from 1,024 rays on;
then ours split by pixels (shell, objects, background counted) and the relative error.

    python3 benches/paper/sensitivity_tables.py cube.csv hall.csv > tables.md
"""
import csv
import sys
from collections import defaultdict

PAPER_A = {32: 0.5971, 64: 0.3121, 128: 0.1967, 256: 0.1113, 1024: 0.0357, 2048: 0.0248, 4096: 0.0351, 8192: 0.0109}
PAPER_B = {32: 0.8255, 64: 0.4799, 128: 0.3003, 256: 0.2181, 1024: 0.0994, 2048: 0.0460, 4096: 0.0454, 8192: 0.0211}
SHOWN = [32, 256, 1024]
OURS = ("cosine robust jittered", "same method")

rows = [r for path in sys.argv[1:] for r in csv.DictReader(open(path))]
by_scene = defaultdict(list)
for r in rows:
    by_scene[r["scene"]].append(r)

for scene, rs in by_scene.items():
    paper = PAPER_A if scene == "cube" else PAPER_B if scene == "hall" else {}
    floor = [r for r in rs if r["reference"].startswith("ours seed")]
    configs = defaultdict(dict)
    for r in rs:
        if r in floor:
            continue
        configs[(r["method"], r["reference"])][int(r["rays"])] = r
    ours = configs[OURS]
    size = rs[0]["size"]
    print(f"### `{scene}`, {size}²\n")
    if floor:
        f = floor[0]
        print(f"Noise floor (two independent {f['rays']}-ray references): f_diff {float(f['f_diff']):.4f}.\n")
    counts = sorted(ours)
    head = ["method", "reference"] + [f"N = {n}" for n in SHOWN] + [f"÷ ours at {n}" for n in SHOWN] + ["steps from 1,024"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for (method, reference), by_n in configs.items():
        cells = [f"`{method}`", reference]
        cells += [f"{float(by_n[n]['f_diff']):.4f}" if n in by_n else "" for n in SHOWN]
        cells += [f"×{float(by_n[n]['f_diff']) / float(ours[n]['f_diff']):.2f}" if n in by_n and n in ours else "" for n in SHOWN]
        tail = [n for n in sorted(by_n) if n >= 1024]
        steps = [float(by_n[b]["f_diff"]) / float(by_n[a]["f_diff"]) for a, b in zip(tail, tail[1:])]
        cells.append(", ".join(f"{s:.2f}" for s in steps))
        print("| " + " | ".join(cells) + " |")
    if paper:
        cells = ["the paper (as read)", ""] + [f"{paper[n]:.4f}" if n in paper else "" for n in SHOWN]
        cells += [f"×{paper[n] / float(ours[n]['f_diff']):.2f}" if n in paper else "" for n in SHOWN]
        tail = [n for n in sorted(paper) if n >= 1024]
        cells.append(", ".join(f"{paper[b] / paper[a]:.2f}" for a, b in zip(tail, tail[1:])))
        print("| " + " | ".join(cells) + " |")
    print()
    print("Ours by pixels, and the relative error:\n")
    head = ["N", "all", "shell only", "objects only", "background counted", "mean relative error", "mean H (% of l_diag)"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for n in counts:
        r = ours[n]
        print(f"| {n} | {float(r['f_diff']):.4f} | {float(r['f_diff_shell']):.4f} | {float(r['f_diff_objects']):.4f} | "
              f"{float(r['f_diff_with_background']):.4f} | {float(r['mean_rel_err']):.4f} | {float(r['mean_h_ref_pct']):.2f} |")
    print()
