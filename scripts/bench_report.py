#!/usr/bin/env python3
"""Turn a benchmark run into the figures of docs/benchmarks.md (standard library only).

Reads the divan output of `cargo bench --bench structure` (OUT/divan.txt), generates mechanism
files with `mbsa generate`, measures the real binary (peak memory with GNU time, end-to-end time
with hyperfine when installed, else a repeated loop), then rewrites the blocks between
`<!-- generated:NAME -->` and `<!-- end:NAME -->` in the docs file and writes the growth plot
(SVG, hand-written: no plotting library needed). Run through scripts/bench.sh.
"""

import argparse
import json
import math
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import time

FAMILIES = ["assur2A", "assur2B", "assur3dA", "assur3dB", "stewart", "random3d", "random2d"]
FAMILY_TEXT = {
    "assur2A": "planar Assur II (triads), A",
    "assur2B": "planar Assur II (triads), B",
    "assur3dA": "spatial Assur II (U joints), A",
    "assur3dB": "spatial Assur II (U joints), B",
    "stewart": "spatial Stewart stack",
    "random3d": "random spatial",
    "random2d": "random planar",
}
SIZES = [1_000, 10_000, 100_000, 1_000_000]
E2E_BODIES = 100_000
TABLE16 = [("I-2", 1, 2), ("I-4", 1, 4), ("I-8", 1, 8), ("II-2", 2, 2), ("II-4", 2, 4),
           ("II-8", 2, 8), ("III-2", 3, 2), ("III-4", 3, 4)]
# The paper's Table 16 (MATLAB, i7-8550U), quoted from docs/benchmarks.md of the brief:
# case -> (bodies, SGs A, t A (s), SGs B, t B (s)); None where the paper's code failed.
PAPER = {
    "I-2": (6, 3, "0.905", 2, "0.845"),
    "I-4": (10, 5, "0.923", 3, "0.927"),
    "I-8": (18, 9, "0.988", 3, "4.650"),
    "II-2": (10, 3, "0.914", 1, "0.908"),
    "II-4": (18, 5, "1.160", 2, "5.394"),
    "II-8": (34, 9, "2.331", None, "failed"),
    "III-2": (14, 3, "1.042", 1, "1.390"),
    "III-4": (26, 5, "5.225", 1, "70,940 (19.7 h)"),
}
UNITS = {"ns": 1e-9, "µs": 1e-6, "us": 1e-6, "ms": 1e-3, "s": 1.0, "m": 60.0, "h": 3600.0}


def rank_feasible(family, bodies):
    """Mirror of benches/structure.rs: the rank check runs on every family (blocks above its
    dense-size cap are listed as unchecked instead)."""
    return True


def count_feasible(family, bodies):
    """Mirror of benches/structure.rs: random spatial count-only grows superlinearly."""
    return not (family == "random3d" and bodies > 100_000)


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw).stdout


def parse_seconds(text):
    m = re.match(r"\s*([\d.]+)\s*(ns|µs|us|ms|s|m|h)\s*$", text)
    return float(m.group(1)) * UNITS[m.group(2)] if m else None


def parse_divan(path):
    """Median seconds by path (`table16/count_only/I-2A`), plus the preamble lines."""
    medians, checks, probes = {}, {}, {}
    stack = []
    in_tree = False
    with open(path, encoding="utf-8") as f:
        for line in f:
            line = line.rstrip("\n")
            m = re.match(r"check (\S+): (\d+) bodies, (\d+) / (\S+) SGs, largest (\d+), (\w+)", line)
            if m:
                checks[m.group(1)] = {"bodies": int(m.group(2)), "sgs": int(m.group(3)),
                                      "largest": int(m.group(5)), "status": m.group(6)}
                continue
            m = re.match(r"probe (\S+): finished in ([\d.]+) s, (\d+) SGs", line)
            if m:
                probes[m.group(1)] = float(m.group(2))
                continue
            m = re.match(r"probe (\S+): did not finish within ([\d.]+) s", line)
            if m:
                probes[m.group(1)] = None
                probes["budget"] = float(m.group(2))
                continue
            if re.match(r"^\S+\s+fastest\s+│", line):
                in_tree = True
                continue
            if not in_tree or "│" not in line:
                continue
            # The tree's own `│` looks like the column separator: columns are the last five.
            parts = line.split("│")
            if len(parts) < 6:
                continue
            cells = ["│".join(parts[:-5]), *parts[-5:]]
            m = re.match(r"^([│├╰─ ]*)(\S+)(.*)$", cells[0])
            if not m:
                continue
            depth = len(m.group(1)) // 3
            stack = stack[: depth - 1] + [m.group(2)]
            if len(cells) >= 3:
                median = parse_seconds(cells[2])
                if median is not None:
                    medians["/".join(stack)] = median
    return medians, checks, probes


