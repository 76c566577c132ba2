#!/usr/bin/env python3
"""Reads a pedsynth dataset's LiDAR with pyarrow and numpy only, as DATASET.md's example does, and checks it
independently of pedsynth's own reader: every point is registered into the world with the `sensor_poses` table
(quaternion → matrix by hand, CARLA's y-right flipped), and every point tagged Pedestrian (12) of an annotated
pedestrian must lie in that pedestrian's 3D box from the `annotations` table (1 mm for float rounding). Optionally writes the
bird's-eye view of a frame pair coloured by tag as a PPM image.

Usage: tools/lidar_bev.py DATASET [--image FILE.ppm]
Exit 0 when every checked point is inside its box, 1 otherwise.
"""
import argparse
import sys

import numpy as np
import pyarrow.dataset as ds
import pyarrow.parquet as pq


def quat_matrix(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


PALETTE = {1: (128, 64, 128), 2: (244, 35, 232), 3: (70, 70, 70), 6: (153, 153, 153), 9: (107, 142, 35),
           10: (145, 170, 100), 12: (220, 20, 60), 14: (0, 0, 142), 24: (157, 234, 50), 25: (81, 0, 81)}


def columns(path, names):
    t = pq.read_table(path, columns=names)
    return {n: t.column(n).to_numpy(zero_copy_only=False) for n in names}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("--image")
    args = ap.parse_args()
    root = args.dataset
    checked = outside = 0
    first = None
    for path in sorted(ds.dataset(f"{root}/sensors/lidar", format="parquet").files):
        pts = columns(path, ["clip_id", "frame", "x", "y", "z", "tag", "instance", "actor_id"])
        clip = pts["clip_id"][0]
        pose = columns(f"{root}/tables/sensor_poses/{clip}.parquet",
                       ["frame", "sensor", "x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"])
        lidar = {int(f): i for i, f in enumerate(pose["frame"]) if pose["sensor"][i] == "lidar"}
        ann = columns(f"{root}/tables/annotations/{clip}.parquet",
                      ["frame", "pedestrian", "yaw_rad", "box3d_x_m", "box3d_y_m", "box3d_z_m",
                       "box3d_length_m", "box3d_width_m", "box3d_height_m"])
        boxes = {(int(f), int(p)): i for i, (f, p) in enumerate(zip(ann["frame"], ann["pedestrian"]))}
        world = np.empty((len(pts["frame"]), 3))
        for frame in np.unique(pts["frame"]):
            idx = np.flatnonzero(pts["frame"] == frame)
            k = lidar[int(frame)]
            r = quat_matrix(pose["qw"][k], pose["qx"][k], pose["qy"][k], pose["qz"][k])
            local = np.stack([pts["x"][idx], -pts["y"][idx], pts["z"][idx]], axis=1)
            world[idx] = local @ r.T + [pose["x_m"][k], pose["y_m"][k], pose["z_m"][k]]
        if first is None:
            f0 = pts["frame"][0]
            sel = (pts["frame"] == f0) | (pts["frame"] == f0 + 1)
            first = (world[sel], pts["tag"][sel])
        ped = (pts["tag"] == 12) & (pts["instance"] < 16384)
        for i in np.flatnonzero(ped):
            b = boxes.get((int(pts["frame"][i]), int(pts["actor_id"][i])))
            if b is None:
                continue
            c, s = np.cos(ann["yaw_rad"][b]), np.sin(ann["yaw_rad"][b])
            d = world[i] - [ann["box3d_x_m"][b], ann["box3d_y_m"][b], ann["box3d_z_m"][b]]
            local = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]])
            half = np.array([ann["box3d_length_m"][b], ann["box3d_width_m"][b], ann["box3d_height_m"][b]]) / 2 + 0.001
            checked += 1
            if (np.abs(local) > half).any():
                outside += 1
                if outside <= 5:
                    print(f"{clip} frame {pts['frame'][i]} pedestrian {pts['actor_id'][i]}: point {world[i]} "
                          "outside its box", file=sys.stderr)
    print(f"lidar_bev: {checked} pedestrian points of annotated pedestrians checked, {outside} outside their boxes")
    if args.image and first is not None:
        w, tags = first
        centre = w[:, :2].mean(axis=0)
        img = np.zeros((400, 400, 3), np.uint8)
        ij = ((w[:, :2] - centre) * 5 + 200).astype(int)
        ok = (ij >= 0).all(axis=1) & (ij < 400).all(axis=1)
        img[399 - ij[ok, 1], ij[ok, 0]] = [PALETTE.get(int(t), (150, 150, 150)) for t in tags[ok]]
        with open(args.image, "wb") as f:
            f.write(b"P6 400 400 255\n" + img.tobytes())
    return 0 if checked > 0 and outside == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
