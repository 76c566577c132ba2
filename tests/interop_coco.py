"""Interop (issue 45): pycocotools, unmodified, reads `pedsynth export coco` and agrees with our tables.

Usage: python3 tests/interop_coco.py DATASET --pedsynth PATH/TO/pedsynth

Exports DATASET as COCO into a temporary directory, then, for every split's annotation file:
- pycocotools' COCO() loads it; every image file it names exists;
- COCOeval of the ground truth scored as detections gives AP 1.0 for `bbox`, `segm` (when the dataset has
  masks) and `keypoints`; faster-coco-eval's own COCO reader and evaluator (a second implementation) load the
  file and give AP 1.0 too;
- every decoded mask (pycocotools' annToMask) equals the instance image's pixels of that instance, and `area`
  is their count;
- the annotations are, one for one, the `annotations` table's rows (and the annotated cyclists' rows): boxes,
  keypoints in COCO order, crossing labels.
Any difference fails with a message.
"""

import argparse
import contextlib
import io
import json
import pathlib
import subprocess
import sys
import tempfile

import numpy as np
import pyarrow.parquet as pq
from PIL import Image
from pycocotools import mask as mask_utils
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval
import faster_coco_eval


def fail(msg):
    print(f"interop_coco: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def table(root, name):
    files = sorted((root / "tables" / name).glob("*.parquet"))
    return [r for f in files for r in pq.read_table(f).to_pylist()]


def detections(gt, kind):
    """The ground truth of `gt` as detections of `kind`, each scored 1."""
    dets = []
    for a in gt.dataset["annotations"]:
        d = {"image_id": a["image_id"], "category_id": a["category_id"], "bbox": a["bbox"], "score": 1.0}
        if kind == "segm":
            d["segmentation"] = a["segmentation"]
        if kind == "keypoints":
            d["keypoints"] = a["keypoints"]
        dets.append(d)
    return dets


def evaluate(gt, kind, evaluator=COCOeval):
    """AP over IoU 0.50:0.95 of the ground truth scored as detections, by `evaluator`."""
    with contextlib.redirect_stdout(io.StringIO()):
        dt = gt.loadRes(detections(gt, kind))
        ev = evaluator(gt, dt, kind)
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    return ev.stats[0]


def evaluate_faster(path, kind):
    """faster-coco-eval's own COCO reader and evaluator on the file."""
    with contextlib.redirect_stdout(io.StringIO()):
        gt = faster_coco_eval.COCO(str(path))
    return evaluate(gt, kind, faster_coco_eval.COCOeval_faster)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset", type=pathlib.Path)
    ap.add_argument("--pedsynth", required=True)
    args = ap.parse_args()
    root = args.dataset
    manifest = json.loads((root / "manifest.json").read_text())
    with_masks = manifest["sensors"].get("instance", "disabled").startswith("rendered")
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "coco"
        subprocess.run([args.pedsynth, "export", "coco", str(root), "--out", str(out)], check=True)
        files = sorted((out / "annotations").glob("*.json"))
        if not files:
            fail("no annotation files")
        rows = {(r["clip_id"], r["frame"], "pedestrian", r["pedestrian"]): r for r in table(root, "annotations")}
        for r in table(root, "cyclists"):
            if r["annotated"]:
                rows[(r["clip_id"], r["frame"], "cyclist", r["cyclist"])] = r
        seen = set()
        for f in files:
            with contextlib.redirect_stdout(io.StringIO()):
                gt = COCO(str(f))
            images = gt.dataset["images"]
            anns = gt.dataset["annotations"]
            for img in images:
                if not (out / "images" / img["file_name"]).is_file():
                    fail(f"{f.name}: image {img['file_name']} is missing")
            cats = {c["id"]: c["name"] for c in gt.dataset["categories"]}
            kinds = ["bbox", "keypoints"] + (["segm"] if with_masks else [])
            for kind in kinds:
                ap_all = evaluate(gt, kind)
                if abs(ap_all - 1.0) > 1e-9:
                    fail(f"{f.name}: COCOeval {kind} of the ground truth as detections gives AP {ap_all}, not 1")
                ap_faster = evaluate_faster(f, kind)
                if abs(ap_faster - 1.0) > 1e-9:
                    fail(f"{f.name}: faster-coco-eval {kind} of the ground truth as detections gives AP "
                         f"{ap_faster}, not 1")
            masks_checked = 0
            by_image = {}
            for a in anns:
                by_image.setdefault(a["image_id"], []).append(a)
            for img in images:
                inst = None
                for a in by_image.get(img["id"], []):
                    name = cats[a["category_id"]]
                    key = (img["clip_id"], img["frame"], name, a["instance"])
                    if key not in rows:
                        fail(f"{f.name}: annotation {a['id']} has no row in our tables: {key}")
                    seen.add(key)
                    r = rows[key]
                    box = [r["bbox_x_min"], r["bbox_y_min"], r["bbox_x_max"], r["bbox_y_max"]] if name == "pedestrian" \
                        else [r["x1"], r["y1"], r["x2"], r["y2"]]
                    want = [box[0], box[1], box[2] - box[0], box[3] - box[1]]
                    if not np.allclose(a["bbox"], want, atol=1e-3):
                        fail(f"{f.name}: annotation {a['id']}: bbox {a['bbox']} vs the table's {want}")
                    kp = np.array(r["keypoints"], dtype=np.float64).reshape(-1, 3)
                    ours = np.array(a["keypoints"], dtype=np.float64).reshape(17, 3)
                    if len(kp) == 17:
                        for j in range(17):
                            if kp[j, 2] >= 1 and not np.allclose(ours[j], kp[j], atol=1e-3):
                                fail(f"{f.name}: annotation {a['id']}: joint {j} {ours[j]} vs {kp[j]}")
                            if kp[j, 2] == 0 and ours[j].any():
                                fail(f"{f.name}: annotation {a['id']}: joint {j} is out of the image but not 0")
                    if a["num_keypoints"] != int((ours[:, 2] > 0).sum()):
                        fail(f"{f.name}: annotation {a['id']}: num_keypoints {a['num_keypoints']}")
                    if name == "pedestrian" and a["crossing"] != r["crossing"]:
                        fail(f"{f.name}: annotation {a['id']}: crossing differs from the table")
                    if with_masks:
                        if inst is None:
                            inst = np.asarray(Image.open(root / "sensors" / "instance" / img["clip_id"]
                                                         / f"{img['frame']:06}.png"))
                        base = 1 if name == "pedestrian" else 49152
                        want_mask = inst == base + a["instance"]
                        got = gt.annToMask(a).astype(bool)
                        if got.shape != want_mask.shape or not np.array_equal(got, want_mask):
                            fail(f"{f.name}: annotation {a['id']}: the decoded mask differs from the instance "
                                 f"pixels ({int(got.sum())} vs {int(want_mask.sum())})")
                        if a["area"] != int(want_mask.sum()) or int(mask_utils.area(a["segmentation"])) != a["area"]:
                            fail(f"{f.name}: annotation {a['id']}: area {a['area']} vs {int(want_mask.sum())}")
                        masks_checked += 1
            print(f"interop_coco: {f.name}: pycocotools loads {len(images)} images, {len(anns)} annotations "
                  f"({', '.join(sorted(set(cats.values())))}); COCOeval and faster-coco-eval AP 1.0 for "
                  f"{', '.join(kinds)}; "
                  f"{masks_checked} decoded masks equal the instance pixels")
        missing = set(rows) - seen
        if missing:
            fail(f"{len(missing)} annotated rows of our tables are not in the export, e.g. {sorted(missing)[:3]}")
    print("interop_coco: ok")


if __name__ == "__main__":
    main()
