#!/usr/bin/env python3
"""The inputs that once grew faster than their size, measured from 10^2 or 10^3 upwards.

The table of docs/benchmarks.md, "Inputs that once fell off a cliff". Each family writes its
files itself (the shapes `mbsa generate` does not make: a mechanism at its file's geometry, an
imported robot description, a bar-joint framework), then runs one command through the release
binary under `/usr/bin/time` with the CPU and address-space caps of scripts/growth.py. The last
column is the largest ratio of a size's CPU to its linear extrapolation from the smallest size
(whose CPU counts as at least 10 ms): 1 is linear, and the target is at most 3.

Usage: python3 scripts/cliffs.py [--cap-seconds 120] [--repeat 1] [--families a,b] [--write]
"""

import argparse
import os
import random
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from growth import BIN, ROOT, fmt_time, run  # noqa: E402


def n_four_bar(windows, planar=True):
    """The IFToMM N-four-bar (as mechanisms/n-four-bar-40-driven.toml): verticals pinned to the
    ground at (k, 0), their tops at (k + 0.6, 0.8) joined by horizontals; the first crank driven.
    Every number known to ±0.05, as the digits of `100.6` say: read from its digits alone, a
    pin at `1234` would be known to ±0.5, half a link, and the largest files undecidable."""
    out = [f'name = "N-four-bar (N = {windows})"', f'space = "{"planar" if planar else "spatial"}"',
           "frame = 1", "precision = 0.05", ""]

    def joint(ident, a, b, x, y, driven=0):
        origin = f"[{x:g}, {y:g}]" if planar else f"[{x:g}, {y:g}, 0]"
        out.extend(["[[joint]]", f'id = "{ident}"', 'type = "R"', f"bodies = [{a}, {b}]",
                    f"origin = {origin}"])
        if not planar:
            out.append("axis = [0, 0, 1]")
        if driven:
            out.append(f"driven = {driven}")
        out.append("")

    joint("A0", 1, 2, 0, 0, driven=1)
    for k in range(1, windows + 1):
        joint(f"VB{k - 1}", 2 * k, 2 * k + 1, k - 1 + 0.6, 0.8)
        joint(f"B{k}", 2 * k + 1, 2 * k + 2, k + 0.6, 0.8)
        joint(f"P{k}", 1, 2 * k + 2, k, 0)
    return "\n".join(out)


