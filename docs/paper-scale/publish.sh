#!/usr/bin/env bash
# Copies an experiment run's results from OUT into DEST for the repository: the
# tables (Markdown, CSV), plots (SVG), index.html, the plan and plan-against-run files, and the
# picture grids, each PNG over 2 MB downscaled (Lanczos) until it is under 2 MB (at paper scale
# a grid of 1024² tiles is 15 MB). No image cache, no EXR.
#
#   docs/paper-scale/publish.sh OUT DEST [RUN]   # e.g. /tmp/paper-cube docs/paper-scale/cube table1_table2
#
# With RUN, several runs publish into one DEST: the run's plan files are named plan_RUN.* and
# plan_vs_actual_RUN.* (not plan.* over an earlier run's), and its index.html is merged into
# DEST's: the run's experiments replace their sections there, the others stay, in the order of
# `hmdist experiment all`, and the run's plan-against-run table becomes a section of its own.
#
# Needs Python 3 with Pillow (pip install pillow).
set -euo pipefail
out="$1"
dest="$2"
run="${3:-}"
mkdir -p "$dest"
shopt -s nullglob
for f in "$out"/*.md "$out"/*.csv "$out"/*.svg "$out"/*.json; do
    name="$(basename "$f")"
    if [[ -n "$run" && ( "$name" == plan.* || "$name" == plan_vs_actual.* ) ]]; then
        name="${name%%.*}_$run.${name#*.}"
    fi
    cp "$f" "$dest/$name"
done
python3 - "$out/index.html" "$dest/index.html" "$run" <<'PY'
import os, re, sys

source, target, run = sys.argv[1], sys.argv[2], sys.argv[3]
ORDER = ["table1", "table2", "fig9", "fig11", "table3", "fig10", "table4", "fig16_17", "adaptive", "memory", "cost"]

def parse(html):
    """(head up to <body>, intro: h1 and its paragraph, preamble before the first section,
    {section id: html}, tail)"""
    head, body = html.split("<body>\n", 1)
    body, tail = body.rsplit("</body>", 1)
    parts = re.split(r'(?=<h2 id=")', body)
    intro_and_preamble = parts[0]
    split = intro_and_preamble.find("</p>\n") + len("</p>\n")
    intro, preamble = intro_and_preamble[:split], intro_and_preamble[split:]
    sections = {}
    for part in parts[1:]:
        sections[re.match(r'<h2 id="([^"]+)"', part).group(1)] = part
    return head + "<body>\n", intro, preamble, sections, "</body>" + tail

def write(page):
    open(target + ".tmp", "w", encoding="utf-8").write(page)
    os.replace(target + ".tmp", target)

new = open(source, encoding="utf-8").read()
if not run:
    write(new)
    sys.exit()
head, intro, preamble, sections, tail = parse(new)
if preamble.strip():
    preamble = preamble.replace('<a href="plan.md">plan.md</a>', f'<a href="plan_{run}.md">plan_{run}.md</a>')
    sections[f"plan_{run}"] = f'<h2 id="plan_{run}">Appendix: plan against run, {run}</h2>\n{preamble}'
if os.path.exists(target):
    _, old_intro, _, old_sections, _ = parse(open(target, encoding="utf-8").read())
    if old_intro != intro:
        sys.exit(f"{target} is another scene's, preset's or size's report: not merged")
    sections = {**old_sections, **sections}
rank = lambda s: (ORDER.index(s) if s in ORDER else len(ORDER), s)
sections.pop("findings", None)
sections.pop("our-findings", None)
order = sorted(sections, key=rank)
# The page's first sections: every section's findings (its <li class="finding"> items), each
# linked to its section, made again from the merged sections; the paper's first, then those
# of the studies beyond the paper (the report's BEYOND_THE_PAPER).
BEYOND_THE_PAPER = ["adaptive", "cache", "memory", "cost"]
findings, count = "", 0
for id, heading, ours in [("findings", "The paper's findings", False), ("our-findings", "Findings of our own, beyond the paper", True)]:
    items = [
        f'<li><a href="#{name}">{name}</a>: {item}</li>'
        for name in order
        if (name in BEYOND_THE_PAPER) == ours
        for item in re.findall(r'<li class="finding">(.*?)</li>', sections[name])
    ]
    count += len(items)
    if items:
        findings += f'<h2 id="{id}">{heading}</h2>\n<ul>\n' + "\n".join(items) + "\n</ul>\n"
write(head + intro + findings + "".join(sections[s] for s in order) + tail)
print(f"{os.path.basename(target)}: sections {', '.join(order)}; {count} findings")
PY
for f in "$out"/*.png; do
    python3 - "$f" "$dest/$(basename "$f")" <<'PY'
import os, sys
from PIL import Image

source, target = sys.argv[1], sys.argv[2]
limit = 2 * 1024 * 1024
image = Image.open(source)
scale = 1
while True:
    size = (max(1, image.width // scale), max(1, image.height // scale))
    small = image if scale == 1 else image.resize(size, Image.LANCZOS)
    small.save(target + ".tmp.png", optimize=True)
    if os.path.getsize(target + ".tmp.png") <= limit or min(size) <= 64:
        break
    scale *= 2
os.replace(target + ".tmp.png", target)
print(f"{os.path.basename(target)}: {image.width}x{image.height} -> {size[0]}x{size[1]}, "
      f"{os.path.getsize(target) / 1e6:.1f} MB")
PY
done
