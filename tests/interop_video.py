#!/usr/bin/env python3
"""Interop check for `output.rgb_encoding: h264`: JAAD's and PIE's own `extract_and_save_images()`, unmodified,
decode the MP4 videos that `pedsynth export jaad|pie` links from a dataset (through OpenCV's FFmpeg), and the
images they write are the frames pedsynth rendered: as many as the clip has, the right size, and within a
PSNR bound of the same frames rendered as PNG by a second run of the same spec with `rgb_encoding: png`.

Usage: python3 tests/interop_video.py H264_DATASET PNG_DATASET --pedsynth BIN [--min-psnr DB]

The loaders are imported from ../shared/interfaces (not copied). Exits 1 with the first disagreement.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import cv2
import numpy as np
import pyarrow.parquet as pq

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.join(ROOT, "..", "shared", "interfaces")


def fail(msg):
    print(f"interop_video: FAIL: {msg}")
    sys.exit(1)


def psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return 99.0 if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)


def compare(name, clips, frames_dir_of, png_dataset, min_psnr):
    """Every clip's extracted frames against the PNG run's; returns (frames, lowest PSNR, mean PSNR)."""
    values = []
    for clip_id, frame_count in sorted(clips.items()):
        d = frames_dir_of(clip_id)
        files = sorted(f for f in os.listdir(d) if f.endswith(".png")) if os.path.isdir(d) else []
        if len(files) != frame_count:
            fail(f"{name}: {clip_id}: {len(files)} frames extracted, the clip has {frame_count}")
        for f in range(frame_count):
            got = cv2.imread(os.path.join(d, f"{f:05d}.png"))
            want = cv2.imread(os.path.join(png_dataset, "sensors", "rgb", clip_id, f"{f:06d}.png"))
            if got is None or want is None:
                fail(f"{name}: {clip_id}: frame {f} missing")
            if got.shape != want.shape:
                fail(f"{name}: {clip_id}: frame {f} is {got.shape}, the PNG {want.shape}")
            p = psnr(got, want)
            if p < min_psnr:
                fail(f"{name}: {clip_id}: frame {f} PSNR {p:.1f} dB < {min_psnr}")
            values.append(p)
    return len(values), min(values), float(np.mean(values))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("h264_dataset")
    ap.add_argument("png_dataset")
    ap.add_argument("--pedsynth", required=True)
    ap.add_argument("--min-psnr", type=float, default=30.0)
    args = ap.parse_args()
    manifest = json.load(open(os.path.join(args.h264_dataset, "manifest.json")))
    if not manifest["sensors"]["rgb"].startswith("rendered: sensors/rgb/<clip_id>.mp4"):
        fail(f"{args.h264_dataset} has no H.264 RGB stream: {manifest['sensors']['rgb']}")
    clips = {}
    d = os.path.join(args.h264_dataset, "tables", "clips")
    for f in sorted(os.listdir(d)):
        for r in pq.read_table(os.path.join(d, f), columns=["clip_id", "frame_count"]).to_pylist():
            clips[r["clip_id"]] = r["frame_count"]
    work = tempfile.mkdtemp(prefix="interop_video_")
    try:
        # The container as OpenCV (FFmpeg) reads it: frame rate, size, frame count.
        for clip_id, n in clips.items():
            cap = cv2.VideoCapture(os.path.join(args.h264_dataset, "sensors", "rgb", f"{clip_id}.mp4"))
            fps, count = cap.get(cv2.CAP_PROP_FPS), int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
            if abs(fps - 30.0) > 1e-6 or count != n:
                fail(f"{clip_id}: OpenCV reads {count} frames at {fps} FPS, the clip has {n} at 30")

        jaad_out = os.path.join(work, "jaad")
        subprocess.run([args.pedsynth, "export", "jaad", args.h264_dataset, "--out", jaad_out], check=True)
        video_of = {v["clip_id"]: v["video"] for v in json.load(open(os.path.join(jaad_out, "pedsynth_export.json")))["videos"]}
        sys.path.insert(0, os.path.join(SHARED, "jaad"))
        from jaad_data import JAAD  # noqa: E402

        JAAD(data_path=jaad_out).extract_and_save_images()
        n, lo, mean = compare("jaad", clips, lambda c: os.path.join(jaad_out, "images", video_of[c]),
                              args.png_dataset, args.min_psnr)
        print(f"interop_video: JAAD's extract_and_save_images decoded {n} frames of {len(clips)} MP4 videos; "
              f"PSNR against the PNG run: lowest {lo:.1f} dB, mean {mean:.1f} dB")

        pie_out = os.path.join(work, "pie")
        subprocess.run([args.pedsynth, "export", "pie", args.h264_dataset, "--out", pie_out], check=True)
        pie_of = {v["clip_id"]: (v["set"], v["video"])
                  for v in json.load(open(os.path.join(pie_out, "pedsynth_export.json")))["videos"]}
        sys.path.insert(0, os.path.join(SHARED, "pie"))
        from pie_data import PIE  # noqa: E402

        PIE(data_path=pie_out).extract_and_save_images(extract_frame_type="all")
        n, lo, mean = compare("pie", clips, lambda c: os.path.join(pie_out, "images", *pie_of[c]),
                              args.png_dataset, args.min_psnr)
        print(f"interop_video: PIE's extract_and_save_images('all') decoded {n} frames; "
              f"PSNR against the PNG run: lowest {lo:.1f} dB, mean {mean:.1f} dB")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
