#!/usr/bin/env python3
"""The dataset card that `pedsynth generate` writes (README.md) lets Hugging Face's own `datasets` package load
every table as is: `load_dataset(DIR, TABLE)` for each config of the card, offline, and the rows it returns
equal the Parquet tables read with pyarrow (same count per split, same values in a few key columns). Also
checks the card's licence field and counts against the tables.

    python3 tests/hf_card.py DATASET_DIR [--license ID]
"""

import argparse
import glob
import os
import sys
import tempfile

os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")

import pyarrow.parquet as pq  # noqa: E402
import yaml  # noqa: E402
from datasets import load_dataset  # noqa: E402

SPLITS = {"train": "train", "val": "validation", "test": "test"}


def front_matter(path: str) -> dict:
    text = open(path, encoding="utf-8").read()
    if not text.startswith("---\n"):
        sys.exit(f"{path}: no front matter")
    return yaml.safe_load(text.split("---\n", 2)[1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("--license", default="unknown")
    args = ap.parse_args()
    card = front_matter(os.path.join(args.dataset, "README.md"))
    if card["license"] != args.license:
        sys.exit(f"card licence {card['license']!r}, expected {args.license!r}")
    configs = {c["config_name"]: c for c in card["configs"]}
    tables = sorted(os.listdir(os.path.join(args.dataset, "tables")))
    rows = {
        t: sum(pq.read_metadata(f).num_rows for f in glob.glob(os.path.join(args.dataset, f"tables/{t}/*.parquet")))
        for t in tables
    }
    # A table without any row (`sensors` of a dataset without sensors) has no config: `datasets` cannot load
    # a split without data.
    if sorted(configs) != [t for t in tables if rows[t] > 0]:
        sys.exit(f"configs {sorted(configs)} != the tables with rows {[t for t in tables if rows[t] > 0]}")
    tables = sorted(configs)
    # Which split each clip is in, from the clips table.
    split_of = {}
    for f in glob.glob(os.path.join(args.dataset, "tables/clips/*.parquet")):
        t = pq.read_table(f, columns=["clip_id", "split"]).to_pylist()[0]
        split_of[t["clip_id"]] = SPLITS[t["split"]]
    with tempfile.TemporaryDirectory() as cache:
        for table in tables:
            ds = load_dataset(args.dataset, table, cache_dir=cache)
            for split in ds:
                files = [
                    f
                    for f in sorted(glob.glob(os.path.join(args.dataset, f"tables/{table}/*.parquet")))
                    if split_of[os.path.basename(f)[: -len(".parquet")]] == split
                ]
                want = [r for f in files for r in pq.read_table(f).to_pylist()]
                got = ds[split]
                if len(got) != len(want):
                    sys.exit(f"{table}/{split}: datasets gives {len(got)} rows, the Parquet files {len(want)}")
                key = [c for c in ("clip_id", "frame", "pedestrian", "vehicle", "crossing", "x_m", "keypoints") if c in got.column_names]
                got_rows = sorted(tuple(str(r[c]) for c in key) for r in got.select_columns(key))
                want_rows = sorted(tuple(str(r[c]) for c in key) for r in want)
                if got_rows != want_rows:
                    sys.exit(f"{table}/{split}: the rows datasets returns differ from the Parquet files in {key}")
            with_rows = {
                split_of[os.path.basename(f)[: -len(".parquet")]]
                for f in glob.glob(os.path.join(args.dataset, f"tables/{table}/*.parquet"))
                if pq.read_metadata(f).num_rows > 0
            }
            expected_splits = sorted(with_rows)
            if sorted(ds) != expected_splits:
                sys.exit(f"{table}: splits {sorted(ds)} != {expected_splits}")
            print(f"hf_card: {table}: {', '.join(f'{s} {len(ds[s])} rows' for s in ds)}")
    default = [c for c in card["configs"] if c.get("default")]
    if [c["config_name"] for c in default] != ["annotations"]:
        sys.exit(f"default config: {default}")
    print(f"hf_card: datasets.load_dataset reads all {len(tables)} tables with rows of {args.dataset} as the card describes")


if __name__ == "__main__":
    main()
