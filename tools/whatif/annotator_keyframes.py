"""Annotator boxes drawn at keyframes every K frames and linearly interpolated (K > 1), or with their size and
place smoothed over -K frames (K < 0), then whole pixels; prints the transfer AUC and the domain AUC.

Not pedsynth code: a what-if measured on a generated dataset's tables before building anything (BENCHMARKS.md,
"Transfer to real data"). Run from the repository root: `python3 tools/whatif/annotator_keyframes.py DATASET K annotator|bbox`. Needs
../shared/real/jaad_trainval and tools/transfer_eval.py's packages.
"""
import sys; sys.path.insert(0,'tools')
import transfer_eval as t, numpy as np, yaml, pyarrow.dataset as ds
from pathlib import Path
from collections import defaultdict
root=Path(sys.argv[1]); K=int(sys.argv[2]); src=sys.argv[3]
spec=yaml.safe_load((root/'spec.resolved.yaml').read_text()); W,H=spec['sensors']['rgb']['width_px'],spec['sensors']['rgb']['height_px']
edges=[f'{src}_x_min',f'{src}_y_min',f'{src}_x_max',f'{src}_y_max']
crosser={(r['clip_id'],r['pedestrian']):r['crosser'] for r in ds.dataset(str(root/'tables/pedestrians'),format='parquet').to_table(columns=['clip_id','pedestrian','crosser']).to_pylist()}
tb=ds.dataset(str(root/'tables/annotations'),format='parquet').to_table(columns=['clip_id','pedestrian','frame','crossing',*edges])
cols={n:tb.column(n).to_numpy(zero_copy_only=False) for n in tb.column_names}
tracks=defaultdict(list)
for i in range(tb.num_rows): tracks[(cols['clip_id'][i],int(cols['pedestrian'][i]))].append(i)
xs,ys=[],[]
for key in sorted(tracks):
    idx=sorted(tracks[key],key=lambda i: cols['frame'][i])
    if crosser[key]:
        first=next((j for j,i in enumerate(idx) if cols['crossing'][i]),None); idx=idx[:first+1] if first is not None else []
    if len(idx)<t.MIN_TRACK: continue
    a=np.stack([cols[c][idx] for c in edges],1).astype(float)
    fr=cols['frame'][idx].astype(float)
    if K<0:
        k=-K; ker=np.ones(k)/k
        pad=lambda v: np.convolve(np.pad(v,(k//2,k-1-k//2),mode="edge"),ker,mode="valid")
        hh=np.round(pad(a[:,3]-a[:,1])); ww=np.round(pad(a[:,2]-a[:,0])); bb=np.round(pad(a[:,3])); cc=pad((a[:,0]+a[:,2])/2)
        a=np.stack([np.round(cc-ww/2),bb-hh,np.round(cc-ww/2)+ww,bb],1)
    if K>1:
        keys=np.arange(0,len(a),K)
        if keys[-1]!=len(a)-1: keys=np.append(keys,len(a)-1)
        a=np.stack([np.interp(fr,fr[keys],a[keys,j]) for j in range(4)],1)
        a=np.round(a)
    for w in t.windows(a): xs.append(w); ys.append(1 if crosser[key] else 0)
xs,ys=np.array(xs),np.array(ys)
xr,yr,sr=t.real_windows(Path('../shared/real/jaad_trainval'),'train'); xv,yv,sv=t.real_windows(Path('../shared/real/jaad_trainval'),'val')
fr_,fv,fs=t.features(xr,sr),t.features(xv,sv),t.features(xs,(W,H))
print(K,src,'transfer',round(t.auc(yv,t.classifier().fit(fs,ys).predict_proba(fv)[:,1]),3),'domain',round(t.domain_auc(fr_,fs),3))
