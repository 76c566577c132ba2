#!/usr/bin/env python3
"""nuScenes interop (issue 45): nuscenes-devkit, unmodified and pinned (tools/nuscenes-requirements.txt), opens
`pedsynth export nuscenes` of a dataset, and what it returns is what our tables hold.

Usage: interop_nuscenes.py DATASET --pedsynth BIN [--out DIR]

- `NuScenes(version='v1.0-pedsynth', dataroot=...)` loads every table; every scene's sample chain has
  `nbr_samples` samples from its first to its last token; every sample has CAM_FRONT and LIDAR_TOP.
- `get_sample_data` returns each keyframe's boxes and file; `box_velocity` is finite for every annotation
  with a neighbour within the devkit's time limits, and for pedestrians within a median 0.3 m/s of the
  tables' velocity.
- `render_sample_data` draws a camera and a LiDAR frame (nsweeps 1 and 2, over the map) without error; a
  keyframe's two sweeps (`from_file_multisweep`, nsweeps=2) cover every 10° sector of azimuth.
- The `.pcd.bin` points are our Parquet points of the frame (y flipped to the right-handed frame), in order;
  every LiDAR point of an annotated pedestrian lies in its box (the devkit's `points_in_box`), and
  `num_lidar_pts` is the devkit's count of points in the box.
- The pedestrians' 3D keypoints (our `keypoints_3d`, world) projected with the exported ego pose, calibration
  and the devkit's `view_points` land on our 2D keypoints; each tight 2D box lies inside its 3D box's
  projection (within a pixel), with a median IoU of at least 0.5 between the two.
- Every annotated pedestrian of a keyframe has one box, with nuScenes' pedestrian attributes; `splits.json`
  lists the clips by split.
- Every parked car's box is a `vehicle.car` with `vehicle.parked`, of its `parked_cars` row's size and place, and
  holds every LiDAR point of its instance.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np  # noqa: E402
import pyarrow.dataset as pads  # noqa: E402
from nuscenes.nuscenes import NuScenes  # noqa: E402
from nuscenes.utils.data_classes import LidarPointCloud  # noqa: E402
from nuscenes.utils.geometry_utils import BoxVisibility, points_in_box, view_points  # noqa: E402
from pyquaternion import Quaternion  # noqa: E402

VERSION = "v1.0-pedsynth"
PED_ATTRS = {"pedestrian.moving", "pedestrian.standing", "pedestrian.sitting_lying_down"}


def fail(msg):
    print(f"interop_nuscenes: FAIL: {msg}")
    sys.exit(1)


def annotations_of(nusc, sample, kind):
    """The sample's annotations of instances of `kind`: (token, annotation, instance, attribute names)."""
    for tok in sample["anns"]:
        a = nusc.get("sample_annotation", tok)
        inst = nusc.get("instance", a["instance_token"])
        if inst["kind"] == kind:
            yield tok, a, inst, {nusc.get("attribute", t)["name"] for t in a["attribute_tokens"]}


