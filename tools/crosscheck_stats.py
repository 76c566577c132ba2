#!/usr/bin/env python3
"""Cross-checks `pedsynth stats --json` against an independent reading of the dataset's Parquet tables.

Reads each table directory (`DIR/tables/<table>/`) as one pyarrow dataset, recomputes the clip, frame and
pedestrian counts, the sequence-level crossing / non-crossing counts (from `pedestrians.crosser`), the
annotated and C = 1 samples, the samples per behaviour state, the per-split counts, towns, weathers,
visibility-gate rejections and contacts, and compares them with the statistics pedsynth computed.

Usage:
    python3 tools/crosscheck_stats.py DIR --pedsynth path/to/pedsynth   # runs `pedsynth stats DIR --json`
    python3 tools/crosscheck_stats.py DIR --stats-json stats.json       # or reads its output from a file

Prints `crosscheck: N passed, 0 failed` and exits 0 when everything agrees; prints every mismatch and exits 1
otherwise (2 when the dataset or the statistics cannot be read).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as ds


def read_table(root: Path, name: str, columns: list[str]) -> pa.Table:
    """Reads one table directory as a dataset (hidden `.`/`_` files such as temporaries are skipped)."""
    path = root / "tables" / name
    if not path.is_dir():
        raise FileNotFoundError(f"{path}: no such table directory (is this a pedsynth dataset?)")
    return ds.dataset(str(path), format="parquet").to_table(columns=columns)


def counts_by(table: pa.Table, key: str, value: str | None = None) -> dict[str, int]:
    """Rows per `key` value, or the sum of the boolean/integer column `value` per `key` value."""
    if table.num_rows == 0:
        return {}
    if value is None:
        grouped = table.group_by(key).aggregate([(key, "count")])
        col = f"{key}_count"
    else:
        t = table.set_column(
            table.schema.get_field_index(value), value, pc.cast(table[value], pa.int64())
        )
        grouped = t.group_by(key).aggregate([(value, "sum")])
        col = f"{value}_sum"
    return {k: int(v) for k, v in zip(grouped[key].to_pylist(), grouped[col].to_pylist())}


def recompute(root: Path) -> dict:
    """The statistics, recomputed from the tables."""
    clips = read_table(
        root,
        "clips",
        [
            "clip_id",
            "town",
            "weather",
            "split",
            "rejected_too_far",
            "rejected_behind",
            "rejected_too_small",
            "rejected_outside_image",
            "rejected_occluded",
            "emergency",
        ],
    )
    frames = read_table(root, "frames", ["clip_id", "frame"])
    peds = read_table(root, "pedestrians", ["clip_id", "pedestrian", "crosser"])
    ann = read_table(
        root,
        "annotations",
        ["clip_id", "frame", "pedestrian", "state", "crossing", "look", "action", "gesture", "reaction",
         "walk_signal", "against_signal", "on_crosswalk"],
    )
    events = read_table(root, "events", ["clip_id", "kind", "unavoidable", "cyclist", "min_clearance_m", "swerved"])
    cyclists = read_table(root, "cyclists", ["clip_id", "cyclist", "in_view", "annotated"])
    # Red-light events of cyclists are counted apart from the motor vehicles'.
    ev = list(zip(
        events["kind"].to_pylist(), events["unavoidable"].to_pylist(), events["cyclist"].to_pylist(),
        events["min_clearance_m"].to_pylist(), events["swerved"].to_pylist(),
    ))
    clearances = [c for k, _, _, c, _ in ev if k == "overtook_cyclist"]

    split_of = clips.select(["clip_id", "split"])
    n_peds = peds.num_rows
    unique_peds = len(set(zip(peds["clip_id"].to_pylist(), peds["pedestrian"].to_pylist())))
    crossing = int(pc.sum(pc.cast(peds["crosser"], pa.int64())).as_py() or 0)
    state_samples = counts_by(ann, "state")

    splits: dict[str, dict[str, int]] = {}

    def add(field: str, per_split: dict[str, int]) -> None:
        for split, n in per_split.items():
            splits.setdefault(split, {"clips": 0, "frames": 0, "pedestrians": 0, "crossers": 0, "samples": 0})
            splits[split][field] = n

    add("clips", counts_by(clips, "split"))
    add("frames", counts_by(frames.join(split_of, "clip_id"), "split"))
    peds_split = peds.join(split_of, "clip_id")
    add("pedestrians", counts_by(peds_split, "split"))
    add("crossers", counts_by(peds_split, "split", "crosser"))
    add("samples", counts_by(ann.join(split_of, "clip_id"), "split"))

    rejected = {
        reason: int(pc.sum(clips[f"rejected_{reason}"]).as_py() or 0)
        for reason in ["too_far", "behind", "too_small", "outside_image", "occluded"]
    }
    ratio = lambda a, b: 0.0 if b == 0 else a / b  # noqa: E731
    total_samples = ann.num_rows
    return {
        "clips": clips.num_rows,
        "clips_with_frames": len(set(frames["clip_id"].to_pylist())),
        "frames": frames.num_rows,
        "pedestrians": n_peds,
        "unique_pedestrians": unique_peds,
        "crossing": crossing,
        "non_crossing": n_peds - crossing,
        "crossing_share": ratio(crossing, n_peds),
        "annotated_samples": total_samples,
        "crossing_samples": int(pc.sum(pc.cast(ann["crossing"], pa.int64())).as_py() or 0),
        "state_samples": state_samples,
        "state_shares": {k: ratio(v, total_samples) for k, v in state_samples.items()},
        "splits": splits,
        "towns": sorted(set(clips["town"].to_pylist())),
        "weathers": sorted(set(clips["weather"].to_pylist())),
        "rejected": rejected,
        "contacts": int(pc.sum(pc.cast(pc.equal(events["kind"], "contact"), pa.int64())).as_py() or 0),
        "looking_samples": int(pc.sum(pc.cast(ann["look"], pa.int64())).as_py() or 0),
        "walking_samples": int(pc.sum(pc.cast(pc.equal(ann["action"], "walking"), pa.int64())).as_py() or 0),
        "gesture_samples": {k: v for k, v in counts_by(ann, "gesture").items() if k != "none"},
        "gesturing_pedestrians": {
            k: v
            for k, v in counts_by(ann.group_by(["clip_id", "pedestrian", "gesture"]).aggregate([]), "gesture").items()
            if k != "none"
        },
        "reaction_samples": {k: v for k, v in counts_by(ann, "reaction").items() if k != "none"},
        "emergency_clips": counts_by(clips.filter(pc.is_valid(clips["emergency"])), "emergency"),
        "yielding_vehicle_frames": int(
            pc.sum(pc.cast(read_table(root, "vehicles", ["yielding"])["yielding"], pa.int64())).as_py() or 0
        )
        + int(pc.sum(pc.cast(read_table(root, "frames", ["ego_yielding"])["ego_yielding"], pa.int64())).as_py() or 0),
        "pedestrians_at_signals": len({
            (c, p) for c, p, w in zip(
                ann["clip_id"].to_pylist(), ann["pedestrian"].to_pylist(), ann["walk_signal"].to_pylist()
            ) if w is not None
        }),
        "against_signal_samples": int(pc.sum(pc.cast(ann["against_signal"], pa.int64())).as_py() or 0),
        "on_crosswalk_samples": int(pc.sum(pc.cast(ann["on_crosswalk"], pa.int64())).as_py() or 0),
        "red_lights_stopped_for": sum(1 for k, _, c, _, _ in ev if k == "stopped_at_red_light" and c is None),
        "red_light_violations": sum(1 for k, u, c, _, _ in ev if k == "ran_red_light" and not u and c is None),
        "red_lights_run_unavoidably": sum(1 for k, u, c, _, _ in ev if k == "ran_red_light" and u and c is None),
        "cyclist_red_lights_stopped_for": sum(
            1 for k, _, c, _, _ in ev if k == "stopped_at_red_light" and c is not None
        ),
        "cyclist_red_light_runs": sum(1 for k, _, c, _, _ in ev if k == "ran_red_light" and c is not None),
        "cyclists": len(set(zip(cyclists["clip_id"].to_pylist(), cyclists["cyclist"].to_pylist()))),
        "cyclist_frames_in_view": int(pc.sum(pc.cast(cyclists["in_view"], pa.int64())).as_py() or 0),
        "cyclist_samples": int(pc.sum(pc.cast(cyclists["annotated"], pa.int64())).as_py() or 0),
        "cyclist_overtakes": len(clearances),
        "min_overtaking_clearance_m": min(clearances) if clearances else None,
        "cyclist_swerves": sum(1 for k, _, _, _, s in ev if k == "cyclist_yielded" and s),
        "cyclist_brakes_for_pedestrians": sum(1 for k, _, _, _, s in ev if k == "cyclist_yielded" and not s),
        "pedestrian_cyclist_conflicts": sum(1 for k, _, c, _, _ in ev if k == "conflict" and c is not None),
        "cyclist_contacts": sum(1 for k, _, c, _, _ in ev if k == "contact" and c is not None),
    }


class Checker:
    """Collects comparison results."""

    def __init__(self) -> None:
        self.passed = 0
        self.failures: list[str] = []

    def equal(self, what: str, mine, theirs) -> None:
        if mine == theirs:
            self.passed += 1
        else:
            self.failures.append(f"{what}: tables say {mine!r}, pedsynth stats says {theirs!r}")

    def close(self, what: str, mine: float, theirs, tol: float = 1e-9) -> None:
        if isinstance(theirs, (int, float)) and math.isclose(mine, theirs, rel_tol=tol, abs_tol=tol):
            self.passed += 1
        else:
            self.failures.append(f"{what}: tables say {mine!r}, pedsynth stats says {theirs!r}")


def compare(mine: dict, stats: dict) -> Checker:
    c = Checker()
    for key in ["clips", "frames", "pedestrians", "crossing", "non_crossing", "annotated_samples", "crossing_samples"]:
        c.equal(key, mine[key], stats.get(key))
    c.equal("clips (distinct clip ids in frames)", mine["clips_with_frames"], stats.get("clips"))
    c.equal("pedestrians (distinct clip, pedestrian)", mine["unique_pedestrians"], stats.get("pedestrians"))
    c.close("crossing_share", mine["crossing_share"], stats.get("crossing_share"))
    c.equal("towns", mine["towns"], stats.get("towns"))
    c.equal("weathers", mine["weathers"], stats.get("weathers"))
    c.equal("contacts", mine["contacts"], stats.get("contacts"))
    c.equal("rejected", mine["rejected"], stats.get("rejected"))
    for key in ["looking_samples", "walking_samples", "gesture_samples", "gesturing_pedestrians", "reaction_samples",
                "emergency_clips", "yielding_vehicle_frames", "red_lights_stopped_for", "red_light_violations",
                "red_lights_run_unavoidably", "pedestrians_at_signals", "against_signal_samples",
                "on_crosswalk_samples", "cyclists", "cyclist_frames_in_view", "cyclist_samples", "cyclist_overtakes",
                "cyclist_swerves", "cyclist_brakes_for_pedestrians", "pedestrian_cyclist_conflicts", "cyclist_contacts",
                "cyclist_red_lights_stopped_for", "cyclist_red_light_runs"]:
        c.equal(key, mine[key], stats.get(key))
    if mine["min_overtaking_clearance_m"] is None:
        c.equal("min_overtaking_clearance_m", None, stats.get("min_overtaking_clearance_m"))
    else:
        # The events table stores the clearance as float32.
        c.close("min_overtaking_clearance_m", mine["min_overtaking_clearance_m"],
                stats.get("min_overtaking_clearance_m"), tol=1e-9)
    their_counts = stats.get("state_samples")
    if their_counts is not None:
        c.equal("states with samples", sorted(mine["state_samples"]), sorted(their_counts))
        for state, n in sorted(mine["state_samples"].items()):
            c.equal(f"state_samples[{state}]", n, their_counts.get(state))
    their_shares = stats.get("state_shares", {})
    c.equal("states with a share", sorted(mine["state_shares"]), sorted(their_shares))
    for state, share in sorted(mine["state_shares"].items()):
        c.close(f"state_shares[{state}]", share, their_shares.get(state))
    their_splits = stats.get("splits", {})
    c.equal("splits", sorted(mine["splits"]), sorted(their_splits))
    for split, counts in sorted(mine["splits"].items()):
        for field, n in counts.items():
            c.equal(f"splits[{split}].{field}", n, their_splits.get(split, {}).get(field))
    return c


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path, help="dataset directory written by `pedsynth generate`")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--pedsynth", help="the pedsynth binary: runs `pedsynth stats DIR --json`")
    source.add_argument("--stats-json", type=Path, help="a file holding the output of `pedsynth stats DIR --json`")
    args = parser.parse_args(argv)

    try:
        if args.pedsynth:
            run = subprocess.run(
                [args.pedsynth, "stats", str(args.dataset), "--json"], capture_output=True, text=True, check=False
            )
            if run.returncode != 0:
                print(f"crosscheck: `pedsynth stats` failed ({run.returncode}):\n{run.stderr}", file=sys.stderr)
                return 2
            stats = json.loads(run.stdout)
        else:
            stats = json.loads(args.stats_json.read_text())
        mine = recompute(args.dataset)
    except (OSError, ValueError, pa.ArrowException) as e:
        print(f"crosscheck: cannot read the dataset or the statistics: {e}", file=sys.stderr)
        return 2

    result = compare(mine, stats)
    for failure in result.failures:
        print(f"crosscheck: MISMATCH {failure}", file=sys.stderr)
    print(f"crosscheck: {result.passed} passed, {len(result.failures)} failed")
    if mine["annotated_samples"] == 0 or mine["clips"] == 0:
        print("crosscheck: the dataset is empty (no clips or no annotated samples)", file=sys.stderr)
        return 1
    return 1 if result.failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
