"""Annotator boxes drawn at keyframes every K frames and linearly interpolated (K > 1), or with their size and
place smoothed over -K frames (K < 0), then whole pixels; prints the transfer AUC and the domain AUC.

Not pedsynth code: a what-if measured on a generated dataset's tables before building anything (BENCHMARKS.md,
"Transfer to real data"). Run from the repository root: `python3 tools/whatif/annotator_keyframes.py DATASET K annotator|bbox`. Needs
../shared/real/jaad_trainval and tools/transfer_eval.py's packages.
"""
import sys
from pathlib import Path

import numpy as np

import common

root = Path(sys.argv[1]); K = int(sys.argv[2]); src = sys.argv[3]


def redraw(key, frames, a):
    fr = frames.astype(float)
    if K < 0:  # size and place smoothed over -K frames
        k = -K; ker = np.ones(k) / k
        pad = lambda v: np.convolve(np.pad(v, (k // 2, k - 1 - k // 2), mode="edge"), ker, mode="valid")
        hh = np.round(pad(a[:, 3] - a[:, 1])); ww = np.round(pad(a[:, 2] - a[:, 0]))
        bb = np.round(pad(a[:, 3])); cc = pad((a[:, 0] + a[:, 2]) / 2)
        a = np.stack([np.round(cc - ww / 2), bb - hh, np.round(cc - ww / 2) + ww, bb], 1)
    if K > 1:  # keyframes every K frames, linear between, whole pixels
        keys = np.arange(0, len(a), K)
        if keys[-1] != len(a) - 1:
            keys = np.append(keys, len(a) - 1)
        a = np.round(np.stack([np.interp(fr, fr[keys], a[keys, j]) for j in range(4)], 1))
    return a


common.evaluate(f"{K} {src}", root, src, redraw)
