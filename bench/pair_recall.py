#!/usr/bin/env python3
"""Recall of pair selection against a synthetic survey's ground truth.

Reads the pairs a database has attempted (a row in two_view_geometries each) and verified
(an accepted geometry with inliers), and gt/overlap_pairs.txt (NAME1 NAME2 SHARED_POINTS);
prints one JSON object: pairs attempted per image and the share of ground-truth pairs with
at least --min-shared points that were verified.
"""
import argparse
import json
import sqlite3
import sys

# COLMAP's TwoViewGeometry::ConfigurationType: 0 undefined, 1 degenerate.
UNVERIFIED_CONFIGS = (0, 1)
MAX_NUM_IMAGES = 2147483647


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--database", required=True)
    parser.add_argument("--overlap-pairs", required=True, help="gt/overlap_pairs.txt")
    parser.add_argument("--min-shared", type=int, default=100)
    args = parser.parse_args()

    db = sqlite3.connect(args.database)
    names = dict(db.execute("SELECT image_id, name FROM images"))
    attempted, verified = set(), set()
    for pair_id, rows, config in db.execute("SELECT pair_id, rows, config FROM two_view_geometries"):
        id2 = pair_id % MAX_NUM_IMAGES
        id1 = (pair_id - id2) // MAX_NUM_IMAGES
        pair = tuple(sorted((names[id1], names[id2])))
        attempted.add(pair)
        if rows > 0 and config not in UNVERIFIED_CONFIGS:
            verified.add(pair)

    truth = []
    with open(args.overlap_pairs) as stream:
        for line in stream:
            name1, name2, shared = line.split()
            if int(shared) >= args.min_shared:
                truth.append(tuple(sorted((name1, name2))))
    found = sum(1 for pair in truth if pair in verified)
    attempted_truth = sum(1 for pair in truth if pair in attempted)
    num_images = len(names)
    json.dump({
        "images": num_images,
        "pairs_attempted": len(attempted),
        "pairs_attempted_per_image": round(len(attempted) / max(num_images, 1), 2),
        "pairs_verified": len(verified),
        "truth_pairs": len(truth),
        "min_shared_points": args.min_shared,
        "truth_attempted": attempted_truth,
        "truth_verified": found,
        "recall": round(found / max(len(truth), 1), 4),
    }, sys.stdout)
    print()


if __name__ == "__main__":
    main()
