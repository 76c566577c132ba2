"""Which parts of the 16-box windows give a generated set away: the domain classifier (synthetic vs JAAD
train, 5-fold grouped by clip and video, as tools/transfer_eval.py) on feature groups alone.

Not pedsynth code: a what-if measured on a generated dataset's tables before building anything (BENCHMARKS.md,
"Transfer to real data"). Run from the repository root: `python3 tools/whatif/domain_parts.py DATASET `. Needs
../shared/real/jaad_trainval and tools/transfer_eval.py's packages.
"""
import sys; sys.path.insert(0,'tools')
import transfer_eval as t, numpy as np
from pathlib import Path
xs,ys,ss,gs=t.synth_windows_grouped(Path(sys.argv[1]))
xr,yr,sr,gr=t.real_windows_grouped(Path('../shared/real/jaad_trainval'),'train')
def parts(w,size):
    W,H=size
    x0,y0,x1,y1=[w[:,:,i] for i in range(4)]
    h=(y1-y0)/H; bw=(x1-x0)/W; cx=(x0+x1)/2/W; b=y1/H
    dh=np.diff(h,axis=1); dcx=np.diff(cx,axis=1); db=np.diff(b,axis=1)
    return {'cx':cx,'bottom':b,'h':h,'w':bw,'dynamics (d cx, d h, d bottom over h)':np.concatenate([dcx/h[:,1:],dh/h[:,1:],db/h[:,1:]],1),
            'size+place at the last frame':np.stack([cx[:,-1],b[:,-1],h[:,-1],bw[:,-1]],1),
            'second differences over h':np.concatenate([np.diff(cx,2,axis=1)/h[:,2:],np.diff(h,2,axis=1)/h[:,2:],np.diff(b,2,axis=1)/h[:,2:]],1)}
ps,pr=parts(xs,ss),parts(xr,sr)
for k in ps: print(f'{k:45s} domain AUC {t.domain_auc(pr[k],ps[k],gr,gs):.3f}')


# Finer: the dynamics and the window's shape by part.
def parts2(w, size):
    W, H = size
    x0, y0, x1, y1 = [w[:, :, i] for i in range(4)]
    h = (y1 - y0) / H; cx = (x0 + x1) / 2 / W; b = y1 / H; bw = (x1 - x0) / W
    tot = lambda v: (v[:, -1] - v[:, 0])[:, None]
    steps = np.arange(16)
    resid = lambda v: np.std(v - np.polyval(np.polyfit(steps, v.T, 1), steps[:, None]).T, axis=1)
    return {'d cx / h': np.diff(cx, axis=1) / h[:, 1:], 'd h / h': np.diff(h, axis=1) / h[:, 1:],
            'd bottom / h': np.diff(b, axis=1) / h[:, 1:], 'd w / h': np.diff(bw, axis=1) / h[:, 1:],
            'total change of cx, h, bottom, w over the window / h': np.concatenate([tot(cx), tot(h), tot(b), tot(bw)], 1) / h[:, :1],
            'residual sd of cx, h about a 16-frame line / h': np.stack([resid(cx), resid(h)], 1) / h[:, :1]}
ps, pr = parts2(xs, ss), parts2(xr, sr)
for k in ps: print(f'{k:52s} domain AUC {t.domain_auc(pr[k], ps[k], gr, gs):.3f}')
