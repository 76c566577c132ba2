"""Why the box-bottom cue (crossers' windows lower in the image than non-crossers') is weaker in a generated set
than in JAAD train: the cue with and without each video's or clip's horizon, the horizon's spread, the classes'
box heights and bottoms, which pedestrians the synthetic windows come from, and where non-crossers' tracks end.

The horizon of a video (JAAD) or clip (ours) is the intercept of `bottom = horizon + slope × height` fitted to its
unoccluded boxes (fractions of the image height), as `pedsynth calibrate` fits the camera. Windows are
PedestrianActionBenchmark's (tools/transfer_eval.py's sampling).

Not pedsynth code: a measurement (BENCHMARKS.md, "Transfer to real data", "The bottom cue"). Run from the
repository root: `python3 tools/whatif/bottom_cue.py DATASET` (a set generated with the fitted profile, tables
only). Needs pyarrow, numpy, scikit-learn and PyYAML. Reads JAAD's train split only.
"""
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.dataset as ds
import pyarrow.parquet as pq
from sklearn.metrics import roc_auc_score

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import transfer_eval as te  # noqa: E402

import common  # noqa: E402

REAL = Path(__file__).resolve().parents[3] / "shared/real/jaad_trainval"


def horizons(groups, heights, bottoms) -> dict:
    """Per group, the intercept of bottom against height (groups with 50+ boxes)."""
    per = defaultdict(list)
    for g, h, b in zip(groups, heights, bottoms):
        per[g].append((h, b))
    out = {}
    for g, xs in per.items():
        xs = np.array(xs)
        if len(xs) >= 50:
            out[g] = np.linalg.lstsq(np.c_[np.ones(len(xs)), xs[:, 0]], xs[:, 1], rcond=None)[0][0]
    return out


def real():
    videos = pq.read_table(REAL / "videos.parquet").to_pylist()
    keep = {v["video"] for v in videos if v["split"] == "train"}
    size = (videos[0]["width"], videos[0]["height"])
    boxes = [r for r in pq.read_table(REAL / "boxes.parquet").to_pylist() if r["video"] in keep]
    clear = [r for r in boxes if r["occlusion"] == 0]
    hz = horizons(
        [r["video"] for r in clear],
        [(r["y_max"] - r["y_min"]) / size[1] for r in clear],
        [r["y_max"] / size[1] for r in clear],
    )
    peds = {(p["video"], p["pedestrian"]): p for p in pq.read_table(REAL / "pedestrians.parquet").to_pylist()}
    tracks = defaultdict(list)
    for r in boxes:
        if "p" not in r["pedestrian"]:
            tracks[(r["video"], r["pedestrian"])].append((r["frame"], r["x_min"], r["y_min"], r["x_max"], r["y_max"]))
    out, ends = [], []
    for key in sorted(tracks):
        rows = sorted(tracks[key])
        p = peds.get(key, {})
        label = int("b" in key[1] and (p.get("crossing") or 0) > 0)
        if not label and len(rows) >= te.MIN_TRACK:
            # The whole track's last frame, and the box height 3 frames before it (track_ends).
            ends.append((key[0], rows[-1][0], (rows[-3][4] - rows[-3][2]) / size[1]))
        event = p.get("crossing_point") if "b" in key[1] else -1
        event = -1 if event is None else int(event)
        rows = rows[: [r[0] for r in rows].index(event) + 1] if event != -1 else rows[:-2]
        if len(rows) >= te.MIN_TRACK:
            for w in te.windows(np.array([r[1:] for r in rows], dtype=np.float64)):
                out.append((w, label, key[0], "jaad"))
    lengths = {v["video"]: v["num_frames"] for v in videos if v["video"] in keep}
    return (out, size, hz), (ends, lengths)


def box_kind(spec: dict) -> str:
    """The box the spec's `annotations.export_box` chooses (the tight box by default)."""
    return "annotator" if spec.get("annotations", {}).get("export_box") == "annotator" else "bbox"


