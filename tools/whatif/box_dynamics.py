"""How box sizes change from frame to frame in JAAD train and in a generated set: share of frames whose
width / height stay the same, changes over the height, sign changes per window.

Not pedsynth code: a what-if measured on a generated dataset's tables before building anything (BENCHMARKS.md,
"Transfer to real data"). Run from the repository root: `python3 tools/whatif/box_dynamics.py DATASET `. Needs
../shared/real/jaad_trainval and tools/transfer_eval.py's packages.
"""
import sys; sys.path.insert(0,'tools')
import transfer_eval as t, numpy as np
from pathlib import Path
xs,ys,ss=t.synth_windows(Path(sys.argv[1]))
xr,yr,sr=t.real_windows(Path('../shared/real/jaad_trainval'),'train')
for name,w,(W,H) in [('JAAD train',xr,sr),('ours',xs,ss)]:
    h=(w[:,:,3]-w[:,:,1]); bw=(w[:,:,2]-w[:,:,0])
    dw=np.diff(bw,axis=1); dh=np.diff(h,axis=1)
    print(f'{name:10s} px at 1080: |dw|=0 {np.mean(np.abs(dw)<0.01):.2f} |dh|=0 {np.mean(np.abs(dh)<0.01):.2f}  |dw|/h p50 {np.median(np.abs(dw)/h[:,1:]):.4f} p90 {np.percentile(np.abs(dw)/h[:,1:],90):.4f}  |dh|/h p50 {np.median(np.abs(dh)/h[:,1:]):.4f} p90 {np.percentile(np.abs(dh)/h[:,1:],90):.4f}  sign changes of dh per window {np.mean(np.sum(np.diff(np.sign(dh),axis=1)!=0,axis=1)):.1f}')