def dyad_strip(bodies):
    """A strip of planar RRR dyads, each pinned to the two bodies of the one before: dyad k's
    bodies meet at (k + 0.5, 0.5) and join the previous dyad at (k, 1) and (k, 0) (right angles:
    far from any fold); the crank, pinned to the frame at (0, 0.5), is driven. Coordinates are
    exact (`precision`): the file's numbers, not their digits, set the geometry."""
    dyads = max(1, (bodies - 2) // 2)
    out = ['name = "Dyad strip"', "precision = 0", 'space = "planar"', "frame = 1", ""]

    def joint(ident, a, b, x, y, driven=0):
        out.extend(["[[joint]]", f'id = "{ident}"', 'type = "R"', f"bodies = [{a}, {b}]",
                    f"origin = [{x}, {y}]"] + ([f"driven = {driven}"] if driven else []) + [""])

    joint("A0", 1, 2, 0, 0.5, driven=1)
    for k in range(1, dyads + 1):
        a, b = 2 * k + 1, 2 * k + 2
        joint(f"T{k}", 2 if k == 1 else a - 2, a, k, 1)
        joint(f"C{k}", a, b, k + 0.5, 0.5)
        joint(f"B{k}", 1 if k == 1 else b - 2, b, k, 0)
    return "\n".join(out)


def generated(*args):
    """A file `mbsa generate ARGS` writes."""
    return lambda n: subprocess.run([BIN, "generate", *args, "--bodies", str(n)], check=True,
                                    capture_output=True, text=True).stdout


def urdf_chain(links):
    """A serial chain of revolute joints, each link 0.1 along x from its parent."""
    out = ['<robot name="chain">', '<link name="l0"/>']
    for k in range(1, links):
        out.append(f'<link name="l{k}"/>')
        out.append(f'<joint name="j{k}" type="revolute"><parent link="l{k - 1}"/>'
                   f'<child link="l{k}"/><origin xyz="0.1 0 0"/><axis xyz="0 0 1"/>'
                   '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
    out.append("</robot>")
    return "\n".join(out)


def mjcf_chain(links):
    """The tree of urdf_chain written in MJCF (nested bodies)."""
    out = ['<mujoco model="chain">', "<worldbody>"]
    for k in range(1, links):
        out.append(f'<body name="l{k}" pos="0.1 0 0"><joint name="j{k}" axis="0 0 1"/>')
    out.append("</body>" * (links - 1))
    out.append("</worldbody></mujoco>")
    return "\n".join(out)


def laman(points):
    """A Laman framework by Henneberg steps: point k barred to points k-1 and k-2, at random
    (seeded) positions, so 2n - 3 bars and no redundant one."""
    rng = random.Random(1)
    out = []
    for k in range(points):
        out.append(f"[[point]]\nid = {k}\nat = [{rng.random():.6f}, {rng.random():.6f}]\n")
    out.append("[[bar]]\npoints = [0, 1]\n")
    for k in range(2, points):
        out.append(f"[[bar]]\npoints = [{k - 2}, {k}]\n[[bar]]\npoints = [{k - 1}, {k}]\n")
    return 'space = "planar"\nframe = "0-1"\n\n' + "\n".join(out)


# (key, label, size unit, sizes, writer, file suffix, command: the file's path replaces `{}`)
FAMILIES = [
    ("n-four-bar", "N-four-bar, planar, file geometry", "bodies", [100, 1_000, 10_000],
     lambda n: n_four_bar((n - 2) // 2), "toml", ["analyze"]),
    ("n-four-bar-3d", "N-four-bar written in 3D, file geometry", "bodies", [100, 1_000, 10_000],
     lambda n: n_four_bar((n - 2) // 2, planar=False), "toml", ["analyze"]),
    ("urdf", "URDF serial chain (reading)", "links", [1_000, 10_000, 100_000],
     urdf_chain, "urdf", ["mobility"]),
    ("mjcf", "MJCF serial chain (reading)", "links", [1_000, 10_000, 100_000],
     mjcf_chain, "xml", ["mobility"]),
    ("laman", "Laman framework (reading, pebble game)", "points", [1_000, 10_000, 100_000],
     laman, "toml", ["mobility"]),
    ("solve", "dyad strip, crank +1°, group by group", "bodies", [1_000, 10_000, 100_000],
     dyad_strip, "toml", ["solve", "{}", "--set", "A0=1"]),
    ("solve-global", "dyad strip, crank +1°, global (sparse)", "bodies",
     [1_000, 10_000, 100_000], dyad_strip, "toml", ["solve", "{}", "--set", "A0=1", "--global"]),
    ("random-spatial", "random spatial (`generate random --seed 1`)", "bodies",
     [1_000, 100_000, 1_000_000], generated("random", "--seed", "1"), "toml", ["analyze"]),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cap-seconds", type=float, default=120)
    ap.add_argument("--memory-cap-gb", type=int, default=8)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--families", default="")
    ap.add_argument("--write", action="store_true")
    a = ap.parse_args()
    fams = [f for f in FAMILIES if not a.families or f[0] in a.families.split(",")]
    work = tempfile.mkdtemp(prefix="mbsa-cliffs-")
    rows = []
    for key, label, unit, sizes, write, suffix, cmd in fams:
        cells, first, worst = [], None, None
        for n in sizes:
            path = os.path.join(work, f"{key}-{n}.{suffix}")
            with open(path, "w") as f:
                f.write(write(n))
            args = [path if c == "{}" else c for c in cmd] if "{}" in cmd else cmd + [path]
            runs = sorted((run([BIN] + args, a.cap_seconds, a.memory_cap_gb)
                           for _ in range(a.repeat)), key=lambda r: r[1] or 0)
            wall, cpu, rss, code = runs[len(runs) // 2]
            os.remove(path)
            print(f"{label:42} {n:>8} cpu {cpu} wall {wall} rss {rss} -> {code}",
                  file=sys.stderr, flush=True)
            if code == "timeout":
                cells.append(f"> {a.cap_seconds:.0f} s")
                worst = None
                break
            # Exit 1 is an answer for a check, a failure for a solve.
            ok = code == 0 or (code == 1 and cmd[0] != "solve")
            cells.append(f"{fmt_time(cpu)}, {rss:.0f} MB" if ok
                         else f"exit {code}, {fmt_time(cpu)}")
            if not ok:
                continue
            if first is None:
                first = (n, max(cpu, 0.01))
            else:
                r = cpu / (first[1] * n / first[0])
                worst = r if worst is None else max(worst, r)
        cells += ["not run"] * (len(sizes) - len(cells))
        ratio = "–" if worst is None else f"{worst:.2f}"
        shown = " ".join(c for c in cmd if c != "{}")
        rows.append(f"| {label} | `{shown}` | {unit} "
                    + " ".join(f"{n:,}" for n in sizes) + " | " + " | ".join(cells)
                    + f" | {ratio} |")
    head = ["| family | command | sizes | small | middle | large | worst / linear from small |",
            "|---|---|---|---|---|---|---|"]
    print("\n".join(head + rows))
    if a.write:
        doc = os.path.join(ROOT, "docs", "benchmarks.md")
        text = open(doc).read()
        # With --families only those rows are measured: the others keep their cells.
        old = re.search(r"<!-- generated:cliffs -->\n(.*?)<!-- end:cliffs -->", text, flags=re.S)
        by_label = {}
        for line in (old.group(1).splitlines() if old else [])[2:]:
            by_label[line.split(" | ")[0].lstrip("| ")] = line
        for line in rows:
            by_label[line.split(" | ")[0].lstrip("| ")] = line
        order = [f[1] for f in FAMILIES]
        kept = sorted(by_label.items(),
                      key=lambda kv: order.index(kv[0]) if kv[0] in order else len(order))
        table = "\n".join(head + [line for _, line in kept])
        block = f"<!-- generated:cliffs -->\n{table}\n<!-- end:cliffs -->"
        new, k = re.subn(r"<!-- generated:cliffs -->.*?<!-- end:cliffs -->", lambda _: block, text,
                         flags=re.S)
        if k != 1:
            sys.exit("docs/benchmarks.md has no generated:cliffs block")
        open(doc, "w").write(new)


if __name__ == "__main__":
    main()
