#!/usr/bin/env python3
"""Renders a scene with several light samplers under one budget, measures each against a
reference as `rll compare` does, and plots their error against render time (log-log).

    PYTHONPATH=build/python /usr/bin/python3 examples/convergence.py builtin:cornell-boxes-room \
        --samplers power,tree,rll --spp 64 --out convergence-example.png
"""
import argparse

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt

import rll


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="builtin:cornell-boxes-room")
    ap.add_argument("--samplers", default="power,tree,rll")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", default="160x120")
    ap.add_argument("--reference-spp", type=int, default=1024)
    ap.add_argument("--metric", default="relmse", choices=["relmse", "trimmed_relmse", "mrse", "mse"])
    ap.add_argument("--cache-dir", default=None)
    ap.add_argument("--out", default="convergence-example.png")
    a = ap.parse_args()

    scene = rll.load(a.scene, res=a.res)
    result = rll.compare(scene, a.samplers.split(","), spp=a.spp, reference_spp=a.reference_spp,
                         cache_dir=a.cache_dir)
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    for s in result["samplers"]:
        run = s["runs"][0]
        fields = s["checkpoint_fields"]
        t = [c[fields.index("seconds")] for c in run["checkpoints"]]
        e = [c[fields.index(a.metric)] for c in run["checkpoints"]]
        ax.loglog(t, e, marker="o", markersize=3, label=s["name"])
        print(f"{s['name']}: {s['spp']['median']:.0f} spp, {a.metric} {run[a.metric]:.4e}, "
              f"visible-sample ratio {s['visible_sample_ratio']['median']:.3f}")
    ax.set_xlabel("render time (s)")
    ax.set_ylabel(a.metric)
    ax.set_title(f"{a.scene}, {scene.resolution[0]}x{scene.resolution[1]}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
