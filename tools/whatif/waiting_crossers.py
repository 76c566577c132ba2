"""Planned crossers that never cross in a generated set, and what holds them at the clip's end: their last state,
whether they stand, how far ahead the ego is and whether it is stopped, and whether someone else is crossing in
front of the ego then.

Not pedsynth code: a measurement on a generated dataset's tables (BENCHMARKS.md, "Transfer to real data", the
roll-up paragraph). Run from the repository root: `python3 tools/whatif/waiting_crossers.py DATASET`. Needs
pyarrow, numpy and pandas.
"""
import sys

import numpy as np
import pyarrow.dataset as ds

ATTENTIVE = ["CHECKING_TRAFFIC", "LOOKING_AROUND", "HESITATING"]
CROSSING = ["CROSSING_ROAD", "SUDDEN_CROSSING", "JAYWALKING", "PAUSING_MID_CROSS", "RUNNING_ACROSS"]
# The ego's courtesy zone (traffic.ego.courtesy_ahead_m and courtesy_lateral_m's defaults), metres.
ZONE_AHEAD_M, ZONE_LATERAL_M = 35.0, 10.0


def table(root, name, columns=None):
    return ds.dataset(f"{root}/tables/{name}", format="parquet").to_table(columns=columns).to_pandas()


def in_ego_frame(df):
    """Adds `ahead` and `lateral`: the position in the ego's frame (x forward, y left), metres."""
    dx, dy = df.x_m - df.ego_x_m, df.y_m - df.ego_y_m
    c, s = np.cos(df.ego_yaw_rad), np.sin(df.ego_yaw_rad)
    return df.assign(ahead=dx * c + dy * s, lateral=-dx * s + dy * c)


def main(root):
    peds = table(root, "pedestrians", ["clip_id", "pedestrian", "role", "crosser", "first_crossing_frame"])
    tracks = table(root, "tracks", ["clip_id", "frame", "pedestrian", "x_m", "y_m", "vx_mps", "vy_mps", "state"])
    frames = table(root, "frames", ["clip_id", "frame", "ego_x_m", "ego_y_m", "ego_yaw_rad", "ego_speed_mps"])
    planned = peds[peds.role == "crosser"]
    never = planned[planned.first_crossing_frame.isna()]
    print(f"planned crossers {len(planned)}: labelled crossers {int(planned.crosser.sum())}, "
          f"not labelled {int((~planned.crosser).sum())}, never crossed {len(never)}")
    last = tracks.sort_values("frame").groupby(["clip_id", "pedestrian"]).tail(1)
    end = in_ego_frame(never.merge(last, on=["clip_id", "pedestrian"]).merge(frames, on=["clip_id", "frame"]))
    print("their state at the clip's end:", end.state.value_counts().to_dict())
    standing = end[(end.state == "WALKING_SIDEWALK") & (np.hypot(end.vx_mps, end.vy_mps) < 0.1)]
    stopped = standing[standing.ego_speed_mps < 0.3]
    print(f"standing on the sidewalk: {len(standing)}; the ego ahead of them {np.mean(standing.ahead > 0):.1%}, "
          f"stopped {len(stopped) / max(len(standing), 1):.1%}, median distance "
          f"{np.median(np.hypot(standing.ahead, standing.lateral)):.1f} m")
    ends = stopped[["clip_id", "frame"]].drop_duplicates()
    others = in_ego_frame(tracks.merge(ends, on=["clip_id", "frame"]).merge(frames, on=["clip_id", "frame"]))
    zone = others[(others.ahead > 0) & (others.ahead < ZONE_AHEAD_M) & (others.lateral.abs() < ZONE_LATERAL_M)]
    print(f"clips where such a crosser waits for a stopped ego: {len(ends)}; someone crossing in the ego's "
          f"courtesy zone then: {zone[zone.state.isin(CROSSING)].clip_id.nunique()}; someone waiting "
          f"attentively at a curb there: {zone[zone.state.isin(ATTENTIVE)].clip_id.nunique()}")


if __name__ == "__main__":
    main(sys.argv[1])
