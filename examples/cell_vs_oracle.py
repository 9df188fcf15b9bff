#!/usr/bin/env python3
"""Renders a scene with rll and saves what it learnt, loads that state again, and plots what one
cell learnt (the pmf of every light at the cell) against the oracle's knowledge of the same cell.

    PYTHONPATH=build/python /usr/bin/python3 examples/cell_vs_oracle.py builtin:cornell-boxes-room \
        --spp 64 --out cell-example.png
"""
import argparse
import os
import tempfile

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt
import numpy as np

import rll


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="builtin:cornell-boxes-room")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", default="160x120")
    ap.add_argument("--out", default="cell-example.png")
    a = ap.parse_args()

    scene = rll.load(a.scene, res=a.res)
    learnt = rll.render(scene, sampler="rll", spp=a.spp)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "rll.state")
        learnt.state.save(path)
        state = rll.load_state(path, scene)  # as a state saved by `rll render --rll-state`
    oracle = rll.render(scene, sampler="oracle", spp=1).state

    # The most rewarded cell of rll that the oracle knows too (cells are matched by key: the
    # same region of space and normals).
    cells, known = state.cells, oracle.cells
    keys = {int(k): int(i) for k, i in zip(known["key"], known["id"])}
    order = np.argsort(-cells["rewards"])
    pick = next(i for i in order if int(cells["key"][i]) in keys and cells["size"][i] > 0)
    cell, oracle_cell = int(cells["id"][pick]), keys[int(cells["key"][pick])]
    anchor, normal = cells["anchor"][pick], cells["normal"][pick]
    p_rll = state.pmf(cell)
    p_oracle = oracle.pmf(oracle_cell, point=anchor, normal=normal)
    p = state.cut(cell)["probability"]
    p = p[p > 0]
    print(f"cell {cell} (key {int(cells['key'][pick]):016x}), anchor {np.round(anchor, 3)}, "
          f"{cells['rewards'][pick]:.0f} rewards, {len(p)} clusters, entropy "
          f"{-(p * np.log2(p)).sum():.2f} bits")
    print(f"pmf sums: rll {p_rll.sum():.6f}, oracle {p_oracle.sum():.6f}; "
          f"total variation distance {0.5 * np.abs(p_rll - p_oracle).sum():.3f}")

    fig, ax = plt.subplots(figsize=(7, 3.5), dpi=120)
    lights = np.arange(state.lights)
    ax.bar(lights - 0.2, p_rll, width=0.4, label="rll (learnt)")
    ax.bar(lights + 0.2, p_oracle, width=0.4, label="oracle")
    ax.set_xlabel("light (tree order)")
    ax.set_ylabel("P(light | cell)")
    ax.set_title(f"{a.scene}: cell {cell} after {a.spp} spp")
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
