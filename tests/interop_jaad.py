#!/usr/bin/env python3
"""Interop check: JAAD's own loader and PedestrianActionBenchmark's own `get_pose`, unmodified, read
`pedsynth export jaad` and `pedsynth export pab-poses-jaad`, and what they return equals our tables.

Usage: python3 tests/interop_jaad.py DATASET --pedsynth BIN [--no-poses]

As tests/interop_pie.py (whose helpers it uses), for JAAD's layout: behaviour-annotated pedestrians ("b" ids),
`crossing_point` -1 for non-crossers (JAAD's loader then ends their tracks two frames before the last), the
split lists, and the JAAD set of the pose files.
"""

import os
import shutil
import sys

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from interop_pie import (  # noqa: E402
    SHARED, check_sequences, check_track, fail, install_pab_get_pose, report_behaviour, setup,
)


def main():
    args, work, out, export, poses_too, clips, peds, tracks = setup("jaad", ["jaad", "pab-poses-jaad"])
    video_of = {v["clip_id"]: v["video"] for v in export["videos"]}
    jaad_id = lambda c, p: f"0_{int(video_of[c][6:])}_{p}b"  # noqa: E731
    by_id = {jaad_id(c, p): (c, p) for (c, p) in tracks}

    sys.path.insert(0, os.path.join(SHARED, "jaad"))
    from jaad_data import JAAD  # noqa: E402

    db = JAAD(data_path=out, regen_pkl=True).generate_database()
    imdb = JAAD(data_path=out)
    seen = 0
    figures = {}
    label_key = lambda worn: ",".join(k for k, v in worn.items() if v) or "none"  # noqa: E731
    for clip_id, video in video_of.items():
        v = db[video]
        if v["num_frames"] != clips[clip_id]["frame_count"]:
            fail(f"{clip_id}: num_frames differ")
        ours = {jaad_id(c, p): t for (c, p), t in tracks.items() if c == clip_id}
        theirs = v["ped_annotations"]
        if sorted(ours) != sorted(theirs):
            fail(f"{clip_id}: pedestrians {sorted(theirs)} != ours {sorted(ours)}")
        for pid, t in ours.items():
            a = theirs[pid]
            check_track(pid, t, a)
            ped = peds[by_id[pid]]
            attrs = a["attributes"]
            first_c = next((r["frame"] for r in t if r["crossing"]), None)
            if attrs["crossing"] != int(ped["crosser"]):
                fail(f"{pid}: crossing {attrs['crossing']} != crosser")
            if attrs["crossing_point"] != (first_c if ped["crosser"] else -1):
                fail(f"{pid}: crossing_point {attrs['crossing_point']}")
            if attrs["age"] != {"child": 0, "young": 1, "adult": 2, "senior": 3}[ped["age_group"]]:
                fail(f"{pid}: age differs")
            # The loader keeps appearance values as strings: exactly one side is "1".
            sides = [a["appearance"][k][0] for k in ["pose_front", "pose_back", "pose_left", "pose_right"]]
            if sorted(sides) != ["0", "0", "0", "1"]:
                fail(f"{pid}: appearance sides {sides}")
            # The figure's labels, constant over the track, equal the pedestrians table's.
            worn = {
                "backpack": ped["carry"] == "backpack",
                "bag_shoulder": ped["carry"] == "shoulder_bag",
                "bag_left_side": ped["carry"] == "shoulder_bag",
                "cap": bool(ped["headwear"]),
                "clothes_below_knee": ped["garment"] == "coat",
                "umbrella": bool(ped["umbrella"]),
                "hood": bool(ped["hood"]),
            }
            for label, want in worn.items():
                if set(a["appearance"][label]) != {str(int(want))}:
                    fail(f"{pid}: appearance {label} {sorted(set(a['appearance'][label]))}, the table says {want}")
            figures[label_key(worn)] = figures.get(label_key(worn), 0) + 1
            seen += 1
    print(f"interop_jaad: generate_database: {seen} pedestrian tracks in {len(video_of)} videos equal the tables "
          f"(appearance labels worn: {dict(sorted(figures.items()))})")
    report_behaviour("interop_jaad")

    config = yaml.safe_load(open(os.path.join(SHARED, "pedestrian_action_benchmark", "configs_default.yaml")))
    data_opts = dict(config["data_opts"])
    get_pose = install_pab_get_pose()
    total = 0
    for split in ["train", "val", "test"]:
        if not any(c["split"] == split for c in clips.values()):
            # JAAD's _get_crossing fails on a split without videos (UnboundLocalError on img_width); the
            # export warns about it.
            print(f"interop_jaad: {split}: no clips, skipped")
            continue
        seq = imdb.generate_data_trajectory_sequence(split, **data_opts)
        want = 0
        for (c, p), t in tracks.items():
            if clips[c]["split"] != split:
                continue
            first_c = next((r["frame"] for r in t if r["crossing"]), None)
            n = sum(1 for r in t if r["frame"] <= first_c) if peds[(c, p)]["crosser"] else len(t) - 2
            want += n >= data_opts["min_track_size"]
        if len(seq["pid"]) != want:
            fail(f"{split}: {len(seq['pid'])} sequences, the tables give {want}")
        windows = check_sequences(seq, tracks, peds, by_id, export, out, split, poses_too, get_pose, "jaad")
        total += len(seq["pid"])
        print(f"interop_jaad: {split}: {len(seq['pid'])} crossing sequences, boxes and labels equal; "
              + (f"get_pose equals our keypoints in {len(windows)} windows of 16 frames" if poses_too
                 else "poses not checked"))
    if total == 0:
        fail("no sequence in any split: the check would prove nothing")
    shutil.rmtree(work)


if __name__ == "__main__":
    main()
