"""What-if on a generated dataset's boxes before building the pitch wobble and the horizon quantiles (BENCHMARKS.md,
"The car's nod and the videos' horizons"): each clip's boxes shifted by f·tan(pitch) rows of a smooth two-lag pitch
(`--pitch SD_DEG --T SECONDS`), and/or each clip's horizon (median of bottom − 0.818 × height) rank-mapped onto JAAD
train's videos' (`--remap 1`); with `--box bbox` (the default) the annotator box is redrawn from the tight box (margin,
aspect, 5.8 px pad, noise `--npx` + `--nfrac` × height, keyframes every 2–10 frames, whole pixels). Prints the
transfer AUC on JAAD val, the grouped domain AUC (class-matched) and that AUC on the top edge alone and on the x
edges alone.

Not pedsynth code. Run from the repository root:
`python3 tools/whatif/nod_horizons.py DATASET [--remap 1] [--pitch 0.47 --T 0.35] [--nfrac 0.01]`. Needs
../shared/real/jaad_trainval and tools/transfer_eval.py's packages.
"""
import sys, argparse
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
sys.path.insert(0, str(Path(__file__).resolve().parent)); sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from collections import defaultdict
import common, transfer_eval as t
ap=argparse.ArgumentParser(); ap.add_argument('root'); ap.add_argument('--remap',type=int,default=0); ap.add_argument('--pitch',type=float,default=0); ap.add_argument('--T',type=float,default=0.35)
ap.add_argument('--nfrac',type=float,default=0); ap.add_argument('--npx',type=float,default=0.5); ap.add_argument('--smooth',type=float,default=0); ap.add_argument('--box',default='bbox')
A=ap.parse_args(); root=Path(A.root)
spec=common.spec(root); rgb=spec['sensors']['rgb']; H=rgb['height_px']; W=rgb['width_px']; fps=spec['dataset']['fps']
f=W/2/np.tan(np.radians(rgb['fov_deg'])/2)
rng=np.random.default_rng(7)
tr=list(common.tracks(root,A.box))
shift=defaultdict(float)
if A.remap:
    real=Path(__file__).resolve().parents[3]/'shared/real/jaad_trainval'
    videos=pq.read_table(real/'videos.parquet').to_pylist(); keep={v['video'] for v in videos if v['split']=='train'}
    b=pq.read_table(real/'boxes.parquet',columns=['video','y_min','y_max','occlusion']).to_pandas()
    b=b[b.video.isin(keep)&(b.occlusion==0)]
    h=(b.y_max-b.y_min)/1080; rv=(b.y_max/1080-0.818*h).groupby(b.video).median().values
    per=defaultdict(list)
    for key,fr,a,c in tr:
        hh=(a[:,3]-a[:,1])/H; per[key[0]]+=list(a[:,3]/H-0.818*hh)
    clips=sorted(per); oc=np.array([np.median(per[c]) for c in clips])
    rank=np.argsort(np.argsort(oc))/(len(oc)-1)
    shift.update(dict(zip(clips,(np.quantile(rv,rank)-oc)*H)))
pitch={}
def clip_pitch(clip):
    if clip not in pitch:
        if A.pitch<=0: pitch[clip]=np.zeros(3000); return pitch[clip]
        k=fps*A.T; rho=np.exp(-1/k); sdi=A.pitch*(1+rho)/np.sqrt(1+rho*rho); inn=sdi*np.sqrt(1-rho*rho)
        z=rng.normal(size=int(10*k)+3000); inner=0.0; off=0.0; out=[]
        for i,zz in enumerate(z):
            inner=rho*inner+inn*zz; off=rho*off+(1-rho)*inner
            if i>=int(10*k): out.append(off)
        pitch[clip]=np.array(out)
    return pitch[clip]
def smooth(v,k):
    pad=np.pad(v,(k//2,k//2),mode='edge'); return np.convolve(pad,np.ones(k)/k,mode='valid')[:len(v)]
def redraw(key,frames,a):
    a=a.copy(); dv=shift[key[0]]+f*np.tan(np.radians(clip_pitch(key[0])[frames.astype(int)]))
    a[:,1]+=dv; a[:,3]+=dv
    if A.box!='bbox': return a
    x0,y0,x1,y1=a.T; h=y1-y0; cx=(x0+x1)/2; cy=(y0+y1)/2; w=x1-x0
    k=int(round(A.smooth*fps))|1
    if k>1: w=smooth(w,k); cx=smooth(cx,k)
    margin=rng.uniform(0,0.06); mina=rng.uniform(0.28,0.46)
    hd=h*(1+margin); wd=np.maximum(w+margin*h, mina*hd+5.8)
    n=len(a); sd=A.npx+A.nfrac*h
    B=np.stack([cx-wd/2,cy-hd/2,cx+wd/2,cy+hd/2],1)+rng.normal(size=(n,4))*sd[:,None]
    X=np.stack([B[:,0],B[:,1],B[:,2]-B[:,0],B[:,3]-B[:,1]],1)
    keys=[0]
    while keys[-1]<n-1: keys.append(min(n-1,keys[-1]+rng.integers(2,11)))
    out=np.zeros_like(X)
    for j in range(4): out[:,j]=np.interp(np.arange(n),keys,X[keys,j])
    out=np.round(out)
    return np.stack([out[:,0],out[:,1],out[:,0]+out[:,2],out[:,1]+out[:,3]],1)
xs,ys,gs=[],[],[]
for key,frames,boxes,c in tr:
    for w in t.windows(redraw(key,frames,boxes)): xs.append(w); ys.append(int(c)); gs.append(key[0])
xs,ys,gs=np.array(xs),np.array(ys),np.array(gs)
real=Path(__file__).resolve().parents[3]/'shared/real/jaad_trainval'
xr,yr,sr,gr=t.real_windows_grouped(real,'train'); xv,yv,sv=t.real_windows(real,'val')
fr,fv,fs=t.features(xr,sr),t.features(xv,sv),t.features(xs,(W,H))
tra=t.auc(yv,t.classifier().fit(fs,ys).predict_proba(fv)[:,1])
m=t.class_matched(yr,ys)
d=t.domain_auc(fr,fs[m],gr,gs[m])
r3=fr.reshape(len(fr),16,4); s3=fs[m].reshape(len(m),16,4)
dy=t.domain_auc(r3[:,:,1],s3[:,:,1],gr,gs[m]); dx=t.domain_auc(r3[:,:,[0,2]].reshape(len(fr),-1),s3[:,:,[0,2]].reshape(len(m),-1),gr,gs[m])
print(f'{vars(A)} transfer {tra:.3f} domain {d:.3f} y0-only {dy:.3f} x-only {dx:.3f}',flush=True)
