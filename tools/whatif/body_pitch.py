"""Per-frame body pitch of the ego (a braking dip, low-passed with 0.25 s, plus AR(1) road undulation with a
1 s correlation time) emulated on the boxes: every box shifts by f·tan(pitch) rows; prints the transfer AUC on
JAAD val and the domain AUC.

Not pedsynth code: a what-if measured on a generated dataset's tables before building anything (BENCHMARKS.md,
"Transfer to real data"). Run from the repository root: `python3 tools/whatif/body_pitch.py DATASET PITCH_DEG_PER_MPS2 ROAD_SD_DEG`. Needs
../shared/real/jaad_trainval and tools/transfer_eval.py's packages.
"""
import sys; sys.path.insert(0,'tools')
import transfer_eval as t, numpy as np, yaml, pyarrow.dataset as ds
from pathlib import Path
from collections import defaultdict
root=Path(sys.argv[1]); k=float(sys.argv[2]); road_sd=float(sys.argv[3]); tau=0.25
spec=yaml.safe_load((root/'spec.resolved.yaml').read_text()); W,H=spec['sensors']['rgb']['width_px'],spec['sensors']['rgb']['height_px']
f=W/2/np.tan(np.radians(spec['sensors']['rgb']['fov_deg'])/2)
fps=spec['dataset']['fps']
box='annotator' if spec['annotations'].get('export_box')=='annotator' else 'bbox'
edges=[f'{box}_x_min',f'{box}_y_min',f'{box}_x_max',f'{box}_y_max']
fr=ds.dataset(str(root/'tables/frames'),format='parquet').to_table(columns=['clip_id','frame','ego_accel_mps2'])
acc=defaultdict(dict)
for c,fi,a in zip(fr['clip_id'].to_pylist(),fr['frame'].to_pylist(),fr['ego_accel_mps2'].to_pylist()): acc[c][fi]=a
rng=np.random.default_rng(3)
pitch={}
alpha=1-np.exp(-1/fps/tau)
for c in sorted(acc):
    n=max(acc[c])+1; a=np.array([acc[c].get(i,0.0) for i in range(n)])
    p=np.zeros(n); 
    for i in range(n): p[i]=(p[i-1] if i else k*a[0])+alpha*(k*a[i]-(p[i-1] if i else k*a[0]))
    # road undulation: AR(1) with a 1 s correlation time, sd road_sd
    r=np.zeros(n); rho=np.exp(-1/fps/1.0); e=rng.normal(0,road_sd*np.sqrt(1-rho**2),n); r[0]=rng.normal(0,road_sd)
    for i in range(1,n): r[i]=rho*r[i-1]+e[i]
    pitch[c]=p+r   # degrees, positive nose up (braking: accel < 0 → nose down)
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
    # nose down (negative pitch) → the camera looks down → the scene moves up in the image
    dv=f*np.tan(np.radians(pitch[key[0]][cols['frame'][idx]]))
    a[:,1]+=dv; a[:,3]+=dv
    for w in t.windows(a): xs.append(w); ys.append(1 if crosser[key] else 0)
xs,ys=np.array(xs),np.array(ys)
xr,yr,sr=t.real_windows(Path('../shared/real/jaad_trainval'),'train'); xv,yv,sv=t.real_windows(Path('../shared/real/jaad_trainval'),'val')
fr_,fv,fs=t.features(xr,sr),t.features(xv,sv),t.features(xs,(W,H))
print(k,road_sd,'transfer',round(t.auc(yv,t.classifier().fit(fs,ys).predict_proba(fv)[:,1]),3),'domain',round(t.domain_auc(fr_,fs),3))