def table(root, name):
    return pads.dataset(f"{root}/tables/{name}").to_table().to_pandas()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("--pedsynth", required=True)
    ap.add_argument("--out")
    args = ap.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="nusc-")
    subprocess.run([args.pedsynth, "export", "nuscenes", args.dataset, "--out", out], check=True)
    nusc = NuScenes(version=VERSION, dataroot=out, verbose=False)

    clips = table(args.dataset, "clips").set_index("clip_id")
    ann = table(args.dataset, "annotations")
    frames_t = table(args.dataset, "frames")
    parked = table(args.dataset, "parked_cars").set_index(["clip_id", "parked_car"])
    if len(nusc.scene) != len(clips):
        fail(f"{len(nusc.scene)} scenes for {len(clips)} clips")

    # Scenes and samples.
    samples = 0
    for scene in nusc.scene:
        tok, seen, last = scene["first_sample_token"], 0, None
        while tok:
            s = nusc.get("sample", tok)
            if set(s["data"]) != {"CAM_FRONT", "LIDAR_TOP"}:
                fail(f"sample {tok} has {sorted(s['data'])}")
            seen, last, tok = seen + 1, s["token"], s["next"]
        if seen != scene["nbr_samples"] or last != scene["last_sample_token"]:
            fail(f"scene {scene['name']}: {seen} samples walked, nbr_samples {scene['nbr_samples']}")
        samples += seen
    if samples != len(nusc.sample):
        fail(f"{samples} samples walked of {len(nusc.sample)}")

    splits = json.load(open(f"{out}/{VERSION}/splits.json"))
    for split, names in splits.items():
        for n in names:
            if clips.loc[n, "split"] != split:
                fail(f"splits.json puts {n} in {split}, the clips table in {clips.loc[n, 'split']}")
    if sorted(sum(splits.values(), [])) != sorted(clips.index):
        fail("splits.json does not list every clip once")

    map_origin = {m["token"]: np.array(m["world_origin_m"] + [0.0]) for m in nusc.map}
    log_map = {log["token"]: log["map_token"] for log in nusc.log}
    lidar_cache = {}

    checked = {"boxes": 0, "points": 0, "keypoints": 0, "velocities": 0, "lidar_files": 0, "images": 0,
               "parked_boxes": 0, "parked_points": 0}
    worst_kp = 0.0
    speed_errors = []
    ious = []
    for sample in nusc.sample:
        scene = nusc.get("scene", sample["scene_token"])
        clip = scene["name"]
        origin = map_origin[log_map[scene["log_token"]]]
        cam_tok, lidar_tok = sample["data"]["CAM_FRONT"], sample["data"]["LIDAR_TOP"]
        cam_path, cam_boxes, K = nusc.get_sample_data(cam_tok, box_vis_level=BoxVisibility.NONE)
        lidar_path, lidar_boxes, _ = nusc.get_sample_data(lidar_tok)
        if not os.path.isfile(cam_path):
            fail(f"{cam_path} missing")
        checked["images"] += 1
        sd = nusc.get("sample_data", lidar_tok)
        fps = int(clips.loc[clip, "fps"])
        frame = round(sd["timestamp"] * fps / 1e6)

        # Pedestrian boxes against the annotations table.
        rows = ann[(ann.clip_id == clip) & (ann.frame == frame)].set_index("pedestrian")
        ped_anns = {}
        for tok, a, inst, attrs in annotations_of(nusc, sample, "pedestrian"):
            if not attrs or not attrs <= PED_ATTRS:
                fail(f"pedestrian annotation {tok}: attributes {attrs}")
            if not a["category_name"].startswith("human.pedestrian."):
                fail(f"pedestrian annotation {tok}: category {a['category_name']}")
            ped_anns[inst["id"]] = a
        if sorted(ped_anns) != sorted(rows.index):
            fail(f"{clip} frame {frame}: boxes for pedestrians {sorted(ped_anns)}, annotations {sorted(rows.index)}")
        for tok in sample["anns"]:
            v = nusc.box_velocity(tok)
            a = nusc.get("sample_annotation", tok)
            stamp = lambda t: nusc.get("sample", nusc.get("sample_annotation", t)["sample_token"])["timestamp"]
            first = stamp(a["prev"]) if a["prev"] else sample["timestamp"]
            last = stamp(a["next"]) if a["next"] else sample["timestamp"]
            # The devkit estimates over at most 1.5 s (3 s for a centred difference) and returns NaN beyond.
            limit = 3.0 if a["prev"] and a["next"] else 1.5
            if (a["prev"] or a["next"]) and (last - first) / 1e6 <= limit:
                if not np.all(np.isfinite(v[:2])):
                    fail(f"box_velocity({tok}) = {v}")
                checked["velocities"] += 1
                inst = nusc.get("instance", a["instance_token"])
                if inst["kind"] == "pedestrian":
                    r = rows.loc[inst["id"]]
                    speed_errors.append(float(np.hypot(v[0] - r.vx_mps, v[1] - r.vy_mps)))

        # LiDAR: the file is our points, pedestrian points lie in their boxes.
        pc = LidarPointCloud.from_file(lidar_path)
        raw = np.fromfile(lidar_path, dtype=np.float32).reshape(-1, 5)
        if clip not in lidar_cache:
            lidar_cache.clear()
            lidar_cache[clip] = pads.dataset(f"{args.dataset}/sensors/lidar/{clip}.parquet").to_table().to_pandas()
        pts = lidar_cache[clip]
        ours = pts[pts.frame == frame]
        if len(ours) != raw.shape[0]:
            fail(f"{lidar_path}: {raw.shape[0]} points, our frame {frame} has {len(ours)}")
        expect = np.stack([ours.x, -ours.y, ours.z, ours.intensity], axis=1).astype(np.float32)
        if not np.array_equal(raw[:, :4], expect):
            fail(f"{lidar_path}: points differ from the Parquet's frame {frame}")
        if raw[:, 4].min() < 0 or raw[:, 4].max() > 63 or np.any(raw[:, 4] != np.round(raw[:, 4])):
            fail(f"{lidar_path}: ring outside 0..63")
        checked["lidar_files"] += 1
        by_inst = {b.token: b for b in lidar_boxes}  # the devkit's boxes carry their annotation's token
        for ped, a in ped_anns.items():
            box = by_inst[a["token"]]
            inside = points_in_box(box, pc.points[:3, :])
            if int(inside.sum()) != a["num_lidar_pts"]:
                fail(f"{clip} frame {frame} pedestrian {ped}: num_lidar_pts {a['num_lidar_pts']}, "
                     f"{int(inside.sum())} points in the box")
            mine = (ours.actor_id.to_numpy() == ped) & (ours.instance.to_numpy() == 1 + ped)
            if np.any(mine & ~inside):
                bad = np.flatnonzero(mine & ~inside)
                fail(f"{clip} frame {frame} pedestrian {ped}: {len(bad)} of {int(mine.sum())} of its points "
                     f"outside its box")
            checked["points"] += int(mine.sum())
            checked["boxes"] += 1

        # Parked cars: a `vehicle.car` box with `vehicle.parked` each, the size and place of its `parked_cars` row,
        # and every LiDAR point of its instance (57344 + id) inside it.
        for tok, a, inst, attrs in annotations_of(nusc, sample, "parked_car"):
            if a["category_name"] != "vehicle.car" or attrs != {"vehicle.parked"}:
                fail(f"parked car annotation {tok}: {a['category_name']}, {attrs}")
            car = parked.loc[(clip, inst["id"])]
            want = np.array([car.x_m, car.y_m, car.z_m + 0.5 * car.height_m]) - origin
            if np.abs(np.array(a["translation"]) - want).max() > 1e-3 or \
                    np.abs(np.array(a["size"]) - [car.width_m, car.length_m, car.height_m]).max() > 1e-5:
                fail(f"parked car {inst['id']} of {clip}: box {a['translation']} {a['size']}, row {want}")
            mine = ours.instance.to_numpy() == 57344 + inst["id"]
            inside = points_in_box(by_inst[a["token"]], pc.points[:3, :])
            if np.any(mine & ~inside):
                fail(f"{clip} frame {frame} parked car {inst['id']}: {int((mine & ~inside).sum())} of "
                     f"{int(mine.sum())} of its points outside its box")
            checked["parked_points"] += int(mine.sum())
            checked["parked_boxes"] += 1

        # Camera: keypoints_3d through the exported poses and calibration land on our keypoints.
        cam_sd = nusc.get("sample_data", cam_tok)
        pose = nusc.get("ego_pose", cam_sd["ego_pose_token"])
        cs = nusc.get("calibrated_sensor", cam_sd["calibrated_sensor_token"])
        cam_by_tok = {b.token: b for b in cam_boxes}
        for ped, a in ped_anns.items():
            r = rows.loc[ped]
            kp3 = np.asarray(r.keypoints_3d, dtype=np.float64).reshape(-1, 3)
            kp2 = np.asarray(r.keypoints, dtype=np.float64).reshape(-1, 3)
            p = kp3 - origin  # world → the export's global frame
            p = Quaternion(pose["rotation"]).inverse.rotation_matrix @ (p - pose["translation"]).T
            p = Quaternion(cs["rotation"]).inverse.rotation_matrix @ (p.T - cs["translation"]).T
            front = p[2] > 0.1
            uv = view_points(p, np.array(cs["camera_intrinsic"]), normalize=True)[:2].T
            labelled = front & (kp2[:, 2] > 0)
            if labelled.any():
                err = np.abs(uv[labelled] - kp2[labelled, :2]).max()
                worst_kp = max(worst_kp, err)
                if err > 0.05:
                    fail(f"{clip} frame {frame} pedestrian {ped}: keypoints projected {err:.3f} px from ours")
                checked["keypoints"] += int(labelled.sum())
            box = cam_by_tok[a["token"]]
            corners = view_points(box.corners(), K, normalize=True)[:2]
            x0, y0 = corners.min(axis=1)
            x1, y1 = corners.max(axis=1)
            # The 3D box's projection clipped to the image, against the tight box (inside it, and close).
            w, h = cam_sd["width"], cam_sd["height"]
            cx0, cy0, cx1, cy1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
            ix = max(0.0, min(cx1, r.bbox_x_max) - max(cx0, r.bbox_x_min))
            iy = max(0.0, min(cy1, r.bbox_y_max) - max(cy0, r.bbox_y_min))
            inter = ix * iy
            union = (cx1 - cx0) * (cy1 - cy0) + (r.bbox_x_max - r.bbox_x_min) * (r.bbox_y_max - r.bbox_y_min) - inter
            ious.append(inter / union if union > 0 else 0.0)
            if (r.bbox_x_min < x0 - 1 or r.bbox_y_min < y0 - 1 or r.bbox_x_max > x1 + 1
                    or r.bbox_y_max > y1 + 1):
                fail(f"{clip} frame {frame} pedestrian {ped}: tight box "
                     f"{[r.bbox_x_min, r.bbox_y_min, r.bbox_x_max, r.bbox_y_max]} outside the 3D box's "
                     f"projection {[x0, y0, x1, y1]}")

    # The ego poses are the frames table's.
    for sd in nusc.sample_data[:200]:
        scene = nusc.get("scene", nusc.get("sample", sd["sample_token"])["scene_token"])
        origin = map_origin[log_map[scene["log_token"]]]
        fps = int(clips.loc[scene["name"], "fps"])
        frame = round(sd["timestamp"] * fps / 1e6)
        row = frames_t[(frames_t.clip_id == scene["name"]) & (frames_t.frame == frame)].iloc[0]
        pose = nusc.get("ego_pose", sd["ego_pose_token"])
        t = np.array(pose["translation"]) + origin
        yaw = Quaternion(pose["rotation"]).yaw_pitch_roll[0]
        if np.abs(t - [row.ego_x_m, row.ego_y_m, row.ego_z_m]).max() > 1e-6 or \
                abs(np.angle(np.exp(1j * (yaw - row.ego_yaw_rad)))) > 1e-9:
            fail(f"ego pose of {sd['token']} differs from frames row {scene['name']} {frame}")

    # A keyframe's tick and the one before it (the devkit's nsweeps=2) cover all 360° of azimuth.
    s = next(s for s in nusc.sample[len(nusc.sample) // 2:]
             if nusc.get("sample_data", s["data"]["LIDAR_TOP"])["prev"])
    pc, times = LidarPointCloud.from_file_multisweep(nusc, s, "LIDAR_TOP", "LIDAR_TOP", nsweeps=2)
    azimuth_bins = np.unique((np.degrees(np.arctan2(pc.points[1], pc.points[0])) // 10).astype(int))
    if len(np.unique(times)) != 2 or len(azimuth_bins) < 36:
        fail(f"nsweeps=2: {len(np.unique(times))} sweeps covering {len(azimuth_bins)} of 36 10° sectors")
    # The devkit draws a camera and a LiDAR frame (over the map, one and two sweeps).
    render_dir = os.path.join(out, "renders")
    os.makedirs(render_dir, exist_ok=True)
    nusc.render_sample_data(s["data"]["CAM_FRONT"], out_path=f"{render_dir}/cam.png", verbose=False)
    nusc.render_sample_data(s["data"]["LIDAR_TOP"], out_path=f"{render_dir}/lidar.png", verbose=False)
    nusc.render_sample_data(s["data"]["LIDAR_TOP"], nsweeps=2, out_path=f"{render_dir}/lidar2.png", verbose=False)
    for f in ("cam.png", "lidar.png", "lidar2.png"):
        if os.path.getsize(f"{render_dir}/{f}") < 10_000:
            fail(f"render {f} is nearly empty")
    if checked["boxes"] == 0 or checked["points"] == 0 or not speed_errors or checked["parked_points"] == 0:
        fail(f"nothing checked: {checked}")
    # Box centres move as the body walks: their finite differences follow the tables' ground velocity.
    median_speed_error = float(np.median(speed_errors))
    median_iou = float(np.median(ious))
    if median_iou < 0.5:
        fail(f"the 3D boxes' projections overlap the tight 2D boxes with a median IoU of {median_iou:.2f}")
    if median_speed_error > 0.3:
        fail(f"box_velocity is {median_speed_error:.2f} m/s from the tables' velocity (median)")
    print(f"interop_nuscenes: OK: {len(nusc.scene)} scenes, {len(nusc.sample)} samples, "
          f"{len(nusc.sample_data)} sample_data, {len(nusc.sample_annotation)} annotations; checked "
          f"{checked['boxes']} pedestrian boxes holding {checked['points']} of their LiDAR points, "
          f"{checked['keypoints']} keypoints (worst {worst_kp:.4f} px), 3D box projections around the 2D boxes "
          f"(median IoU {median_iou:.2f}, lowest {min(ious):.2f}), {checked['velocities']} velocities (pedestrians within a median {median_speed_error:.3f} m/s of the "
          f"tables'), "
          f"{checked['parked_boxes']} parked-car boxes holding {checked['parked_points']} of their LiDAR points, "
          f"{checked['lidar_files']} LiDAR files; renders in {render_dir}")


if __name__ == "__main__":
    main()
