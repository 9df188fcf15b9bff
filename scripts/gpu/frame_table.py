#!/usr/bin/env python3
"""The tables of bench/RESULTS.md's "GPU frame times" (issue 43) from scripts/gpu-check.sh's
measurements: a timings file with one line per render,

    scene<TAB>sampler<TAB>depth<TAB>spp<TAB>repeat<TAB>seconds<TAB>stats.json

(seconds: the render's own time from --stats, set-up excluded), and `rll interactive --stats`
files named frames-SCENE-SAMPLER-dDEPTH.json. Prints markdown:

- one row per scene, sampler and depth: ms per 1080p spp as pbrt-v4 measures it, (time at 256
  spp - time at 64 spp) / 192, the median over the repeats of each repeat's difference; the two
  medians it comes from; pbrt-v4's time on the same scene and depth (../shared/GPU.md, H100) and
  whether the goal holds (power at most pbrt-v4's power, rll at most pbrt-v4's bvh); the
  synchronisations per pass and allocations after the first pass of the 256-spp render;
- RLL's overhead over power per scene and depth (goal: at most 1.5 ms at depth 5);
- the per-stage medians of interactive's frames (ms).

Usage: frame_table.py TIMINGS [INTERACTIVE_JSON ...]
"""
import json
import os
import re
import statistics
import sys

# pbrt-v4 on an H100, ms per 1080p spp (../shared/GPU.md): (scene, depth) -> (bvh, power).
PBRT = {
    ("cornell-boxes-room", 1): (11.98, 11.80),
    ("cornell-boxes-room", 5): (24.79, 23.15),
    ("arch-interior", 1): (10.57, 10.64),
    ("arch-interior", 5): (20.48, 20.26),
}
STAGES = ["camera", "closest_hit", "emission", "nee_sample", "shadow", "nee_finish", "rewards",
          "bsdf_sample", "accumulate", "end_pass"]


def fail(msg):
    print(f"frame_table.py: {msg}", file=sys.stderr)
    sys.exit(1)


def read_timings(path):
    runs = {}  # (scene, sampler, depth) -> {spp: {repeat: (seconds, stats)}}
    with open(path) as f:
        for n, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line or line.startswith("#"):
                continue
            parts = line.split("\t")
            if len(parts) < 6:
                fail(f"{path}:{n}: expected scene, sampler, depth, spp, repeat, seconds[, stats]")
            scene, sampler = parts[0], parts[1]
            try:
                depth, spp, repeat = int(parts[2]), int(parts[3]), int(parts[4])
                seconds = float(parts[5])
            except ValueError:
                fail(f"{path}:{n}: depth, spp and repeat must be integers, seconds a number")
            stats = parts[6] if len(parts) > 6 else ""
            runs.setdefault((scene, sampler, depth), {}).setdefault(spp, {})[repeat] = (seconds,
                                                                                      stats)
    return runs


def device_work(stats_path):
    """Synchronisations per pass (the most of any pass) and allocations after the first pass."""
    if not stats_path or not os.path.exists(stats_path):
        return "", ""
    with open(stats_path) as f:
        work = json.load(f).get("device_work", [])
    if not work:
        return "", ""
    return str(max(w["syncs"] for w in work)), str(sum(w["allocations"] for w in work[1:]))


def order(key):
    """Scenes and samplers in the issue's order (others after, by name), then depth."""
    scene, sampler, depth = key
    scenes = ["cornell-boxes-room", "arch-interior"]
    samplers = ["power", "tree", "rll"]
    return (scenes.index(scene) if scene in scenes else len(scenes), scene,
            samplers.index(sampler) if sampler in samplers else len(samplers), sampler, depth)


def frame_rows(runs):
    out = ["| scene | sampler | depth | ms per 1080p spp | s at 64 spp | s at 256 spp | "
           "pbrt-v4 ms (bvh / power) | goal | syncs per pass | allocations after pass 1 |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    ms_of = {}
    for (scene, sampler, depth), by_spp in sorted(runs.items(), key=lambda kv: order(kv[0])):
        if 64 not in by_spp or 256 not in by_spp:
            out.append(f"| {scene} | {sampler} | {depth} | (missing 64 or 256 spp) | | | | | | |")
            continue
        repeats = sorted(set(by_spp[64]) & set(by_spp[256]))
        if not repeats:
            out.append(f"| {scene} | {sampler} | {depth} | (no repeat has both) | | | | | | |")
            continue
        diffs = [(by_spp[256][r][0] - by_spp[64][r][0]) / 192 * 1e3 for r in repeats]
        ms = statistics.median(diffs)
        ms_of[(scene, sampler, depth)] = ms
        t64 = statistics.median(by_spp[64][r][0] for r in repeats)
        t256 = statistics.median(by_spp[256][r][0] for r in repeats)
        pbrt = PBRT.get((scene, depth))
        goal = ""
        if pbrt:
            if sampler == "power":
                goal = "met" if ms <= pbrt[1] else "missed"
            elif sampler == "rll":
                goal = "met" if ms <= pbrt[0] else "missed"
        syncs, allocs = device_work(by_spp[256][repeats[len(repeats) // 2]][1])
        pbrt_text = f"{pbrt[0]:.2f} / {pbrt[1]:.2f}" if pbrt else ""
        out.append(f"| {scene} | {sampler} | {depth} | {ms:.2f} | {t64:.3f} | {t256:.3f} | "
                   f"{pbrt_text} | {goal} | {syncs} | {allocs} |")
    out.append("")
    out.append("| scene | depth | rll minus power, ms per 1080p spp | goal (depth 5: at most 1.5) |")
    out.append("|---|---|---|---|")
    for (scene, sampler, depth), ms in sorted(ms_of.items(), key=lambda kv: order(kv[0])):
        if sampler != "rll" or (scene, "power", depth) not in ms_of:
            continue
        over = ms - ms_of[(scene, "power", depth)]
        goal = ("met" if over <= 1.5 else "missed") if depth == 5 else ""
        out.append(f"| {scene} | {depth} | {over:+.2f} | {goal} |")
    return out


def stage_rows(paths):
    out = ["| scene | sampler | depth | frame ms | " + " | ".join(STAGES) + " |",
           "|---|---|---|---|" + "---|" * len(STAGES)]
    for path in sorted(paths):
        m = re.match(r"frames-(.+)-([a-z]+)-d(\d+)\.json$", os.path.basename(path))
        if not m:
            fail(f"{path}: expected a name frames-SCENE-SAMPLER-dDEPTH.json")
        with open(path) as f:
            summary = json.load(f).get("summary", {})
        if "ms_total" not in summary:
            out.append(f"| {m[1]} | {m[2]} | {m[3]} | (no measured frame) |" + " |" * len(STAGES))
            continue
        stages = summary.get("ms_stages", {})
        cells = [f"{stages[s]['median']:.2f}" if s in stages else "" for s in STAGES]
        out.append(f"| {m[1]} | {m[2]} | {m[3]} | {summary['ms_total']['median']:.2f} | " +
                   " | ".join(cells) + " |")
    return out


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        sys.exit(0 if len(sys.argv) >= 2 else 2)
    runs = read_timings(sys.argv[1])
    lines = frame_rows(runs)
    if len(sys.argv) > 2:
        lines += ["", "Per stage, median ms of `rll interactive`'s frames (1 spp, 1080p):", ""]
        lines += stage_rows(sys.argv[2:])
    print("\n".join(lines))


if __name__ == "__main__":
    main()
