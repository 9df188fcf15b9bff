#!/usr/bin/env python3
"""Writes bench/RESULTS.md from the outputs of scripts/bench.sh (summary.json files and the
micro-benchmarks). Sections of RESULTS.md that this script does not write (such as Loading)
are kept as they are."""
import json
import os
import re
import subprocess
import sys
from datetime import date

out_dir, results, settings = sys.argv[1], sys.argv[2], sys.argv[3]
# The parts this run measured; files of the others left in out_dir are an earlier run's.
_parts = re.search(r"parts=(.*)$", settings)
PARTS = _parts.group(1).split() if _parts else ["equal-time", "equal-spp", "ablation", "seed-to-seed", "rays", "samplers"]
OWN = ["Headline", "Goals", "Per-sample noise of tree (seed to seed)", "Equal time",
       "Resampled next-event estimation at equal time", "Long renders", "The new scenes at equal time",
       "Equal samples per pixel", "Ablation", "Renderer ray rate", "Sampler costs", "How these figures were made"]


def load(name, any_time=False):
    """A comparison's summary.json, None where it did not run with this run's settings (any_time:
    whatever its time budget, for the long renders)."""
    path = os.path.join(out_dir, name, "summary.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        j = json.load(f)
    if not j.get("samplers"):
        return None  # an interrupted compare leaves no samplers
    # A comparison left in out_dir by an earlier run of other settings (a part this run left out)
    # is not this run's: its section keeps the previous RESULTS' figures, marked as such.
    res = re.search(r"res=(\d+)x(\d+)", settings)
    if res and j.get("resolution") != [int(res.group(1)), int(res.group(2))]:
        return None
    secs = re.search(r"seconds=([0-9.]+)", settings)
    if secs and not any_time and "time" in j.get("budget", {}) and abs(j["budget"]["time"] - float(secs.group(1))) > 1e-9:
        return None
    return j


def med(s, key):
    return s[key]["median"]


def comparisons(suffix="", only=None):
    """(scene, integrator, summary) of every comparison that ran, in table order."""
    for scene in only or scenes:
        for integ in integrators:
            s = load(f"{scene}-{integ}{suffix}")
            if s:
                yield scene, integ, s


# rht runs twice (scripts/bench.sh): rll's tuned setting and the study's own; the better of the two
# (lower median relMSE in that run) is the peer every "rht" column and goal is measured against.
RHT_STUDY = "rht:gamma=0.025:reservoirs=16:samples=1"


def by_name(summary):
    b = {s["name"]: s for s in summary["samplers"]}
    if "rht" in b and RHT_STUDY in b:
        tuned, study = b["rht"], b[RHT_STUDY]
        b["rht (tuned)"], b["rht (study)"] = tuned, study
        b["rht"] = study if med(study, "relmse") < med(tuned, "relmse") else tuned
    return b


def row_order(b):
    """The samplers of a full table in order, both rht settings where both ran."""
    names = []
    for n in order:
        names += ["rht (tuned)", "rht (study)"] if n == "rht" and "rht (study)" in b else [n]
    return [n for n in names if n in b]


def fmt(x):
    return "—" if x is None else (f"{x:.3g}" if abs(x) >= 1e-3 else f"{x:.2e}")


def pixels(summary):
    w, h = summary["resolution"]
    return w * h


def spp_taken(s):
    # The mean samples per pixel taken (a pass cut at the time budget counts); older summaries
    # have only the complete samples per pixel.
    return med(s, "mean_spp") if s.get("mean_spp") else med(s, "spp")


def rate(summary, s):
    return spp_taken(s) * pixels(summary) / med(s, "seconds")


def visible(s):
    v = s.get("visible_sample_ratio")
    return v["median"] if isinstance(v, dict) else None


def trimmed(s):
    t = s.get("trimmed_relmse")
    return t["median"] if isinstance(t, dict) else None


def v1_tree(scene, integ):
    """The first version's tree, run on the same reference (None where it did not run)."""
    s = load(f"{scene}-{integ}-v1")
    return s["samplers"][0] if s else None


def seed_to_seed(scene, config):
    p = os.path.join(out_dir, f"seed-to-seed-{scene}-{config}.txt")
    if not os.path.exists(p):
        return None
    text = open(p).read()
    m = re.search(r"relmse=([0-9.e+-]+)", text)
    t = re.search(r"trimmed_relmse=([0-9.e+-]+)", text)
    sec = re.search(r"seconds=([0-9.]+)", text)
    return {"relmse": float(m.group(1)), "trimmed": float(t.group(1)) if t else None,
            "seconds": float(sec.group(1))} if m else None


PBRT_SEED_TO_SEED = {"cornell-boxes-room": 0.00087, "arch-interior": 0.00015}


lines = []
P = lines.append
previous = {}  # sections of the RESULTS.md being replaced, by title
previous_run = ""  # the commit and settings of the run that measured them
if os.path.exists(results):
    text = open(results).read()
    m = re.search(r"commit `([0-9a-f]+)`.*?Settings: `([^`]*)`", text)
    if m:
        previous_run = f" (commit `{m.group(1)}`, `{m.group(2)}`)"
    for part in re.split(r"(?m)^## ", text)[1:]:
        title, _, body = part.partition("\n")
        previous[title.strip()] = body.strip()


def keep_previous(title):
    """A part this run left out keeps its previous figures, marked as such."""
    body = previous.get(title)
    if body is None:
        return
    note = f"*Not re-measured in this run (`BENCH_PARTS`): the figures below are from the previous run{previous_run}.*"
    if not body.startswith("*Not re-measured"):
        body = note + "\n\n" + body
    P(body + "\n")
def keep_previous_subsections(title, shown):
    """The subsections (### scene, integrator) of a section that this run did not measure (a scene
    left out by BENCH_SCENES or BENCH_NEW_SCENES) keep their previous figures, marked as such."""
    for part in re.split(r"(?m)^### ", previous.get(title, ""))[1:]:
        sub, _, body = part.partition("\n")
        if sub.strip() in shown or sub.strip().endswith("(quiet machine)"):
            continue
        body = body.strip()
        note = f"*Not re-measured in this run (`BENCH_SCENES`): the figures below are from the previous run{previous_run}.*"
        if not body.startswith("*Not re-measured"):
            body = note + "\n\n" + body
        P(f"### {sub.strip()}\n")
        P(body + "\n")


commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
cpu = "unknown CPU"
try:
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
except OSError:
    pass
P("# Benchmark results\n")
P(f"Measured on {date.today().isoformat()}, commit `{commit}`, {os.cpu_count()} cores ({cpu}), a shared "
  f"machine: figures are medians of interleaved repeats, and ratios within one run are the signal. "
  f"Settings: `{settings}`. Regenerate with `make bench` (about two hours on 2 cores); every report (HTML, images, "
  f"`summary.json`) is under `out/bench/`.\n")

scenes = ["cornell-boxes-room", "arch-interior", "many-lights-open", "cornell-boxes-dynamic"]
integrators = ["direct", "path"]
order = ["power", "tree", "fermat", "ltc", "rht", "rll", "oracle"]

# --- Headline and goals ------------------------------------------------------------------------
P("## Headline\n")
P("relMSE at equal time (lower is better), median of the repeats, and rll's ratio to the others. "
  "`tree (v1)` is the first version's tree in the first version's renderer (light sampling only, "
  "independent points), run on the same reference: what the ratios of the first RESULTS were "
  "measured against. `fermat` is the published RLL (docs/fermat.md), `ltc` Wang et al. 2021 "
  "(docs/ltc.md). Where the reference was rendered as two halves, its noise is subtracted from "
  "every error (`rll compare`). `rht` is the resampled hierarchical tree (docs/rht.md), the winner "
  "of Kvasnica & Havran's study, run at rll's tuned setting (docs/rht.md) and at the study's own "
  f"(`{RHT_STUDY}`); its column is the better of the two in each run.\n")
P("| scene | integrator | power | tree (v1) | tree | fermat | ltc | rht | rll | oracle | rll / rht | rll / ltc | rll / tree |")
P("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
goal_rows = []
for scene, integ, s in comparisons():
    b = by_name(s)
    r = {n: med(b[n], "relmse") if n in b else None for n in order}
    v1 = v1_tree(scene, integ)
    rl = r["rll"] / r["ltc"] if r["rll"] and r["ltc"] else None
    rt = r["rll"] / r["tree"] if r["rll"] and r["tree"] else None
    rh = r["rll"] / r["rht"] if r["rll"] and r["rht"] else None
    P(f"| {scene} | {integ} | {fmt(r['power'])} | {fmt(med(v1, 'relmse') if v1 else None)} | {fmt(r['tree'])} | "
      f"{fmt(r['fermat'])} | {fmt(r['ltc'])} | {fmt(r['rht'])} | {fmt(r['rll'])} | {fmt(r['oracle'])} | {fmt(rh)} | "
      f"{fmt(rl)} | {fmt(rt)} |")
    goal_rows.append((scene, integ, s, b, r))
P("")

missing = [sc for sc in scenes if sc not in {row[0] for row in goal_rows}]
if goal_rows and missing:
    P(f"*Not re-measured in this run (`BENCH_SCENES`): {', '.join(missing)}; their previous figures are kept "
      "under Equal time, marked.*\n")
P("## Goals\n")
P("| goal | measured | |")
P("|---|---|---|")


def goal(text, value, ok):
    P(f"| {text} | {value} | {'met' if ok else '**missed**'} |")


# Issue 11's goals for rll against the sharp tree: relMSE and trimmed relMSE at most this
# fraction of tree's.
TREE_GOAL = {"cornell-boxes-room": 1 / 3, "cornell-boxes-dynamic": 1 / 3, "arch-interior": 1 / 2,
             "many-lights-open": 0.9}
for scene, integ, s, b, r in goal_rows:
    if "rll" not in b or "tree" not in b:
        continue
    g = TREE_GOAL[scene]
    ratios = [r["rll"] / r["tree"]]
    if trimmed(b["rll"]) and trimmed(b["tree"]):
        ratios.append(trimmed(b["rll"]) / trimmed(b["tree"]))
    goal(f"{scene}, {integ}: rll relMSE and trimmed relMSE <= {g:.2g}x tree's",
         " / ".join(f"{x:.2f}x" for x in ratios), max(ratios) <= g)
    goal(f"{scene}, {integ}: rll never worse than tree by more than 10%", f"{max(ratios):.2f}x", max(ratios) <= 1.1)
    rel = b["rll"]["relmse"]
    spread = rel["max"] / rel["min"] if rel["min"] > 0 else float("inf")
    goal(f"{scene}, {integ}: no outlier run (rll's largest repeat within 3x its smallest)", f"{spread:.2f}x",
         spread <= 3)
    if "power" in b:
        ratio = rate(s, b["rll"]) / rate(s, b["power"])
        goal(f"{scene}, {integ}: rll samples per second >= 85% of power's", f"{100 * ratio:.0f}%", ratio >= 0.85)


# rll's resampling variants in the -ris comparison (scripts/bench.sh), with their labels.
RLL_RIS = {"rll:nee.candidates=4": "rll+ris",
           "rll:nee.candidates=4:nee.target=learnt": "rll+ris(learnt)",
           "rll:nee.candidates=2:nee.target=learnt": "rll+ris2(learnt)"}


def best_rll(scene, integ, b):
    """rll's best default at this budget, with or without resampled NEE (the -ris comparison ran
    rll with and without its resampling variants on the same reference): (label, relMSE, trimmed)."""
    best = ("rll", med(b["rll"], "relmse"), trimmed(b["rll"]))
    ris = load(f"{scene}-{integ}-ris")
    if not ris or "rll" not in by_name(ris):
        return best
    x = by_name(ris)
    plain = ("rll", med(b["rll"], "relmse"), trimmed(b["rll"]))
    for name, label in RLL_RIS.items():
        if name not in x:
            continue
        # The ratio of the variant to plain rll within their own run, applied to the rll above.
        f = med(x[name], "relmse") / med(x["rll"], "relmse")
        ft = (trimmed(x[name]) / trimmed(x["rll"]) if trimmed(x["rll"]) and trimmed(x[name])
              else None)
        if plain[1] * f < best[1]:
            best = (label, plain[1] * f, plain[2] * ft if plain[2] and ft else plain[2])
    return best


# Issue 34's goals against rht: the best rll default at most this fraction of rht's.
RHT_GOAL = {"cornell-boxes-room": 0.5, "cornell-boxes-dynamic": 0.5, "arch-interior": 0.5,
            "many-lights-open": 1.0}
for scene, integ, s, b, r in goal_rows:
    if "rll" not in b or "rht" not in b:
        continue
    label, rel, tri = best_rll(scene, integ, b)
    ratios = [rel / r["rht"]]
    if tri and trimmed(b["rht"]):
        ratios.append(tri / trimmed(b["rht"]))
    goal(f"{scene}, {integ}, {s['budget'].get('time', '?'):g} s: best rll ({label}) relMSE and trimmed "
         f"<= {RHT_GOAL[scene]:.2g}x rht's", " / ".join(f"{x:.2f}x" for x in ratios),
         max(ratios) <= RHT_GOAL[scene])
def rll_half_of_rht(scene, s, peer):
    """The goal that rll's relMSE and trimmed relMSE are at most half rht's in one comparison."""
    b = by_name(s) if s else {}
    if "rll" not in b or "rht" not in b:
        return
    rr = [med(b["rll"], "relmse") / med(b["rht"], "relmse")]
    if trimmed(b["rll"]) and trimmed(b["rht"]):
        rr.append(trimmed(b["rll"]) / trimmed(b["rht"]))
    goal(f"{scene}, path, {s['budget']['time']:g} s: rll relMSE and trimmed <= 0.5x {peer}",
         " / ".join(f"{x:.2f}x" for x in rr), max(rr) <= 0.5)


# Issue 45's goal on the new scenes (rll at most 0.5x the better rht), and the long renders'.
for scene in ("spot-hall", "screen-hall"):
    rll_half_of_rht(scene, load(f"{scene}-path"), "the better rht's")
for scene in ("cornell-boxes-room", "arch-interior"):
    rll_half_of_rht(scene, load(f"long-{scene}-path", any_time=True), "rht's")
for scene, integ, s in comparisons("-spp", ("cornell-boxes-room", "arch-interior")):
    r = {x["name"]: med(x, "relmse") for x in s["samplers"]}
    best_other = min(v for n, v in r.items() if n != "oracle")
    goal(f"{scene}, {integ}: oracle's equal-spp relMSE <= every other sampler's",
         f"{r['oracle']:.3g} against {best_other:.3g}", r["oracle"] <= best_other)
    bx = by_name(s)
    if "rll" in bx and "oracle" in bx:
        rr = [r["rll"] / r["oracle"]]
        if trimmed(bx["rll"]) and trimmed(bx["oracle"]):
            rr.append(trimmed(bx["rll"]) / trimmed(bx["oracle"]))
        goal(f"{scene}, {integ}: rll within 1.5x of the oracle at equal spp (relMSE / trimmed)",
             " / ".join(f"{x:.2f}x" for x in rr), max(rr) <= 1.5)
for scene, target in PBRT_SEED_TO_SEED.items():
    x = seed_to_seed(scene, "default")
    if x:
        goal(f"{scene}, direct, 1024 spp, 160x120: tree's seed-to-seed relMSE <= pbrt-v4's {target}",
             f"{x['relmse']:.3g}", x["relmse"] <= target)
for sampler in ("power", "rll"):
    p = os.path.join(out_dir, f"rays-{sampler}.txt")
    m = re.search(r"ratio\s+([0-9.]+) %", open(p).read()) if os.path.exists(p) else None
    if m:
        goal(f"renderer keeps >= 50% of the bare Embree ray rate (path, cornell-boxes-room, {sampler})",
             f"{m.group(1)}%" + ("" if "rays" in PARTS else " (previous run)"), float(m.group(1)) >= 50)
if goal_rows:
    mem = max((med(b["rll"], "seconds") and b["rll"]["memory"]["sampler_bytes"]) for _, _, _, b, _ in goal_rows)
    goal("rll's default memory <= 512 MiB", f"{mem / 2**20:.0f} MiB (sampler state)", mem <= 512 * 2**20)
P("")

# --- Seed to seed ------------------------------------------------------------------------------
P("## Per-sample noise of tree (seed to seed)\n")
if not any(seed_to_seed(scene, "default") for scene in PBRT_SEED_TO_SEED):
    keep_previous("Per-sample noise of tree (seed to seed)")
else:
    P("The relMSE of a render against another seed's render of the same settings (1024 spp, 160x120, "
      "direct lighting, `tree`), as pbrt-v4's BVH light sampler was measured in `shared/PEERS.md` "
      "(pbrt-v4: path integrator with max depth 1, its default Owen-scrambled Sobol' sampler). "
      "`scripts/seed_to_seed.sh`; seconds are one render's on 2 threads.\n")
    P("| scene | pbrt-v4 | rll v1 (its binary) | light sampling only, independent | MIS, independent | MIS, Sobol' (default) | default: trimmed relMSE | seconds (v1 / default) |")
    P("|---|---|---|---|---|---|---|---|")
    for scene, target in PBRT_SEED_TO_SEED.items():
        c = {k: seed_to_seed(scene, k) for k in ("v1", "nee", "independent", "default")}
        if not c["default"]:
            continue
        g = lambda k: fmt(c[k]["relmse"]) if c[k] else "—"
        secs = f"{c['v1']['seconds']:.1f} / " if c["v1"] else ""
        P(f"| {scene} | {target} | {g('v1')} | {g('nee')} | {g('independent')} | **{g('default')}** | "
          f"{fmt(c['default']['trimmed'])} | {secs}{c['default']['seconds']:.1f} |")
    P("")

# --- Full tables -------------------------------------------------------------------------------
P("## Equal time\n")
for scene, integ, s, b, r in goal_rows:
    P(f"### {scene}, {integ}\n")
    budget = f"{s['budget']['time']:g} s per run" if "time" in s["budget"] else f"{s['budget']['spp']} spp per run"
    P(f"{budget}, {s['repeats']} repeat(s), {s['resolution'][0]}x{s['resolution'][1]}, "
      f"reference {s['reference'].get('spp', '?')} spp ({s['reference'].get('sampler', '?')})"
      + (f", {s.get('frames', 1)} frames (the last measured)" if s.get("frames", 1) > 1 else "") + ".\n")
    P("| sampler | spp | seconds | samples/s | relMSE median [min, max] | trimmed relMSE | / power | / tree | / ltc | / rht | / oracle | visible | memory |")
    P("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    v1 = v1_tree(scene, integ)
    rows = [(n, b[n]) for n in row_order(b)]
    if v1:
        rows.insert(1, ("tree (v1)", v1))
    for n, x in rows:
        rel = x["relmse"]
        def ratio(other):
            return fmt(rel["median"] / r[other]) if r.get(other) else "—"
        P(f"| {n} | {spp_taken(x):.0f} | {med(x, 'seconds'):.2f} | {rate(s, x) / 1e6:.2f} M | {fmt(rel['median'])} [{fmt(rel['min'])}, "
          f"{fmt(rel['max'])}] | {fmt(trimmed(x))} | {ratio('power')} | {ratio('tree')} | {ratio('ltc')} | {ratio('rht')} | "
          f"{ratio('oracle')} | {fmt(visible(x))} | {x['memory']['peak_rss_bytes'] / 2**20:.0f} MiB |")
    P("")

keep_previous_subsections("Equal time", {f"{sc}, {ig}" for sc, ig, _, _, _ in goal_rows})

P("## Resampled next-event estimation at equal time\n")
ris_rows = list(comparisons("-ris"))
if not ris_rows:
    keep_previous("Resampled next-event estimation at equal time")
else:
    P("`tree+ris` and `rll+ris`: tree and rll with four candidates (`tree:nee.candidates=4`; docs/nee.md: "
      "four candidates from the sampler, resampled by their unshadowed contribution, one shadow ray); "
      "`rll+ris(learnt)` and `rll+ris2(learnt)`: rll with four and two candidates and the learnt target "
      "(`nee.target=learnt`: the unshadowed contribution times the cell's learnt factor of the candidate's "
      "cluster); beside plain tree, plain rll and rht, in one interleaved compare of its own on the same "
      "cached reference and budget. relMSE medians; `/ plain` is relMSE and trimmed relMSE over the plain "
      "sampler's in the same run.\n")
    names = [("tree", "tree+ris", "tree:nee.candidates=4")] + [("rll", label, n) for n, label in RLL_RIS.items()]
    P("| scene | integrator | tree | rll | " + " | ".join(f"{label} | / plain" for _, label, _ in names)
      + " | rht | best rll / rht |")
    P("|---|---|---|---|" + "---|---|" * len(names) + "---|---|")
    for scene, integ, s in ris_rows:
        b = by_name(s)
        cells = [fmt(med(b[n], "relmse")) if n in b else "—" for n in ("tree", "rll")]
        for plain, _, n in names:
            x, y = b.get(plain), b.get(n)
            if not x or not y:
                cells += [fmt(med(y, "relmse")) if y else "—", "—"]
                continue
            t = trimmed(y) / trimmed(x) if trimmed(x) and trimmed(y) else None
            cells += [fmt(med(y, "relmse")), f"{fmt(med(y, 'relmse') / med(x, 'relmse'))}; {fmt(t)}"]
        rllv = [med(b[n], "relmse") for n in ["rll"] + list(RLL_RIS) if n in b]
        rht = med(b["rht"], "relmse") if "rht" in b else None
        P(f"| {scene} | {integ} | " + " | ".join(cells) + f" | {fmt(rht)} | "
          f"{fmt(min(rllv) / rht) if rllv and rht else '—'} |")
    P("")

P("## Long renders\n")
long_rows = [(sc, load(f"long-{sc}-path", any_time=True)) for sc in ("cornell-boxes-room", "arch-interior")]
long_rows = [(sc, s) for sc, s in long_rows if s]
if not long_rows:
    keep_previous("Long renders")
else:
    P("One run per sampler of the budget below, path, on the equal-time table's cached reference (its "
      "noise subtracted): whether rht catches up with rll when both have long.\n")
    P("| scene | seconds | sampler | spp | relMSE | trimmed relMSE | / tree | / rht | visible |")
    P("|---|---|---|---|---|---|---|---|---|")
    for scene, s in long_rows:
        b = by_name(s)
        for n in ("tree", "rht", "rll"):
            if n not in b:
                continue
            x = b[n]
            rel = med(x, "relmse")
            P(f"| {scene} | {s['budget']['time']:g} | {n} | {spp_taken(x):.0f} | {fmt(rel)} | {fmt(trimmed(x))} | "
              f"{fmt(rel / med(b['tree'], 'relmse')) if 'tree' in b else '—'} | "
              f"{fmt(rel / med(b['rht'], 'relmse')) if 'rht' in b else '—'} | {fmt(visible(x))} |")
    P("")

P("## The new scenes at equal time\n")
new_rows = [(sc, ig, load(f"{sc}-{ig}")) for sc in ("spot-hall", "screen-hall") for ig in integrators]
new_rows = [(sc, ig, s) for sc, ig, s in new_rows if s]
if not new_rows:
    keep_previous("The new scenes at equal time")
else:
    P("The built-in scenes of issue 32 (docs/scenes.md): `spot-hall`, 102,400 spot lights in 16x16 "
      "occluded rooms, and `screen-hall`, three large textured emitters (split into 8,333 lights of nearly "
      "equal power) beside 12 small lamps; equal time as above, path.\n")
    for scene, integ, s in new_rows:
        b = by_name(s)
        P(f"### {scene}, {integ}\n")
        P(f"{s['budget']['time']:g} s per run, {s['repeats']} repeat(s), {s['resolution'][0]}x{s['resolution'][1]}, "
          f"{s.get('lights', '?')} lights, reference {s['reference'].get('spp', '?')} spp ({s['reference'].get('sampler', '?')}).\n")
        P("| sampler | spp | relMSE median [min, max] | trimmed relMSE | / tree | visible | memory |")
        P("|---|---|---|---|---|---|---|")
        shown = row_order(b)
        shown += [x["name"] for x in s["samplers"]
                  if x["name"] not in shown and not (x["name"] in ("rht", RHT_STUDY) and "rht (study)" in b)]
        for name in shown:
            x = b[name]
            rel = x["relmse"]
            P(f"| {name} | {spp_taken(x):.0f} | {fmt(rel['median'])} [{fmt(rel['min'])}, {fmt(rel['max'])}] | "
              f"{fmt(trimmed(x))} | {fmt(rel['median'] / med(b['tree'], 'relmse')) if 'tree' in b else '—'} | "
              f"{fmt(visible(x))} | {x['memory']['peak_rss_bytes'] / 2**20:.0f} MiB |")
        P("")
        if os.path.exists(os.path.join("docs", "images", f"compare-{scene}.png")):
            P(f"![{scene}: every sampler's first repeat and the reference](../docs/images/compare-{scene}.png)\n")

keep_previous_subsections("The new scenes at equal time", {f"{sc}, {ig}" for sc, ig, _ in new_rows})

P("## Equal samples per pixel\n")
spp_rows = list(comparisons("-spp"))
if not spp_rows:
    keep_previous("Equal samples per pixel")
else:
    P("The gap to the oracle (exhaustive per-cell knowledge, precomputed outside the timing) at equal spp:\n")
    P("| scene | integrator | spp | oracle | rll | tree | power | rll / oracle |")
    P("|---|---|---|---|---|---|---|---|")
for scene, integ, s in spp_rows:
    r = {x["name"]: med(x, "relmse") for x in s["samplers"]}
    P(f"| {scene} | {integ} | {s['budget']['spp']} | {fmt(r.get('oracle'))} | {fmt(r.get('rll'))} | "
      f"{fmt(r.get('tree'))} | {fmt(r.get('power'))} | {fmt(r['rll'] / r['oracle'])} |")
P("")

# --- Ablation ----------------------------------------------------------------------------------
# The rows of scripts/bench.sh's ablation, by the sampler spec's last addition.
ABLATION = [
    ("fermat", "published RLL: `fermat` (75% uniform over 256 clusters, exponential Q, max-RGB reward, jitter, reset)"),
    ("reward=cluster", "+ cluster reward (estimate over P(light | cluster))"),
    ("target=moment", "+ target sqrt(second moment) instead of the mean"),
    ("alpha=0.02", "+ shrinkage learning (1/n settling at alpha 0.02)"),
    ("q_init=-1", "+ importance prior and split, epsilon 0.1, trust 256, unvisited clusters from the prior"),
    ("within=tree", "+ tree descent within clusters"),
    ("rll", "rll's defaults (its cut size, splits, cells, no jitter, no reset, cold cells from the tree)"),
]


def ablation_label(name):
    for suffix, label in ABLATION:
        if name == suffix or name.endswith(":" + suffix):
            return label
    return f"`{name}`"


P("## Ablation\n")
if not any(load(f"ablation-{sc}") for sc in ["cornell-boxes-room", "arch-interior"]):
    keep_previous("Ablation")
else:
    P("Equal time, direct lighting, from the published RLL to rll's defaults; each row adds one of "
      "rll's changes to the row above (the sampler specs are in `scripts/bench.sh`). relMSE and "
      "trimmed relMSE medians, reference noise subtracted, and their ratios to tree's in the same run.\n")
for scene in ["cornell-boxes-room", "arch-interior"]:
    s = load(f"ablation-{scene}")
    if not s:
        continue
    b = s["samplers"]
    tree = med(b[0], "relmse")
    tree_t = trimmed(b[0])
    P(f"### {scene}\n")
    P("| settings | spp | relMSE | trimmed relMSE | / tree (relMSE; trimmed) |")
    P("|---|---|---|---|---|")
    P(f"| tree (reference point) | {spp_taken(b[0]):.0f} | {fmt(tree)} | {fmt(tree_t)} | 1 |")
    for x in b[1:]:
        t = trimmed(x)
        P(f"| {ablation_label(x['name'])} | {spp_taken(x):.0f} | {fmt(med(x, 'relmse'))} | {fmt(t)} | "
          f"{fmt(med(x, 'relmse') / tree)}; {fmt(t / tree_t) if t and tree_t else '—'} |")
    P("")

# --- Ray rate, sampler costs -------------------------------------------------------------------
P("## Renderer ray rate\n")
if "rays" not in PARTS:
    keep_previous("Renderer ray rate")
else:
    P("Rays per second of the whole renderer (path tracing, cornell-boxes-room) against a bare loop "
      "tracing the same recorded rays through Embree (`build/bench/rll_bench_rays SCENE SAMPLER 4`). "
      "Goal: the renderer keeps at least 50% of the bare rate.\n")
    P("```")
    for f in ["rays-power.txt", "rays-rll.txt"]:
        p = os.path.join(out_dir, f)
        if os.path.exists(p):
            P(open(p).read().strip())
    P("```\n")

P("## Sampler costs\n")
p = os.path.join(out_dir, "samplers.json")
if "samplers" not in PARTS:
    keep_previous("Sampler costs")
elif os.path.exists(p):
    P("Per call, on open fields of emitters (`build/bench/rll_bench_samplers`, median of 3; rll trained "
      "for 8 passes first). Tree build and refit in ms.\n")
    data = json.load(open(p))
    rows = {}
    for bm in data["benchmarks"]:
        if bm.get("aggregate_name") != "median":
            continue
        m = re.match(r"(\w+)/?(\w*)/(\d+)", bm["run_name"])
        if not m:
            continue
        kind, sampler, n = m.group(1), m.group(2), int(m.group(3))
        unit = bm["time_unit"]
        value = bm["real_time"] if kind.startswith("tree_") else bm["cpu_time"]
        rows.setdefault((kind, sampler), {})[n] = f"{value:.3g} {unit}"
    sizes = sorted({n for r in rows.values() for n in r})
    P("| measure | " + " | ".join(f"{n:,} lights" for n in sizes) + " |")
    P("|---|" + "---|" * len(sizes))
    for (kind, sampler), r in sorted(rows.items()):
        P(f"| {kind} {sampler} | " + " | ".join(r.get(n, "—") for n in sizes) + " |")
    P("")

P("## How these figures were made\n")
P("`make bench` runs `scripts/bench.sh`: for each scene and integrator one `rll compare` at equal time "
  f"(`--samplers power,tree,fermat,ltc,rht,{RHT_STUDY},rll,oracle --repeats 3`, runs interleaved, starting "
  "sampler rotated, each run ending at the budget: the last pass sized from the measured rate), then the "
  "first version's binary (`build-v1/rll`, built from commit a3cbdd4) on the same reference and budget "
  "with `--samplers tree` (a separate process, run right after, so its timing shares the machine's state "
  "less closely than the interleaved runs do), one at equal spp, and for the ablation one compare of rll "
  "variants written `rll:key=value:...`; the seed-to-seed figures come from `scripts/seed_to_seed.sh`. "
  "The exact command lines and outputs are in `out/bench/*.txt`.\n")

# Keep the sections this script does not write.
kept = []
if os.path.exists(results):
    text = open(results).read()
    parts = re.split(r"(?m)^## ", text)
    for part in parts[1:]:
        title = part.split("\n", 1)[0].strip()
        if title not in OWN:
            kept.append("## " + part.rstrip() + "\n")
with open(results + ".tmp", "w") as f:
    f.write("\n".join(lines).rstrip() + "\n\n" + "\n".join(kept))
os.replace(results + ".tmp", results)
