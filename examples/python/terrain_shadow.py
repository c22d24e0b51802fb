#!/usr/bin/python3
"""Which fraction of the terrain is in shadow, and how does shadow vary with height?

    terrain_shadow.py SUN_STORE OVERHEAD_STORE OUT.png [--method mh] [--bands 10] [--pcf 3]

SUN_STORE: the shadow build to ask (e.g. terragen lit by a sun at azimuth 135, elevation 20).
OVERHEAD_STORE: a build of the same scene lit straight down, holding method raw: it supplies the
receivers (receivers.py), one per texel of an even x-y grid, so the fraction of points in shadow is
the fraction of the terrain's plan area in shadow. Prints a JSON summary; plots the shadowed
fraction per height band (and the PCF-softened one) to OUT.png with matplotlib.
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")  # no display: write the PNG only
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import shadowtiles  # noqa: E402
from receivers import terrain_receivers  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("sun_store")
    parser.add_argument("overhead_store")
    parser.add_argument("png")
    parser.add_argument("--method", default="mh")
    parser.add_argument("--bands", type=int, default=10)
    parser.add_argument("--pcf", type=int, default=3, help="PCF kernel for the soft-shadow curve")
    args = parser.parse_args()

    points = terrain_receivers(args.overhead_store)
    with shadowtiles.open(args.sun_store) as sun:
        lit, _ = sun.query(points, args.method)
        soft = sun.pcf(points, args.pcf, args.method)
        sun_meta = sun.meta
    shadowed = ~lit
    heights = points[:, 2]
    edges = np.linspace(heights.min(), heights.max(), args.bands + 1)
    band = np.clip(np.digitize(heights, edges) - 1, 0, args.bands - 1)
    counts = np.bincount(band, minlength=args.bands)
    hard = np.bincount(band, weights=shadowed, minlength=args.bands) / np.maximum(counts, 1)
    pcf_shadow = np.bincount(band, weights=1 - soft, minlength=args.bands) / np.maximum(counts, 1)

    summary = {
        "receivers": int(len(points)),
        "method": args.method,
        "shadowed_fraction": float(shadowed.mean()),
        "pcf_shadowed_fraction": float((1 - soft).mean()),
        "light_direction": sun_meta["light"]["direction"],
        "bands": [{"z_min": float(edges[i]), "z_max": float(edges[i + 1]), "receivers": int(counts[i]),
                   "shadowed_fraction": float(hard[i])} for i in range(args.bands)],
    }
    print(json.dumps(summary, indent=2))

    centres = (edges[:-1] + edges[1:]) / 2
    width = (edges[1] - edges[0]) * 0.8
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.bar(centres, hard, width=width, label="shadowed (%s)" % args.method, color="#4a5d7e")
    ax.plot(centres, pcf_shadow, "o-", color="#e0a030", label="PCF %dx%d shadow" % (args.pcf, args.pcf))
    ax.set_xlabel("terrain height (world units)")
    ax.set_ylabel("fraction of terrain in shadow")
    ax.set_ylim(0, 1)
    ax.set_title("%.1f%% of the terrain in shadow (%d receivers)" % (100 * shadowed.mean(), len(points)))
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.png, dpi=100)


if __name__ == "__main__":
    main()
