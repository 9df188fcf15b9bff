#!/usr/bin/env python3
"""The table of scripts/cluster_bench.sh from its results.tsv: per configuration and total spp,
the median over repeats of the wall seconds of all its processes (and of the merge), relMSE and
trimmed relMSE; then each configuration's time to reach the relMSE that `rll-1` reaches at the
largest budget, interpolated on the log-log line through its two nearest budgets (relMSE falls
about as 1/time), as a ratio to rll-1's."""
import csv, math, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
med = lambda xs: statistics.median(xs) if xs else float("nan")
train = [float(r["seconds"]) for r in rows if r["config"] == "train"]
configs = ["tree-1", "tree-4", "rll-1", "rll-4-cold", "rll-4-warm"]
totals = sorted({int(r["total_spp"]) for r in rows if r["config"] != "train"})
cell = {}
for c in configs:
    for t in totals:
        rs = [r for r in rows if r["config"] == c and int(r["total_spp"]) == t]
        if not rs: continue
        cell[c, t] = {k: med([float(r[k]) for r in rs]) for k in
                      ["seconds", "render_seconds", "merge_seconds", "relmse", "trimmed_relmse"]}
print("| config | total spp | seconds (all processes) | of which rendering | merge | relMSE | trimmed relMSE |")
print("|---|---|---|---|---|---|---|")
for c in configs:
    for t in totals:
        if (c, t) not in cell: continue
        x = cell[c, t]
        merge = f"{x['merge_seconds']:.2f}" if c.endswith("-4") or "-4-" in c else "—"
        print(f"| {c} | {t} | {x['seconds']:.2f} | {x['render_seconds']:.2f} | {merge} | {x['relmse']:.3g} | {x['trimmed_relmse']:.3g} |")
if train:
    print(f"\nTraining render of the warm start (once per scene and resolution): {med(train):.2f} s (median).")

def time_to(c, target):
    pts = sorted((cell[c, t]["seconds"], cell[c, t]["relmse"]) for t in totals if (c, t) in cell)
    pts = [(s, e) for s, e in pts if s > 0 and e > 0]
    if len(pts) < 2: return float("nan")
    # The two budgets whose errors bracket the target (or the nearest two), log-log line.
    best = min(range(len(pts) - 1), key=lambda i: 0 if (pts[i][1] - target) * (pts[i + 1][1] - target) <= 0
               else min(abs(math.log(pts[i][1] / target)), abs(math.log(pts[i + 1][1] / target))))
    (s0, e0), (s1, e1) = pts[best], pts[best + 1]
    slope = (math.log(e1) - math.log(e0)) / (math.log(s1) - math.log(s0))
    return math.exp(math.log(s0) + (math.log(target) - math.log(e0)) / slope)

if ("rll-1", totals[-1]) in cell:
    target = cell["rll-1", totals[-1]]["relmse"]
    base = time_to("rll-1", target)
    print(f"\nTime to relMSE {target:.3g} (rll-1's at {totals[-1]} spp):\n")
    print("| config | seconds | / rll-1 |")
    print("|---|---|---|")
    for c in configs:
        t = time_to(c, target)
        print(f"| {c} | {t:.2f} | {t / base:.2f} |")