def fmt_time(s):
    if s is None:
        return "–"
    def sig(v):
        return f"{v:.3g}" if v < 1000 else f"{v:,.0f}"
    if s < 1e-3:
        return f"{sig(s * 1e6)} µs"
    if s < 1:
        return f"{sig(s * 1e3)} ms"
    return f"{sig(s)} s"


def machine(bin_path):
    lines = []
    try:
        cpu = run(["lscpu"])
        keep = ("Model name", "CPU(s)", "Thread(s) per core", "CPU max MHz", "L2 cache", "L3 cache")
        for l in cpu.splitlines():
            if l.split(":")[0].strip() in keep:
                lines.append("- " + re.sub(r"\s+", " ", l.strip()))
    except (OSError, subprocess.CalledProcessError):
        lines.append(f"- CPU: {platform.processor() or 'unknown'}")
    try:
        with open("/proc/meminfo", encoding="utf-8") as f:
            kb = int(re.search(r"MemTotal:\s+(\d+)", f.read()).group(1))
        lines.append(f"- Memory: {kb / 1024 / 1024:.1f} GiB")
    except (OSError, AttributeError):
        pass
    lines.append(f"- OS: {platform.system()} {platform.release()}")
    lines.append("- " + run(["rustc", "--version"]).strip() + " (release profile, no debug information)")
    if shutil.which("hyperfine"):
        lines.append("- " + run(["hyperfine", "--version"]).strip())
    lines.append(f"- Run on {time.strftime('%Y-%m-%d')}")
    return "\n".join(lines)


def generate(bin_path, family, bodies, files):
    path = os.path.join(files, f"{family}-{bodies}.toml")
    if os.path.exists(path):
        return path
    if family.startswith("assur"):
        args = ["assur", "--class", "2", "--groups", str(math.ceil((bodies - 2) / 4)),
                "--variant", family[-1], "--seed", "364"]
        if "3d" in family:
            args.append("--spatial")
    elif family == "stewart":
        args = ["stewart", "--stages", str(math.ceil((bodies - 1) / 13))]
    else:
        args = ["random", "--bodies", str(bodies), "--seed", "1"]
        if family == "random2d":
            args.append("--planar")
    with open(path + ".tmp", "w", encoding="utf-8") as f:
        subprocess.run([bin_path, "generate", *args], check=True, stdout=f)
    os.replace(path + ".tmp", path)
    return path


def analyze_cmd(bin_path, path, count_only):
    cmd = [bin_path, "analyze", path, "--format", "json"]
    return cmd + ["--count-only"] if count_only else cmd


def peak_memory(cmd):
    """(max RSS in MB, wall seconds) with GNU time."""
    r = subprocess.run(["timeout", "300", "/usr/bin/time", "-v", *cmd], stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True, check=False)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr)
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", r.stderr)
    secs = None
    if wall:
        parts = [float(p) for p in wall.group(1).split(":")]
        secs = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
    if r.returncode != 0:
        return None, None
    return (int(rss.group(1)) / 1024 if rss else None), secs


def time_command(cmd, runs, out_dir, tag):
    """Mean and standard deviation of wall time, hyperfine when available."""
    if shutil.which("hyperfine"):
        export = os.path.join(out_dir, f"hyperfine-{tag}.json")
        shell_cmd = " ".join(cmd) + " > /dev/null"
        subprocess.run(["hyperfine", "--warmup", "1", "--runs", str(runs), "--style", "none",
                        "--export-json", export, shell_cmd], check=True,
                       stdout=subprocess.DEVNULL)
        with open(export, encoding="utf-8") as f:
            r = json.load(f)["results"][0]
        return r["mean"], r["stddev"] or 0.0, "hyperfine"
    times = []
    for _ in range(runs + 1):
        t = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        times.append(time.perf_counter() - t)
    times = times[1:]  # the first run warms the page cache
    return statistics.mean(times), statistics.pstdev(times), "loop"


