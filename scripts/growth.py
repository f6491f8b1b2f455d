#!/usr/bin/env python3
"""Every command at 10^3..10^6 bodies: wall time, user CPU and peak memory, with growth exponents.

The table of docs/benchmarks.md, "Every command from 10^3 to 10^6 bodies"). For each family
and size the mechanism is generated once (`mbsa generate`, TOML), then each command runs through
the release binary under `/usr/bin/time` with a CPU-time cap and an address-space cap. Output goes to
stdout as markdown; with --write the table replaces the block between the markers
`<!-- generated:commands -->` and `<!-- end:commands -->` of docs/benchmarks.md.

A command that exceeds the cap at one size is not run at the larger sizes of that family (the
table says so). The growth exponent is the least-squares slope of log(user CPU) against
log(bodies) over the sizes whose CPU is at least 20 ms (below that, process start dominates).

Usage: python3 scripts/growth.py [--max 1000000] [--cap-seconds 60] [--memory-cap-gb 8] [--write]
       [--families a,b] [--commands "mobility,rigid geometric"] [--repeat 3]

With --repeat N each cell is the run of median CPU time out of N (the machine's other load moves
single runs by 10-40 %, mostly in system time).
"""

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target", "release", "mbsa")

# (key, label, generator arguments for a given number of bodies)
FAMILIES = [
    ("assur-planar", "planar Assur II (A)",
     lambda n: ["assur", "--class", "2", "--groups", str(max(1, (n - 2) // 4))]),
    ("assur-spatial", "spatial Assur II (A, U joints)",
     lambda n: ["assur", "--class", "2", "--groups", str(max(1, (n - 2) // 4)), "--spatial"]),
    ("random-spatial", "random spatial", lambda n: ["random", "--bodies", str(n), "--seed", "1"]),
    ("random-planar", "random planar",
     lambda n: ["random", "--bodies", str(n), "--planar", "--seed", "1"]),
    ("chain", "serial chain (spatial R)", lambda n: ["chain", "--bodies", str(n)]),
    ("star", "star (spatial R)", lambda n: ["star", "--bodies", str(n)]),
    ("hub", "shared S joint", lambda n: ["star", "--bodies", str(n), "--joint", "S", "--shared"]),
]

COMMANDS = [
    ("mobility", ["mobility"]),
    ("analyze", ["analyze"]),
    ("analyze --count-only", ["analyze", "--count-only"]),
    ("transform --limit 100", ["transform", "--limit", "100", "--format", "json"]),
    ("rigid counting", ["rigid", "--method", "counting"]),
    ("rigid geometric", ["rigid", "--method", "geometric"]),
    ("dot", ["dot"]),
]

SIZES = [1_000, 10_000, 100_000, 1_000_000]
MEMORY_CAP_GB = 8  # address space, not resident memory (--memory-cap-gb)


def run(args, cap_seconds, memory_cap_gb=MEMORY_CAP_GB, stdout=subprocess.DEVNULL):
    """Run under /usr/bin/time; return (wall s, user s, peak RSS MB, exit code or 'timeout')."""
    fmt = "%e %U %S %M %x"
    with tempfile.NamedTemporaryFile("r", suffix=".time") as t:
        # The cap is on CPU seconds (RLIMIT_CPU), so a busy machine does not cut a run short;
        # the wall-clock timeout only catches a process that waits forever.
        cmd = ["/usr/bin/time", "-f", fmt, "-o", t.name, "prlimit",
               f"--as={memory_cap_gb * 1024 ** 3}", f"--cpu={int(cap_seconds)}", "--"] + args
        try:
            subprocess.run(cmd, stdout=stdout, stderr=subprocess.DEVNULL,
                           timeout=10 * cap_seconds, check=False)
        except subprocess.TimeoutExpired:
            return None, None, None, "timeout"
        fields = t.read().split()
    # `time` writes "Command exited with non-zero status N" before the numbers on failure.
    wall, user, system, rss, code = fields[-5:]
    cpu = float(user) + float(system)
    # Killed by SIGXCPU at the cap: `time` says "Command terminated by signal 24".
    if "signal" in fields or cpu >= cap_seconds - 0.05:
        return None, None, None, "timeout"
    return float(wall), cpu, int(rss) / 1024, int(code)


def measure(args, a):
    """Run `a.repeat` times (stopping at the first failure or cap); the run of median CPU."""
    runs = []
    for _ in range(a.repeat):
        r = run(args, a.cap_seconds, a.memory_cap_gb)
        runs.append(r)
        if r[3] not in (0, 1):
            return r
    runs.sort(key=lambda r: r[1])
    return runs[len(runs) // 2]


def fmt_time(s):
    if s is None:
        return "–"
    if s < 0.1:
        return f"{s * 1000:.0f} ms" if s >= 0.01 else "< 10 ms"
    if s < 1:
        return f"{s * 1000:.0f} ms"
    return f"{s:.2f} s" if s < 10 else f"{s:.1f} s"


def slope(points):
    pts = [(math.log(n), math.log(t)) for n, t in points if t is not None and t >= 0.02]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    den = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / den if den else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--max", type=int, default=1_000_000)
    ap.add_argument("--cap-seconds", type=float, default=60)
    ap.add_argument("--write", action="store_true")
    ap.add_argument("--families", default="")
    ap.add_argument("--commands", default="")
    ap.add_argument("--memory-cap-gb", type=int, default=MEMORY_CAP_GB)
    ap.add_argument("--repeat", type=int, default=1,
                    help="runs per cell; the cell is the run of median CPU time")
    a = ap.parse_args()
    fams = [f for f in FAMILIES if not a.families or f[0] in a.families.split(",")]
    cmds = [c for c in COMMANDS if not a.commands or c[0] in a.commands.split(",")]
    sizes = [n for n in SIZES if n <= a.max]
    rows = []
    work = tempfile.mkdtemp(prefix="mbsa-growth-")
    started = time.time()
    for key, label, gen in fams:
        capped = set()
        results = {c[0]: [] for c in cmds}
        for n in sizes:
            path = os.path.join(work, f"{key}-{n}.toml")
            with open(path, "w") as f:
                subprocess.run([BIN, "generate"] + gen(n), stdout=f, check=True)
            for name, args in cmds:
                if name in capped:
                    results[name].append((n, None, None, "not run", None))
                    continue
                wall, cpu, rss, code = measure([BIN] + args + [path], a)
                print(f"{label:32} {n:>9} {name:24} wall {wall} cpu {cpu} rss {rss} -> {code}",
                      file=sys.stderr, flush=True)
                if code == "timeout" or (cpu is not None and cpu > a.cap_seconds / 4):
                    capped.add(name)
                results[name].append((n, cpu, rss, code, wall))
            os.remove(path)
        for name, _ in cmds:
            pts = results[name]
            cells = []
            for n, cpu, rss, code, *wall in pts:
                if code == "not run":
                    cells.append("not run")
                elif code == "timeout":
                    cells.append(f"> {a.cap_seconds:.0f} s")
                elif code not in (0, 1):
                    cells.append(f"exit {code}, {fmt_time(cpu)}")
                elif wall and wall[0] is not None and cpu >= 1 and wall[0] < 0.8 * cpu:
                    # Ran on more than one core: the wall time is what the user waits.
                    cells.append(f"{fmt_time(cpu)} ({fmt_time(wall[0])} wall), {rss:.0f} MB")
                else:
                    cells.append(f"{fmt_time(cpu)}, {rss:.0f} MB")
            k = slope([(n, cpu) for n, cpu, _, code, _ in pts if code in (0, 1)])
            rows.append((label, name, cells, "–" if k is None else f"{k:.2f}"))
    header = "| family | command | " + " | ".join(f"{n:,}" for n in sizes) + " | exponent |"
    sep = "|---|---|" + "---|" * len(sizes) + "---|"
    lines = [header, sep]
    for label, name, cells, k in rows:
        lines.append(f"| {label} | {name} | " + " | ".join(cells) + f" | {k} |")
    table = "\n".join(lines)
    print(table)
    print(f"(measured in {time.time() - started:.0f} s)", file=sys.stderr)
    if a.write:
        doc = os.path.join(ROOT, "docs", "benchmarks.md")
        text = open(doc).read()
        if a.families or a.commands:
            # A partial run replaces its own rows and keeps the others of the table.
            old = re.search(r"<!-- generated:commands -->\n(.*?)\n<!-- end:commands -->", text,
                            flags=re.S)
            if old:
                fresh = {tuple(c.strip() for c in l.split("|")[1:3]): l for l in lines[2:]}
                kept = old.group(1).split("\n")
                merged = [fresh.pop(tuple(c.strip() for c in l.split("|")[1:3]), l)
                          for l in kept]
                table = "\n".join(merged + list(fresh.values()))
        block = f"<!-- generated:commands -->\n{table}\n<!-- end:commands -->"
        new, k = re.subn(r"<!-- generated:commands -->.*?<!-- end:commands -->", block, text,
                         flags=re.S)
        if k != 1:
            sys.exit("docs/benchmarks.md has no generated:commands block")
        open(doc, "w").write(new)


if __name__ == "__main__":
    main()
