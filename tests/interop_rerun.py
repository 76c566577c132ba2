#!/usr/bin/env python3
"""Rerun interop (issue 45): rerun-sdk's own reader, pinned (tools/rerun-requirements.txt), opens
`pedsynth export rerun DATASET --clip ID --out CLIP.rrd` (a pedsynth built with `--features rerun`), and its
entity paths and row counts equal what our tables hold.

Usage: interop_rerun.py DATASET --pedsynth BIN [--out DIR]

For the dataset's first clip:
- the static entities: `world` (right-handed, z up), the camera's mount and pinhole, the keypoints' annotation
  context (COCO-17 with the skeleton), the LiDAR's mount;
- one row per frame for the ego's pose and speed, the RGB image and the instance image;
- one row of 2D boxes and one of 3D boxes per frame with annotated pedestrians, holding one box per
  `annotations` row; per pedestrian, one keypoints row and one state row per annotated frame, one TTE row per
  annotated frame before its first crossing frame;
- one LiDAR row per frame holding that frame's points; the vehicles' and cyclists' boxes per frame.
A clip that does not exist is refused with exit 2 naming the clips there are.
"""
import argparse
import collections
import os
import subprocess
import sys
import tempfile

import numpy as np
import pyarrow.dataset as pads
import rerun as rr


def fail(msg):
    print(f"interop_rerun: FAIL: {msg}")
    sys.exit(1)


def table(root, name, clip):
    t = pads.dataset(f"{root}/tables/{name}").to_table(filter=pads.field("clip_id") == clip)
    return t.to_pandas()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("--pedsynth", required=True)
    ap.add_argument("--out")
    args = ap.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="rerun-")
    clips = pads.dataset(f"{args.dataset}/tables/clips").to_table().to_pandas()
    clip = sorted(clips.clip_id)[0]
    rrd = os.path.join(out, f"{clip}.rrd")
    subprocess.run([args.pedsynth, "export", "rerun", args.dataset, "--clip", clip, "--out", rrd], check=True)
    bad = subprocess.run([args.pedsynth, "export", "rerun", args.dataset, "--clip", "no_such_clip", "--out",
                          os.path.join(out, "x.rrd")], capture_output=True, text=True)
    if bad.returncode != 2 or clip not in bad.stderr:
        fail(f"an unknown clip: exit {bad.returncode}, {bad.stderr!r}")

    store = rr.experimental.RrdReader(rrd).stream().collect()
    rows = collections.Counter()
    instances = collections.Counter()
    static = set()
    per_frame_points = {}
    for chunk in store.stream():
        path = chunk.entity_path.lstrip("/")
        if chunk.is_static:
            static.add(path)
            continue
        rb = chunk.to_record_batch()
        rows[path] += rb.num_rows
        for col, name in (("Boxes2D:half_sizes", "boxes2d"), ("Boxes3D:half_sizes", "boxes3d"),
                          ("Points3D:positions", "points")):
            if col in rb.schema.names:
                lengths = rb.column(col).value_lengths().to_numpy(zero_copy_only=False)
                instances[(path, name)] += int(np.nansum(lengths))
                if name == "points":
                    for f, n in zip(rb.column("frame").to_numpy(), lengths):
                        per_frame_points[int(f)] = int(n)

    for path in ("world", "world/ego/camera", "world/ego/camera/image", "world/ego/camera/image/keypoints",
                 "world/ego/lidar"):
        if path not in static:
            fail(f"static entity {path} missing (static: {sorted(static)})")

    frames = table(args.dataset, "frames", clip)
    ann = table(args.dataset, "annotations", clip)
    peds = table(args.dataset, "pedestrians", clip).set_index("pedestrian")
    sensors = table(args.dataset, "sensors", clip)
    n = len(frames)
    want = {
        "world/ego": n,
        "timeseries/ego/speed_mps": n,
        "world/ego/camera/image/rgb": int((sensors.stream == "rgb").sum()),
        "world/ego/camera/image/instance": int((sensors.stream == "instance").sum()),
        "world/ego/camera/image/boxes": ann.frame.nunique(),
        "world/pedestrians": ann.frame.nunique(),
    }
    for ped, group in ann.groupby("pedestrian"):
        want[f"world/ego/camera/image/keypoints/{ped}"] = len(group)
        want[f"timeseries/pedestrian_{ped}/state"] = len(group)
        first = peds.loc[ped, "first_crossing_frame"]
        if first == first and first is not None:
            before = int((group.frame <= first).sum())
            if before:
                want[f"timeseries/pedestrian_{ped}/tte_frames"] = before
    vehicles = table(args.dataset, "vehicles", clip)
    if len(vehicles):
        want["world/vehicles"] = vehicles.frame.nunique()
    cyclists = table(args.dataset, "cyclists", clip)
    if len(cyclists):
        want["world/cyclists"] = cyclists.frame.nunique()
    lidar_path = f"{args.dataset}/sensors/lidar/{clip}.parquet"
    if os.path.exists(lidar_path):
        points = pads.dataset(lidar_path).to_table(columns=["frame"]).to_pandas()
        want["world/ego/lidar/points"] = points.frame.nunique()
        ours = points.frame.value_counts().to_dict()
        if per_frame_points != {int(k): int(v) for k, v in ours.items()}:
            fail("LiDAR points per frame differ from the Parquet's")
    for path, count in sorted(want.items()):
        if rows[path] != count:
            fail(f"{path}: {rows[path]} rows, our tables say {count}")
    extra = sorted(set(rows) - set(want))
    if extra:
        fail(f"entities the tables do not account for: {extra}")
    if instances[("world/ego/camera/image/boxes", "boxes2d")] != len(ann):
        fail(f"{instances[('world/ego/camera/image/boxes', 'boxes2d')]} 2D boxes for {len(ann)} annotations")
    if instances[("world/pedestrians", "boxes3d")] != len(ann):
        fail(f"{instances[('world/pedestrians', 'boxes3d')]} 3D boxes for {len(ann)} annotations")
    if len(vehicles) and instances[("world/vehicles", "boxes3d")] != len(vehicles):
        fail(f"{instances[('world/vehicles', 'boxes3d')]} vehicle boxes for {len(vehicles)} vehicle rows")
    print(f"interop_rerun: OK: {rrd} ({os.path.getsize(rrd) / 1e6:.1f} MB): {len(rows)} temporal entities, "
          f"{sum(rows.values())} rows, {len(static)} static entities; {len(ann)} boxes, "
          f"{sum(per_frame_points.values())} LiDAR points, as the tables hold")


if __name__ == "__main__":
    main()
