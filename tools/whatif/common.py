"""What the what-ifs share: a generated dataset's tracks cut as tools/transfer_eval.py cuts them, and the two
figures (transfer AUC on JAAD val, domain AUC against JAAD train) of windows made from transformed tracks."""
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.dataset as ds
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import transfer_eval as t  # noqa: E402


def spec(root: Path) -> dict:
    return yaml.safe_load((root / "spec.resolved.yaml").read_text())


def tracks(root: Path, box: str):
    """(clip, pedestrian), frames and boxes (x_min, y_min, x_max, y_max) of every track long enough for the
    benchmark, crossers cut at their first crossing frame, and whether it is a crosser; `box`: annotator|bbox."""
    edges = [f"{box}_x_min", f"{box}_y_min", f"{box}_x_max", f"{box}_y_max"]
    crosser = {
        (r["clip_id"], r["pedestrian"]): r["crosser"]
        for r in ds.dataset(str(root / "tables/pedestrians"), format="parquet")
        .to_table(columns=["clip_id", "pedestrian", "crosser"])
        .to_pylist()
    }
    tb = ds.dataset(str(root / "tables/annotations"), format="parquet").to_table(
        columns=["clip_id", "pedestrian", "frame", "crossing", *edges]
    )
    cols = {n: tb.column(n).to_numpy(zero_copy_only=False) for n in tb.column_names}
    by = defaultdict(list)
    for i in range(tb.num_rows):
        by[(cols["clip_id"][i], int(cols["pedestrian"][i]))].append(i)
    for key in sorted(by):
        idx = sorted(by[key], key=lambda i: cols["frame"][i])
        if crosser[key]:
            first = next((j for j, i in enumerate(idx) if cols["crossing"][i]), None)
            idx = idx[: first + 1] if first is not None else []
        if len(idx) < t.MIN_TRACK:
            continue
        boxes = np.stack([cols[c][idx] for c in edges], 1).astype(float)
        yield key, cols["frame"][idx], boxes, bool(crosser[key])


def evaluate(label: str, root: Path, box: str, transform) -> None:
    """Prints the transfer and domain AUC of windows of `transform(key, frames, boxes)` for every track."""
    s = spec(root)["sensors"]["rgb"]
    xs, ys, gs = [], [], []
    for key, frames, boxes, crosser in tracks(root, box):
        for w in t.windows(transform(key, frames, boxes)):
            xs.append(w)
            ys.append(int(crosser))
            gs.append(key[0])
    xs, ys, gs = np.array(xs), np.array(ys), np.array(gs)
    real = Path("../shared/real/jaad_trainval")
    xr, _, sr, gr = t.real_windows_grouped(real, "train")
    xv, yv, sv = t.real_windows(real, "val")
    fr, fv, fs = t.features(xr, sr), t.features(xv, sv), t.features(xs, (s["width_px"], s["height_px"]))
    transfer = t.auc(yv, t.classifier().fit(fs, ys).predict_proba(fv)[:, 1])
    print(label, "transfer", round(transfer, 3), "domain", round(t.domain_auc(fr, fs, gr, gs), 3))
