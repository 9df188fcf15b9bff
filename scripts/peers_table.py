#!/usr/bin/env python3
"""Prints the peers table of bench/RESULTS.md (every sampler per scene and integrator, relMSE and
trimmed relMSE with the reference noise subtracted, rll against ltc and tree; the ablation) from
the summary.json files of scripts/bench.sh: scripts/peers_table.py out/bench"""
import json, os, sys
out = sys.argv[1]
order = ["power", "tree", "fermat", "ltc", "rll", "oracle"]
def fmt(x): return "—" if x is None else (f"{x:.3g}" if abs(x) >= 1e-3 else f"{x:.2e}")
rows = []
print("| scene | integrator | ref. noise (relMSE, subtracted) | " + " | ".join(f"{n}" for n in order) + " | rll / ltc (relMSE; trimmed) | rll / tree (relMSE; trimmed) |")
print("|---|---|---|" + "---|" * len(order) + "---|---|")
for scene in ["cornell-boxes-room", "arch-interior", "many-lights-open", "cornell-boxes-dynamic"]:
    for integ in ["direct", "path"]:
        p = os.path.join(out, f"{scene}-{integ}", "summary.json")
        if not os.path.exists(p): continue
        j = json.load(open(p))
        if "noise_relmse" not in j.get("reference", {}): continue
        b = {s["name"]: s for s in j["samplers"]}
        def m(n, k): return b[n][k]["median"] if n in b and b[n].get(k) else None
        cells = [f"{fmt(m(n,'relmse'))} / {fmt(m(n,'trimmed_relmse'))} ({m(n,'spp'):.0f} spp)" if n in b else "—" for n in order]
        r = lambda a, c, k: fmt(m(a, k) / m(c, k)) if m(a, k) and m(c, k) else "—"
        print(f"| {scene} | {integ} | {fmt(j['reference']['noise_relmse'])} | " + " | ".join(cells) +
              f" | {r('rll','ltc','relmse')}; {r('rll','ltc','trimmed_relmse')} | {r('rll','tree','relmse')}; {r('rll','tree','trimmed_relmse')} |")
for scene in ["cornell-boxes-room", "arch-interior"]:
    p = os.path.join(out, f"ablation-{scene}", "summary.json")
    if not os.path.exists(p): continue
    j = json.load(open(p))
    print(f"\n#### Ablation, {scene}, direct\n")
    print("| sampler | spp | relMSE | trimmed relMSE | / tree (relMSE; trimmed) |")
    print("|---|---|---|---|---|")
    t = j["samplers"][0]
    for s in j["samplers"]:
        print(f"| `{s['name']}` | {s['spp']['median']:.0f} | {fmt(s['relmse']['median'])} | {fmt(s['trimmed_relmse']['median'])} | "
              f"{fmt(s['relmse']['median']/t['relmse']['median'])}; {fmt(s['trimmed_relmse']['median']/t['trimmed_relmse']['median'])} |")
