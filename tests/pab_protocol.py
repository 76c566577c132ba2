#!/usr/bin/env python3
"""PedestrianActionBenchmark's sampling of a pedsynth dataset, written independently of pedsynth, and compared
exactly with `pedsynth stats DIR --protocol pab --json`.

The protocol, from its published code (Kotseruba et al., WACV 2021: `action_predict.py`, `get_data_sequence`,
with the track cut of PIE's and JAAD's `_get_crossing`):
  * a track is a pedestrian's annotated frames in frame order, cut after its event: the first frame with
    crossing = 1 for a crosser (PIE's `crossing_point`), the last frame otherwise;
  * tracks shorter than `min_track_size` (obs_length + time_to_event[1]) are dropped (`len(boxes) / seq_stride <
    min_track_size`, seq_stride 1);
  * `olap_res = obs_length if overlap == 0 else int((1 - overlap) * obs_length)`, at least 1; every kept track
    gives the windows `seq[i:i + obs_length]` for `i in range(len - obs - tte[1], len - obs - tte[0] + 1,
    olap_res)`.

The windows are built as lists, as the benchmark does, and counted; nothing is taken from pedsynth but its JSON
to compare with.

Usage:
    python3 tests/pab_protocol.py DIR --pedsynth path/to/pedsynth [--overlap 0.8] [--obs-length 16] [--tte 30,60]

Prints `pab protocol: agrees ...` and exits 0 when every figure agrees; prints the differences and exits 1.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pyarrow.dataset as ds


def table(root: Path, name: str, columns: list[str]) -> list[dict]:
    return ds.dataset(str(root / "tables" / name), format="parquet").to_table(columns=columns).to_pylist()


def windows(track: list, obs_length: int, tte: tuple[int, int], overlap: float) -> list[list]:
    """`get_data_sequence`'s slicing of one track (a list of frames ending at the event)."""
    olap_res = obs_length if overlap == 0 else int((1 - overlap) * obs_length)
    olap_res = 1 if olap_res < 1 else olap_res
    start_idx = len(track) - obs_length - tte[1]
    end_idx = len(track) - obs_length - tte[0]
    return [track[i : i + obs_length] for i in range(start_idx, end_idx + 1, olap_res)]


def protocol(root: Path, obs_length: int, tte: tuple[int, int], overlap: float, min_track: int) -> dict:
    split_of = {r["clip_id"]: r["split"] for r in table(root, "clips", ["clip_id", "split"])}
    crosser = {
        (r["clip_id"], r["pedestrian"]): r["crosser"]
        for r in table(root, "pedestrians", ["clip_id", "pedestrian", "crosser"])
    }
    frames = defaultdict(list)
    for r in table(root, "annotations", ["clip_id", "pedestrian", "frame", "crossing"]):
        frames[(r["clip_id"], r["pedestrian"])].append((r["frame"], r["crossing"]))

    zero = lambda: {"tracks": 0, "eligible_tracks": 0, "windows": 0}  # noqa: E731
    splits = defaultdict(lambda: {"crossing": zero(), "not_crossing": zero()})
    for key, track in frames.items():
        track.sort()
        if crosser[key]:
            first = next((k for k, (_, c) in enumerate(track) if c), None)
            track = track[: first + 1] if first is not None else []
        counts = splits[split_of[key[0]]]["crossing" if crosser[key] else "not_crossing"]
        counts["tracks"] += 1
        if len(track) / 1 < min_track:
            continue
        counts["eligible_tracks"] += 1
        counts["windows"] += len(windows(track, obs_length, tte, overlap))

    def share(s: dict) -> float:
        total = s["crossing"]["windows"] + s["not_crossing"]["windows"]
        return s["crossing"]["windows"] / total if total else 0.0

    every = {"crossing": zero(), "not_crossing": zero()}
    for s in splits.values():
        s["window_crossing_share"] = share(s)
        for cls in ("crossing", "not_crossing"):
            for k in every[cls]:
                every[cls][k] += s[cls][k]
    every["window_crossing_share"] = share(every)
    return {"splits": dict(splits), "all": every}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", type=Path)
    parser.add_argument("--pedsynth", required=True, help="the pedsynth binary to compare with")
    parser.add_argument("--obs-length", type=int, default=16)
    parser.add_argument("--tte", default="30,60")
    parser.add_argument("--overlap", type=float, default=0.6)
    args = parser.parse_args()
    tte = tuple(int(x) for x in args.tte.split(","))
    min_track = args.obs_length + tte[1]

    ours = protocol(args.dir, args.obs_length, tte, args.overlap, min_track)
    command = [args.pedsynth, "stats", str(args.dir), "--protocol", "pab", "--json"]
    command += ["--obs-length", str(args.obs_length), "--tte", args.tte, "--overlap", str(args.overlap)]
    theirs = json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)

    problems = []
    if set(ours["splits"]) != set(theirs["splits"]):
        problems.append(f"splits: {sorted(ours['splits'])} here, {sorted(theirs['splits'])} in pedsynth")
    for name in sorted(ours["splits"]):
        if ours["splits"][name] != theirs["splits"].get(name):
            problems.append(f"split {name}: {ours['splits'][name]} here, {theirs['splits'].get(name)} in pedsynth")
    if ours["all"] != theirs["all"]:
        problems.append(f"all: {ours['all']} here, {theirs['all']} in pedsynth")
    if problems:
        print("pab protocol: DISAGREES\n  " + "\n  ".join(problems))
        return 1
    a = ours["all"]
    print(
        f"pab protocol: agrees (overlap {args.overlap}): {a['crossing']['windows']} crossing and "
        f"{a['not_crossing']['windows']} not-crossing windows, share {a['window_crossing_share']:.3f}, "
        f"{len(ours['splits'])} splits"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
