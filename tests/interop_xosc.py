"""`pedsynth export openscenario` read back by a third-party OpenSCENARIO library, unmodified: scenariogeneration's
`xosc.ParseOpenScenario` (pinned in tools/xosc-requirements.txt, its own venv) parses every exported file, and what
it returns is compared with the dataset's tables (pyarrow), not only loaded:

  * the road network is `towns/<town>.xodr`, and that file was exported;
  * the entities are exactly the ego, every vehicle, cyclist and pedestrian of the tables and every parked car;
  * every parked car has its `parked_cars` row's length, width and height, the property `parked`, an Init
    teleport to its row's place (1 mm, 0.001 rad) and no trajectory;
  * every moving entity's polyline, interpolated linearly in time as players do, passes within the exporter's
    tolerance (2 cm and 0.02 rad, plus the file's rounding) of its table pose at every frame (`frames` for the
    ego, `vehicles`, `cyclists`, `tracks`), and its Init teleport is its first pose.

Run: `python tests/interop_xosc.py DATASET XOSC_DIR [--every N]` (XOSC_DIR from `pedsynth export openscenario
DATASET --out XOSC_DIR`; `--every N` checks every Nth clip in clip-id order, for large sets: PedSynth++'s 600
take about 5 CPU-minutes whole). Exits 1 on the first clip that disagrees.
"""

import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
from scenariogeneration import xosc

TOL_M = 0.02 + 0.002
TOL_RAD = 0.02 + 0.001


def rows_of(root: Path, name: str, clip_id: str) -> list[dict]:
    """The rows of one clip's file of a table (none where the dataset has no such file)."""
    path = root / "tables" / name / f"{clip_id}.parquet"
    if not path.is_file():
        return []
    t = pq.read_table(path).to_pydict()
    return [dict(zip(t, values)) for values in zip(*t.values())]


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def fail(msg: str) -> None:
    print(f"interop_xosc: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


def check_clip(clip: dict, root: Path, xosc_dir: Path) -> tuple[int, int, int]:
    cid = clip["clip_id"]
    fps = clip["fps"]
    s = xosc.ParseOpenScenario(str(xosc_dir / f"{cid}.xosc"))
    road = s.roadnetwork.road_file
    if road != f"towns/{clip['town']}.xodr" or not (xosc_dir / road).is_file():
        fail(f"{cid}: road network {road!r}")
    objects = {o.name: o.entityobject for o in s.entities.scenario_objects}
    init = s.storyboard.init.initactions

    # The table poses of every moving entity, per frame.
    poses: dict[str, list[tuple[int, float, float, float, float]]] = defaultdict(list)
    for r in rows_of(root, "frames", cid):
        poses["ego"].append((r["frame"], r["ego_x_m"], r["ego_y_m"], r["ego_z_m"], r["ego_yaw_rad"]))
    for kind, key in [("vehicles", "vehicle"), ("cyclists", "cyclist"), ("tracks", "pedestrian")]:
        name = {"vehicles": "vehicle", "cyclists": "cyclist", "tracks": "pedestrian"}[kind]
        for r in rows_of(root, kind, cid):
            poses[f"{name}_{r[key]}"].append((r["frame"], r["x_m"], r["y_m"], r["z_m"], r["yaw_rad"]))
    parked = {f"parked_car_{r['parked_car']}": r for r in rows_of(root, "parked_cars", cid)}
    if set(objects) != set(poses) | set(parked):
        fail(f"{cid}: entities {sorted(set(objects) ^ (set(poses) | set(parked)))} differ from the tables")

    trajectories = {}
    for story in s.storyboard.stories:
        for act in story.acts:
            for group in act.maneuvergroup:
                (actor,) = group.actors.actors
                for maneuver in group.maneuvers:
                    for event in maneuver.events:
                        for action in event.action:
                            follow = action.action
                            if isinstance(follow, xosc.FollowTrajectoryAction):
                                trajectories[actor.entity] = follow.trajectory.shapes

    for name, row in parked.items():
        car = objects[name]
        dims = car.boundingbox.boundingbox
        got = (dims.length, dims.width, dims.height)
        want = (row["length_m"], row["width_m"], row["height_m"])
        if not np.allclose(got, want, atol=1e-5):
            fail(f"{cid} {name}: size {got}, table {want}")
        if ("parked", "true") not in car.properties.properties:
            fail(f"{cid} {name}: no property parked")
        if name in trajectories:
            fail(f"{cid} {name}: a parked car with a trajectory")
        (teleport,) = init[name]
        p = teleport.position
        if np.hypot(p.x - row["x_m"], p.y - row["y_m"]) > 1e-3 or abs(p.z - row["z_m"]) > 1e-3 or abs(
            wrap(p.h - row["yaw_rad"])
        ) > 1e-3:
            fail(f"{cid} {name}: placed at ({p.x}, {p.y}, {p.z}, {p.h}), table {row}")

    frames_checked = 0
    for name, entity_rows in poses.items():
        entity_rows.sort()
        f, x, y, z, h = (np.array(c, dtype=np.float64) for c in zip(*entity_rows))
        line = trajectories.get(name)
        if line is None:
            fail(f"{cid} {name}: no trajectory")
        t = np.array(line.time, dtype=np.float64)
        px = np.array([q.x for q in line.positions])
        py = np.array([q.y for q in line.positions])
        pz = np.array([q.z for q in line.positions])
        ph = np.array([q.h for q in line.positions])
        at = f / fps
        d = np.sqrt(
            (np.interp(at, t, px) - x) ** 2 + (np.interp(at, t, py) - y) ** 2 + (np.interp(at, t, pz) - z) ** 2
        )
        dh = np.abs(wrap(np.interp(at, t, ph) - h))
        if d.max() > TOL_M or dh.max() > TOL_RAD:
            k = int(np.argmax(d))
            fail(f"{cid} {name}: polyline {d.max():.4f} m / {dh.max():.4f} rad off the table (frame {int(f[k])})")
        (teleport,) = init[name]
        p = teleport.position
        if np.hypot(p.x - x[0], p.y - y[0]) > 1e-3 or abs(wrap(p.h - h[0])) > 1e-3:
            fail(f"{cid} {name}: Init teleport ({p.x}, {p.y}, {p.h}) is not its first pose")
        frames_checked += len(f)
    return len(poses), len(parked), frames_checked


def main() -> int:
    args = sys.argv[1:]
    every = 1
    if len(args) == 4 and args[2] == "--every" and args[3].isdigit() and int(args[3]) > 0:
        every = int(args[3])
        args = args[:2]
    if len(args) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    root, xosc_dir = Path(args[0]), Path(args[1])
    clips = []
    for path in sorted((root / "tables" / "clips").glob("*.parquet"))[::every]:
        clips += rows_of(root, "clips", path.stem)
    if not clips:
        fail(f"{root}: no clips")
    moving = parked = frames = 0
    for clip in clips:
        m, p, f = check_clip(clip, root, xosc_dir)
        moving, parked, frames = moving + m, parked + p, frames + f
    if parked == 0:
        fail("the dataset has no parked cars: nothing of theirs was checked")
    print(
        f"interop_xosc: OK: {len(clips)} scenarios parsed by scenariogeneration; {moving} moving entities match the "
        f"tables at {frames} entity-frames, {parked} parked cars their rows"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
