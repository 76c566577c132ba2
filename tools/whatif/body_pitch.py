"""Per-frame body pitch of the ego (a braking dip, low-passed with 0.25 s, plus AR(1) road undulation with a
1 s correlation time) emulated on the boxes: every box shifts by f·tan(pitch) rows; prints the transfer AUC on
JAAD val and the domain AUC.

Not pedsynth code: a what-if measured on a generated dataset's tables before building anything (BENCHMARKS.md,
"Transfer to real data"). Run from the repository root: `python3 tools/whatif/body_pitch.py DATASET PITCH_DEG_PER_MPS2 ROAD_SD_DEG`. Needs
../shared/real/jaad_trainval and tools/transfer_eval.py's packages.
"""
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.dataset as ds

import common

root = Path(sys.argv[1]); k = float(sys.argv[2]); road_sd = float(sys.argv[3]); tau = 0.25
spec = common.spec(root); rgb = spec["sensors"]["rgb"]
f = rgb["width_px"] / 2 / np.tan(np.radians(rgb["fov_deg"]) / 2)
fps = spec["dataset"]["fps"]
box = "annotator" if spec["annotations"].get("export_box") == "annotator" else "bbox"
fr = ds.dataset(str(root / "tables/frames"), format="parquet").to_table(columns=["clip_id", "frame", "ego_accel_mps2"])
acc = defaultdict(dict)
for c, fi, a in zip(fr["clip_id"].to_pylist(), fr["frame"].to_pylist(), fr["ego_accel_mps2"].to_pylist()):
    acc[c][fi] = a
rng = np.random.default_rng(3)
pitch = {}
alpha = 1 - np.exp(-1 / fps / tau)
for c in sorted(acc):
    n = max(acc[c]) + 1
    a = np.array([acc[c].get(i, 0.0) for i in range(n)])
    p = np.zeros(n)
    for i in range(n):
        prev = p[i - 1] if i else k * a[0]
        p[i] = prev + alpha * (k * a[i] - prev)
    # road undulation: AR(1) with a 1 s correlation time, sd road_sd
    r = np.zeros(n); rho = np.exp(-1 / fps / 1.0)
    e = rng.normal(0, road_sd * np.sqrt(1 - rho**2), n); r[0] = rng.normal(0, road_sd)
    for i in range(1, n):
        r[i] = rho * r[i - 1] + e[i]
    pitch[c] = p + r  # degrees, positive nose up (braking: accel < 0 → nose down)


def shift(key, frames, a):
    # nose down (negative pitch) → the camera looks down → the scene moves up in the image
    dv = f * np.tan(np.radians(pitch[key[0]][frames]))
    a[:, 1] += dv
    a[:, 3] += dv
    return a


common.evaluate(f"{k} {road_sd}", root, box, shift)