def table16_block(medians, checks, probes):
    rows = ["| case | bodies | SGs paper | SGs ours | largest SG | paper MATLAB t | "
            "flow count-only | flow default | exhaustive (count-only) | exhaustive / flow |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for name, _, _ in TABLE16:
        bodies, sa, ta, sb, tb = PAPER[name]
        for v, sgs, t in (("A", sa, ta), ("B", sb, tb)):
            case = f"{name}{v}"
            c = checks.get(case, {})
            flow_c = medians.get(f"table16/count_only/{case}")
            flow_r = medians.get(f"table16/rank_check/{case}")
            ex = medians.get(f"exhaustive/count_only/{case}")
            note = ""
            if ex is None and probes.get(case) is not None:
                ex, note = probes[case], " (1 run)"
            if ex is None:
                budget = probes.get("budget")
                ex_text = f"> {budget:.0f} s (budget)" if budget else "–"
                ratio = "–"
            else:
                ex_text = fmt_time(ex) + note
                r = ex / flow_c if flow_c else None
                ratio = "–" if r is None else (f"{r:,.0f}×" if r >= 100 else f"{r:.1f}×")
            rows.append(
                f"| {case} | {c.get('bodies', bodies)} | {sgs if sgs is not None else '– (failed)'} "
                f"| {c.get('sgs', '?')} | {c.get('largest', '?')} | {t if '(' in t or t == 'failed' else t + ' s'} "
                f"| {fmt_time(flow_c)} | {fmt_time(flow_r)} | {ex_text} | {ratio} |")
    worst = max((medians.get(f"table16/{mode}/{n}{v}") or 0.0)
                for n, _, _ in TABLE16 for v in "AB" for mode in ("count_only", "rank_check"))
    verdict = "met" if worst < 1e-3 else "MISSED"
    rows.append("")
    rows.append(f"Slowest Table 16 analysis (either mode): {fmt_time(worst)}; target < 1 ms: "
                f"**{verdict}**.")
    return "\n".join(rows)


def scale_block(medians):
    rows = ["| family | bodies | count-only | default (rank check) | default per body |",
            "|---|---|---|---|---|"]
    for fam in FAMILIES:
        for n in SIZES:
            c = medians.get(f"scale/count_only/{fam}/{n}")
            r = medians.get(f"scale/rank_check/{fam}/{n}")
            r_text = fmt_time(r) if r is not None else (
                "out of reach" if not rank_feasible(fam, n) else "see peak memory")
            per = fmt_time(r / n) if r else "–"
            c_text = fmt_time(c) if c is not None else (
                "not run" if not count_feasible(fam, n) else "–")
            rows.append(f"| {FAMILY_TEXT[fam]} | {n:,} | {c_text} | {r_text} | {per} |")
    return "\n".join(rows)


def pipeline_block(medians):
    rows = ["| family (10^5 bodies) | `format::load` | analyze count-only | analyze default | "
            "`report::json` |", "|---|---|---|---|---|"]
    for fam in FAMILIES:
        key = f"{fam}/{E2E_BODIES}"
        r = medians.get(f"pipeline/analyze_rank_check/{key}")
        rows.append(f"| {FAMILY_TEXT[fam]} | {fmt_time(medians.get(f'pipeline/load/{key}'))} "
                    f"| {fmt_time(medians.get(f'pipeline/analyze_count_only/{key}'))} "
                    f"| {fmt_time(r) if r is not None else 'not run'} "
                    f"| {fmt_time(medians.get(f'pipeline/json/{key}'))} |")
    return "\n".join(rows)


def svg_plot(medians, path):
    """Log-log plot of analysis time against bodies, one colour per family."""
    w, h, left, right, top, bottom = 820, 460, 80, 270, 20, 50
    colours = ["#1f77b4", "#d62728", "#17becf", "#e377c2", "#2ca02c", "#9467bd", "#ff7f0e"]
    pts = [v for k, v in medians.items() if k.startswith("scale/") and v > 0]
    if not pts:
        return
    ymin = 10 ** math.floor(math.log10(min(pts)))
    ymax = 10 ** math.ceil(math.log10(max(pts)))
    xmin, xmax = 1e3, 1e6

    def x(v):
        return left + (math.log10(v) - math.log10(xmin)) / (math.log10(xmax) - math.log10(xmin)) * (w - left - right)

    def y(v):
        return h - bottom - (math.log10(v) - math.log10(ymin)) / (math.log10(ymax) - math.log10(ymin)) * (h - top - bottom)

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>']
    for e in range(3, 7):
        out.append(f'<line x1="{x(10**e):.1f}" y1="{top}" x2="{x(10**e):.1f}" y2="{h-bottom}" stroke="#ddd"/>')
        out.append(f'<text x="{x(10**e):.1f}" y="{h-bottom+18}" text-anchor="middle">10^{e}</text>')
    e = math.log10(ymin)
    while e <= math.log10(ymax) + 1e-9:
        v = 10 ** e
        out.append(f'<line x1="{left}" y1="{y(v):.1f}" x2="{w-right}" y2="{y(v):.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{left-6}" y="{y(v)+4:.1f}" text-anchor="end">{fmt_time(v)}</text>')
        e += 1
    out.append(f'<rect x="{left}" y="{top}" width="{w-left-right}" height="{h-top-bottom}" fill="none" stroke="#333"/>')
    out.append(f'<text x="{(left + w - right) / 2}" y="{h-10}" text-anchor="middle">bodies</text>')
    out.append(f'<text x="16" y="{(top + h - bottom) / 2}" text-anchor="middle" '
               f'transform="rotate(-90 16 {(top + h - bottom) / 2})">analysis time (median)</text>')
    legend_y = top + 10
    for fam, col in zip(FAMILIES, colours):
        for mode, dash in (("count_only", "5,4"), ("rank_check", "")):
            series = [(n, medians.get(f"scale/{mode}/{fam}/{n}")) for n in SIZES]
            series = [(n, v) for n, v in series if v]
            if not series:
                continue
            d = " ".join(f"{x(n):.1f},{y(v):.1f}" for n, v in series)
            style = f' stroke-dasharray="{dash}"' if dash else ""
            out.append(f'<polyline points="{d}" fill="none" stroke="{col}" stroke-width="2"{style}/>')
            for n, v in series:
                out.append(f'<circle cx="{x(n):.1f}" cy="{y(v):.1f}" r="3" fill="{col}"/>')
            label = FAMILY_TEXT[fam] + (" (count-only)" if dash else "")
            lx = w - right + 10
            out.append(f'<line x1="{lx}" y1="{legend_y}" x2="{lx+22}" y2="{legend_y}" stroke="{col}" stroke-width="2"{style}/>')
            out.append(f'<text x="{lx+26}" y="{legend_y+4}" font-size="10">{label}</text>')
            legend_y += 16
    out.append("</svg>")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")


def replace_block(text, name, body):
    pattern = re.compile(rf"(<!-- generated:{name} -->\n).*?(<!-- end:{name} -->)", re.S)
    if not pattern.search(text):
        print(f"warning: no block `{name}` in the docs file", file=sys.stderr)
        return text
    return pattern.sub(lambda m: m.group(1) + body.rstrip() + "\n" + m.group(2), text)


ANALYSES = [
    ("transform_all/default/rotor", "`mbsa transform`: every placement, analysed in full", "rotor", "< 1 s", 1.0),
    ("transform_all/count_only/rotor", "the same, `--count-only`", "rotor", "", None),
    ("transform_all/default/micro-manipulator", "`mbsa transform`: every placement, analysed in full",
     "micro-manipulator", "< 10 s", 10.0),
    ("transform_all/count_only/micro-manipulator", "the same, `--count-only`", "micro-manipulator", "", None),
    ("pebble_game/framework_10k_bars/degree3", "pebble game", "10^4 bars, mean point degree 3", "", None),
    ("pebble_game/framework_10k_bars/degree4", "pebble game", "10^4 bars, degree 4 (threshold)", "< 1 s", 1.0),
    ("pebble_game/framework_10k_bars/degree6", "pebble game", "10^4 bars, degree 6", "", None),
    ("pebble_game/random_planar_10k_bodies", "pebble game", "random planar mechanism, 10^4 bodies", "", None),
    ("geometric_rigidity/double_banana", "geometric rigidity", "double banana (file geometry)", "< 10 ms", 0.01),
    ("geometric_rigidity/framework_996_bars", "geometric rigidity", "Henneberg framework, 996 bars", "< 2 s", 2.0),
]


def analyses_block(medians):
    rows = ["| analysis | input | median | target |", "|---|---|---:|---|"]
    for key, what, inp, target, limit in ANALYSES:
        t = medians.get(key)
        verdict = ""
        if limit is not None and t is not None:
            verdict = ": met" if t < limit else ": **missed**"
        rows.append(f"| {what} | {inp} | {fmt_time(t)} | {target}{verdict} |")
    return "\n".join(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--bin", default="target/release/mbsa")
    ap.add_argument("--out", default="target/bench")
    ap.add_argument("--docs", default="docs/benchmarks.md")
    ap.add_argument("--runs", type=int, default=5, help="end-to-end runs per command")
    ap.add_argument("--max-bodies", type=int, default=1_000_000,
                    help="largest size measured through the binary")
    args = ap.parse_args()
    files = os.path.join(args.out, "files")
    os.makedirs(files, exist_ok=True)

    medians, checks, probes = parse_divan(os.path.join(args.out, "divan.txt"))
    blocks = {"machine": machine(args.bin),
              "table16": table16_block(medians, checks, probes),
              "scale": scale_block(medians),
              "pipeline": pipeline_block(medians)}
    other = os.path.join(args.out, "divan-analyses.txt")
    if os.path.exists(other):
        blocks["analyses"] = analyses_block(parse_divan(other)[0])

    # Peak memory and wall time through the binary, every family and size.
    rows = ["| family | bodies | file size | mode | max RSS | wall time |", "|---|---|---|---|---|---|"]
    for fam in FAMILIES:
        for n in [s for s in SIZES if s <= args.max_bodies and count_feasible(fam, s)]:
            path = generate(args.bin, fam, n, files)
            count_only = not rank_feasible(fam, n)
            rss, wall = peak_memory(analyze_cmd(args.bin, path, count_only))
            size = os.path.getsize(path) / 1e6
            mode = "count-only" if count_only else "default"
            rss_text = f"{rss:,.0f} MB" if rss is not None else "failed"
            rows.append(f"| {FAMILY_TEXT[fam]} | {n:,} | {size:.1f} MB | {mode} | {rss_text} | "
                        f"{fmt_time(wall)} |")
            print(f"memory {fam} {n}: {rss_text}, {fmt_time(wall)}", file=sys.stderr)
    blocks["memory"] = "\n".join(rows)

    # End-to-end at 10^5 bodies: the floor (start + parse + mobility), count-only, default.
    rows = ["| family (10^5 bodies) | floor: `mbsa mobility` | `analyze --count-only` | "
            "`analyze` (default) | < 1 s | peak RSS (default) | < 500 MB |",
            "|---|---|---|---|---|---|---|"]
    tool = "loop"
    for fam in FAMILIES:
        path = generate(args.bin, fam, E2E_BODIES, files)
        floor, _, tool = time_command([args.bin, "mobility", path, "--format", "json"],
                                      args.runs, args.out, f"{fam}-floor")
        co, co_sd, _ = time_command(analyze_cmd(args.bin, path, True), args.runs, args.out,
                                    f"{fam}-count-only")
        if rank_feasible(fam, E2E_BODIES):
            de, de_sd, _ = time_command(analyze_cmd(args.bin, path, False), args.runs, args.out,
                                        f"{fam}-default")
            rss, _ = peak_memory(analyze_cmd(args.bin, path, False))
            de_text = f"{fmt_time(de)} ± {fmt_time(de_sd)}"
        else:
            de, de_text = None, "not run (rank check out of reach)"
            rss, _ = peak_memory(analyze_cmd(args.bin, path, True))
        worst = de if de is not None else co
        rows.append(f"| {FAMILY_TEXT[fam]} | {fmt_time(floor)} | {fmt_time(co)} ± {fmt_time(co_sd)} "
                    f"| {de_text} | {'yes' if worst < 1 else '**no**'} | "
                    f"{f'{rss:,.0f} MB' if rss is not None else 'failed'} | "
                    f"{'yes' if rss is not None and rss < 500 else '**no**'} |")
        print(f"end-to-end {fam}: floor {fmt_time(floor)}, count-only {fmt_time(co)}, "
              f"default {fmt_time(de)}", file=sys.stderr)
    rows.append("")
    rows.append(f"Timed with {tool}, {args.runs} runs after one warm-up; mean ± standard deviation.")
    blocks["endtoend"] = "\n".join(rows)

    svg = os.path.join(os.path.dirname(args.docs), "benchmarks-growth.svg")
    svg_plot(medians, svg)
    with open(args.docs, encoding="utf-8") as f:
        text = f.read()
    for name, body in blocks.items():
        text = replace_block(text, name, body)
    with open(args.docs, "w", encoding="utf-8") as f:
        f.write(text)
    for name, body in blocks.items():
        print(f"\n## {name}\n{body}")


if __name__ == "__main__":
    main()
