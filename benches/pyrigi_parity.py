#!/usr/bin/env python3
"""Side-by-side run of PyRigi and `mbsa rigid` on growing random 2D bar-joint frameworks.

For each size a random graph (seeded) is written as a planar mechanism (every bar a body, every
point of degree >= 2 one revolute joining its bars; bar 1 the frame) and analysed by
  - PyRigi 1.3: Graph.rigid_components(dim=2), and
  - mbsa: `target/release/mbsa rigid --format json FILE` (build with `cargo build --release`).
PyRigi's components are sets of points; they are mapped to sets of bars (the bars with both ends
in the component; one-bar components dropped on both sides) and compared with mbsa's `rigid`.
Prints a markdown table for docs/benchmarks.md on stdout.

Usage: python3 benches/pyrigi_parity.py [sizes...]   (default 50 100 200 500; PyRigi needs
about 0.3, 1.2, 12 and 230 s on these under-braced graphs, so 1000 takes far longer)
"""
import json
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from pyrigi import Graph

MBSA = Path(__file__).resolve().parent.parent / "target" / "release" / "mbsa"


def random_graph(n, m, seed):
    rng = random.Random(seed)
    edges = set()
    while len(edges) < m:
        a, b = rng.sample(range(n), 2)
        edges.add((min(a, b), max(a, b)))
    return sorted(edges)


def toml_of(name, edges):
    lines = [f'name = "{name}"', 'space = "planar"', "frame = 1", ""]
    at = {}
    for i, (a, b) in enumerate(edges):
        at.setdefault(a, []).append(i + 1)
        at.setdefault(b, []).append(i + 1)
    for v in sorted(at):
        if len(at[v]) >= 2:
            lines += ["[[joint]]", f'id = "p{v}"', 'type = "R"', f"bodies = {at[v]}", ""]
    return "\n".join(lines)


def pyrigi_components(edges):
    t = time.perf_counter()
    comps = Graph(edges).rigid_components(dim=2)
    dt = time.perf_counter() - t
    out = []
    for c in comps:
        c = set(c)
        bars = sorted(i + 1 for i, (a, b) in enumerate(edges) if a in c and b in c)
        if len(bars) >= 2:
            out.append(bars)
    return sorted(out), dt


def mbsa_components(path):
    if not MBSA.exists():
        return None, None, "no target/release/mbsa"
    t = time.perf_counter()
    p = subprocess.run([str(MBSA), "rigid", "--method", "counting", "--format", "json", str(path)],
                       capture_output=True, text=True)
    dt = time.perf_counter() - t
    if p.returncode != 0:
        return None, None, (p.stderr.strip().splitlines() or ["failed"])[0]
    r = json.loads(p.stdout)
    comps = sorted(sorted(int(b) for b in c) for c in r["rigid"] if len(c) >= 2)
    return comps, dt, None


def main():
    sizes = [int(s) for s in sys.argv[1:]] or [50, 100, 200, 500]
    sys.setrecursionlimit(100000)
    print("| vertices | bars | PyRigi s | mbsa s | ratio | equal |")
    print("|---:|---:|---:|---:|---:|:---|")
    notes = set()
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            # Just below Laman density (2n - 3) plus a few braces: mixed rigid and flexible.
            m = 2 * n - 3 - n // 10 + n // 25
            edges = random_graph(n, m, seed=n)
            path = Path(tmp) / f"random-{n}.toml"
            path.write_text(toml_of(f"random-{n}", edges))
            want, t_py = pyrigi_components(edges)
            got, t_mb, err = mbsa_components(path)
            if err:
                notes.add(err)
                print(f"| {n} | {m} | {t_py:.3f} | n/a | n/a | n/a |")
            else:
                ratio = t_py / t_mb if t_mb > 0 else float("inf")
                print(f"| {n} | {m} | {t_py:.3f} | {t_mb:.3f} | {ratio:.1f} | {'yes' if got == want else 'NO'} |")
    for note in sorted(notes):
        print(f"\nmbsa not run: {note} (the `mbsa rigid` subcommand is wired by the lead).")
    print("\nmbsa time includes process start and file reading; ratio = PyRigi / mbsa.")


if __name__ == "__main__":
    main()
