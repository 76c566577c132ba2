#!/usr/bin/env python3
"""Plots how long crossers are seen before they cross: per crosser (sequence label 1), the annotated frames up
to and including its first C = 1 frame, as an empirical CDF per dataset, against real JAAD's figures.

JAAD (behaviour tracks of its public annotations, 328 crossers): median 66 frames, p25 20, p75 106, 44 % with
76 or more (the figures of issue 18); they are drawn as the four CDF points they give.

Usage:
    python3 tools/plot_time_in_view.py --out docs/time_in_view.png LABEL=DIR [LABEL=DIR ...]

Prints each dataset's median, quartiles and share >= 76 frames; needs pyarrow, numpy and matplotlib.
"""

from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyarrow.dataset as ds  # noqa: E402

JAAD = {"p25": 20, "median": 66, "p75": 106, "share_76": 0.44}
MIN_TRACK = 76


def frames_to_event(root: Path) -> np.ndarray:
    peds = ds.dataset(str(root / "tables" / "pedestrians")).to_table(columns=["clip_id", "pedestrian", "crosser"])
    crossers = {(c, p) for c, p, x in zip(*(peds[k].to_pylist() for k in ("clip_id", "pedestrian", "crosser"))) if x}
    ann = ds.dataset(str(root / "tables" / "annotations")).to_table(
        columns=["clip_id", "pedestrian", "frame", "crossing"]
    )
    tracks = defaultdict(list)
    for c, p, f, x in zip(*(ann[k].to_pylist() for k in ("clip_id", "pedestrian", "frame", "crossing"))):
        if (c, p) in crossers:
            tracks[(c, p)].append((f, x))
    out = []
    for frames in tracks.values():
        frames.sort()
        out.append(next((k + 1 for k, (_, x) in enumerate(frames) if x), 0))
    return np.sort(np.array(out))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--fps", type=float, default=30.0)
    parser.add_argument("datasets", nargs="+", help="LABEL=DIR")
    args = parser.parse_args()

    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    for spec in args.datasets:
        label, _, d = spec.partition("=")
        f = frames_to_event(Path(d))
        share = float((f >= MIN_TRACK).mean())
        p25, med, p75 = np.percentile(f, [25, 50, 75])
        print(f"{label}: {len(f)} crossers, median {med:.0f} (p25 {p25:.0f}, p75 {p75:.0f}), {100 * share:.1f} % >= 76")
        y = np.arange(1, len(f) + 1) / len(f)
        ax.step(f, y, where="post", label=f"{label}: median {med:.0f}, {100 * share:.0f} % ≥ 76 (n = {len(f)})")
    jx = [JAAD["p25"], JAAD["median"], MIN_TRACK, JAAD["p75"]]
    jy = [0.25, 0.5, 1 - JAAD["share_76"], 0.75]
    ax.plot(jx, jy, "k--o", label=f"JAAD: median {JAAD['median']}, {100 * JAAD['share_76']:.0f} % ≥ 76 (n = 328)")
    ax.axvline(MIN_TRACK, color="grey", lw=0.8)
    ax.text(MIN_TRACK + 4, 0.94, "76 frames: PAB's shortest track", color="grey", fontsize=8)
    ax.annotate("mid-road jaywalkers start on the road", xy=(2, 0.06), xytext=(20, 0.03), fontsize=8, color="grey")
    ax.set_xlim(0, 600)
    ax.set_ylim(0, 1)
    ax.set_xlabel(f"annotated frames up to the first C = 1 frame ({args.fps:.0f} fps)")
    ax.set_ylabel("share of crossers (CDF)")
    ax.set_title("How long crossers are seen before they cross")
    top = ax.secondary_xaxis("top", functions=(lambda x: x / args.fps, lambda s: s * args.fps))
    top.set_xlabel("seconds")
    ax.legend(loc="lower right", bbox_to_anchor=(1.0, 0.1), fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out)


if __name__ == "__main__":
    main()
