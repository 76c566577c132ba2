"""Two geometric what-ifs on the boxes: the ego's heading wobbling (an AR(1) yaw with a 1 s correlation time:
every box of a clip shifts by f·tan(yaw) columns, as a turning or weaving car pans its camera) and non-crossers
standing farther to the side (each non-crossing track moved outward by a per-track draw of U(0, EXTRA) metres,
in pixels at its distance: metres × box height / 1.70 m); prints the transfer AUC on JAAD val and the domain
AUC.

Not pedsynth code: a what-if measured on a generated dataset's tables before building anything (BENCHMARKS.md,
"Transfer to real data"). Run from the repository root:
`python3 tools/whatif/lateral_pan.py DATASET YAW_SD_DEG NC_EXTRA_M`. Needs ../shared/real/jaad_trainval and
tools/transfer_eval.py's packages.
"""
import sys
from pathlib import Path

import numpy as np

import common

root = Path(sys.argv[1]); yaw_sd = float(sys.argv[2]); extra = float(sys.argv[3])
spec = common.spec(root); rgb = spec["sensors"]["rgb"]
W = rgb["width_px"]
f = W / 2 / np.tan(np.radians(rgb["fov_deg"]) / 2)
fps = spec["dataset"]["fps"]
box = "annotator" if spec["annotations"].get("export_box") == "annotator" else "bbox"
crossers = {key: c for key, _, _, c in common.tracks(root, box)}
rng = np.random.default_rng(5)
yaw = {}


def clip_yaw(clip: str, n: int) -> np.ndarray:
    if clip not in yaw or len(yaw[clip]) < n:
        rho = np.exp(-1 / fps / 1.0)
        r = np.zeros(n); r[0] = rng.normal(0, yaw_sd)
        e = rng.normal(0, yaw_sd * np.sqrt(1 - rho**2), n)
        for i in range(1, n):
            r[i] = rho * r[i - 1] + e[i]
        yaw[clip] = r
    return yaw[clip]


def redraw(key, frames, a):
    a = a.copy()
    y = clip_yaw(key[0], int(frames.max()) + 1)[frames.astype(int)]
    dx = f * np.tan(np.radians(y))
    if not crossers[key] and extra > 0:
        side = np.sign(np.mean(a[:, 0] + a[:, 2]) / 2 - W / 2) or 1.0
        dx = dx + side * rng.uniform(0, extra) * (a[:, 3] - a[:, 1]) / 1.70
    a[:, 0] += dx; a[:, 2] += dx
    return a


common.evaluate(f"yaw sd {yaw_sd} deg, non-crossers +U(0, {extra}) m outward", root, box, redraw)
