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
import yaml
from sklearn.metrics import roc_auc_score

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import transfer_eval as te  # noqa: E402

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
    out = []
    for key in sorted(tracks):
        rows = sorted(tracks[key])
        p = peds.get(key, {})
        event = p.get("crossing_point") if "b" in key[1] else -1
        event = -1 if event is None else int(event)
        rows = rows[: [r[0] for r in rows].index(event) + 1] if event != -1 else rows[:-2]
        label = int("b" in key[1] and (p.get("crossing") or 0) > 0)
        if len(rows) >= te.MIN_TRACK:
            for w in te.windows(np.array([r[1:] for r in rows], dtype=np.float64)):
                out.append((w, label, key[0], "jaad"))
    return out, size, hz


def synthetic(root: Path):
    spec = yaml.safe_load((root / "spec.resolved.yaml").read_text())
    size = (spec["sensors"]["rgb"]["width_px"], spec["sensors"]["rgb"]["height_px"])
    box = "annotator" if spec.get("annotations", {}).get("export_box") == "annotator" else "bbox"
    edges = [f"{box}_x_min", f"{box}_y_min", f"{box}_x_max", f"{box}_y_max"]
    peds = {
        (r["clip_id"], r["pedestrian"]): r
        for r in ds.dataset(str(root / "tables/pedestrians"), format="parquet")
        .to_table(columns=["clip_id", "pedestrian", "crosser", "role", "behaviour"])
        .to_pylist()
    }
    tab = ds.dataset(str(root / "tables/annotations"), format="parquet").to_table(
        columns=["clip_id", "pedestrian", "frame", "crossing", "occlusion", *edges]
    )
    c = {n: tab.column(n).to_numpy(zero_copy_only=False) for n in tab.column_names}
    clear = c["occlusion"] == 0
    hz = horizons(
        c["clip_id"][clear],
        (c[edges[3]][clear] - c[edges[1]][clear]) / size[1],
        c[edges[3]][clear] / size[1],
    )
    tracks = defaultdict(list)
    for i in range(tab.num_rows):
        tracks[(c["clip_id"][i], int(c["pedestrian"][i]))].append(i)
    out = []
    for key in sorted(tracks):
        idx = sorted(tracks[key], key=lambda i: c["frame"][i])
        p = peds[key]
        if p["crosser"]:
            first = next((k for k, i in enumerate(idx) if c["crossing"][i]), None)
            idx = idx[: first + 1] if first is not None else []
        if len(idx) >= te.MIN_TRACK:
            arr = np.stack([c[e][idx] for e in edges], axis=1).astype(np.float64)
            for w in te.windows(arr):
                out.append((w, int(p["crosser"]), key[0], f"{p['role']}/{p['behaviour']}"))
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


def real_ends():
    videos = {v["video"]: v for v in pq.read_table(REAL / "videos.parquet").to_pylist() if v["split"] == "train"}
    peds = {(p["video"], p["pedestrian"]): p for p in pq.read_table(REAL / "pedestrians.parquet").to_pylist()}
    tracks = defaultdict(list)
    for r in pq.read_table(REAL / "boxes.parquet", columns=["video", "pedestrian", "frame", "y_min", "y_max"]).to_pylist():
        if r["video"] in videos and "p" not in r["pedestrian"]:
            tracks[(r["video"], r["pedestrian"])].append((r["frame"], (r["y_max"] - r["y_min"]) / videos[r["video"]]["height"]))
    out = []
    for key, rows in tracks.items():
        p = peds.get(key, {})
        if not ("b" in key[1] and (p.get("crossing") or 0) > 0) and len(rows) >= te.MIN_TRACK:
            rows.sort()
            out.append((key[0], rows[-1][0], rows[-3][1]))
    return out, {v: videos[v]["num_frames"] for v in videos}


def synthetic_ends(root: Path):
    spec = yaml.safe_load((root / "spec.resolved.yaml").read_text())
    height = spec["sensors"]["rgb"]["height_px"]
    box = "annotator" if spec.get("annotations", {}).get("export_box") == "annotator" else "bbox"
    frames = {
        r["clip_id"]: r["frame_count"]
        for r in ds.dataset(str(root / "tables/clips"), format="parquet").to_table(columns=["clip_id", "frame_count"]).to_pylist()
    }
    crosser = {
        (r["clip_id"], r["pedestrian"]): r["crosser"]
        for r in ds.dataset(str(root / "tables/pedestrians"), format="parquet")
        .to_table(columns=["clip_id", "pedestrian", "crosser"])
        .to_pylist()
    }
    t = ds.dataset(str(root / "tables/annotations"), format="parquet").to_table(
        columns=["clip_id", "pedestrian", "frame", f"{box}_y_min", f"{box}_y_max"]
    ).to_pydict()
    tracks = defaultdict(list)
    for c, p, f, y0, y1 in zip(t["clip_id"], t["pedestrian"], t["frame"], t[f"{box}_y_min"], t[f"{box}_y_max"]):
        tracks[(c, p)].append((f, (y1 - y0) / height))
    out = []
    for key, rows in tracks.items():
        if not crosser[key] and len(rows) >= te.MIN_TRACK:
            rows.sort()
            out.append((key[0], rows[-1][0], rows[-3][1]))
    return out, frames


def main() -> int:
    report("JAAD train", *real())
    report(sys.argv[1], *synthetic(Path(sys.argv[1])))
    track_ends("JAAD train", *real_ends())
    track_ends(sys.argv[1], *synthetic_ends(Path(sys.argv[1])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