def synthetic(root: Path):
    spec = common.spec(root)
    size = (spec["sensors"]["rgb"]["width_px"], spec["sensors"]["rgb"]["height_px"])
    box = box_kind(spec)
    kind = {
        (r["clip_id"], r["pedestrian"]): f"{r['role']}/{r['behaviour']}"
        for r in ds.dataset(str(root / "tables/pedestrians"), format="parquet")
        .to_table(columns=["clip_id", "pedestrian", "role", "behaviour"])
        .to_pylist()
    }
    tab = ds.dataset(str(root / "tables/annotations"), format="parquet").to_table(
        columns=["clip_id", "occlusion", f"{box}_y_min", f"{box}_y_max"]
    )
    c = {n: tab.column(n).to_numpy(zero_copy_only=False) for n in tab.column_names}
    clear = c["occlusion"] == 0
    y_min, y_max = c[f"{box}_y_min"][clear], c[f"{box}_y_max"][clear]
    hz = horizons(c["clip_id"][clear], (y_max - y_min) / size[1], y_max / size[1])
    out = [
        (w, int(crosser), key[0], kind[key])
        for key, _, boxes, crosser in common.tracks(root, box)
        for w in te.windows(boxes)
    ]
    return out, size, hz


def report(name: str, rows, size, hz) -> None:
    w = np.array([r[0] for r in rows])
    y = np.array([r[1] for r in rows])
    q = te.quantities(w, size)
    h = np.array([hz.get(r[2], np.nan) for r in rows])
    ok = ~np.isnan(h)
    print(f"{name}: {len(y)} windows, {y.sum()} crossing")
    print(
        f"  cues: height {roc_auc_score(y, q['height']):.3f}, bottom {roc_auc_score(y, q['bottom']):.3f}, "
        f"bottom less its horizon {roc_auc_score(y[ok], q['bottom'][ok] - h[ok]):.3f}; horizon alone "
        f"{roc_auc_score(y[ok], h[ok]):.3f}, its sd over windows {np.std(h[ok]):.3f}"
    )
    for label, cls in ((0, "not crossing"), (1, "crossing")):
        m = y == label
        p10, p50, p90 = np.percentile(q["height"][m], [10, 50, 90])
        print(
            f"  {cls}: height p10 / p50 / p90 {p10:.3f} / {p50:.3f} / {p90:.3f}, "
            f"median bottom {np.median(q['bottom'][m]):.3f}"
        )
        kinds = np.array([r[3] for r in rows])
        for k in sorted(set(kinds[m])):
            mk = m & (kinds == k)
            print(f"    {k:28s} {mk.sum():6d} windows, median height {np.median(q['height'][mk]):.3f}")


def track_ends(name: str, tracks, length) -> None:
    """Non-crossers' tracks of 76+ frames: the share that ends with its video or clip (within 3 frames), and the
    box height 3 frames before the end (where the benchmark's last window ends), for those and the others."""
    ends = np.array([(last >= length[g] - 3, h) for g, last, h in tracks])
    at_end, earlier = ends[ends[:, 0] == 1, 1], ends[ends[:, 0] == 0, 1]
    print(
        f"{name}: {len(ends)} non-crossers' tracks, {100 * len(at_end) / len(ends):.0f} % end with the "
        f"video or clip (median last height {np.median(at_end):.3f}), the others earlier ({np.median(earlier):.3f})"
    )


def synthetic_ends(root: Path):
    spec = common.spec(root)
    frames = {
        r["clip_id"]: r["frame_count"]
        for r in ds.dataset(str(root / "tables/clips"), format="parquet")
        .to_table(columns=["clip_id", "frame_count"])
        .to_pylist()
    }
    height = spec["sensors"]["rgb"]["height_px"]
    out = [
        (key[0], int(f[-1]), (boxes[-3, 3] - boxes[-3, 1]) / height)
        for key, f, boxes, crosser in common.tracks(root, box_kind(spec))
        if not crosser
    ]
    return out, frames


def main() -> int:
    windows, ends = real()
    report("JAAD train", *windows)
    report(sys.argv[1], *synthetic(Path(sys.argv[1])))
    track_ends("JAAD train", *ends)
    track_ends(sys.argv[1], *synthetic_ends(Path(sys.argv[1])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
