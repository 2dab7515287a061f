#!/usr/bin/env python3
"""Recall of pair selection against a synthetic survey's ground truth.

Reads the pairs a database has attempted (a row in two_view_geometries each) and verified
(an accepted geometry with inliers), and gt/overlap_pairs.txt (NAME1 NAME2 SHARED_POINTS);
prints one JSON object: pairs attempted per image and the share of ground-truth pairs with
at least --min-shared points that were verified.

With --explain it also says why the missed pairs were missed: not attempted, or attempted
and not verified; and for the latter, how many of their putative matches agree with the
ground-truth cameras (DIR/*_par.txt), which tells a matcher that found no correspondences
from a verification that turned good ones down.
"""
import argparse
import glob
import json
import os
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
    parser.add_argument("--explain", action="store_true",
                        help="add why the missed pairs were missed (needs numpy)")
    parser.add_argument("--max-epipolar-error", type=float, default=2.0,
                        help="--explain: pixels from the true epipolar line that count as agreeing")
    parser.add_argument("--min-num-inliers", type=int, default=15,
                        help="--explain: agreeing matches a verification needs (parallax's default)")
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
    result = {
        "images": num_images,
        "pairs_attempted": len(attempted),
        "pairs_attempted_per_image": round(len(attempted) / max(num_images, 1), 2),
        "pairs_verified": len(verified),
        "truth_pairs": len(truth),
        "min_shared_points": args.min_shared,
        "truth_attempted": attempted_truth,
        "truth_verified": found,
        "recall": round(found / max(len(truth), 1), 4),
    }
    if args.explain:
        failed = [pair for pair in truth if pair in attempted and pair not in verified]
        scene = os.path.dirname(os.path.dirname(os.path.abspath(args.overlap_pairs)))
        result["missed"] = explain_failures(db, names, failed, scene, args)
    json.dump(result, sys.stdout)
    print()


def read_cameras(scene):
    """name -> (K, R, t) from the scene's NAME_par.txt (x ~ K (R X + t))."""
    import numpy as np
    files = glob.glob(os.path.join(scene, "*_par.txt"))
    if len(files) != 1:
        sys.exit(f"pair_recall.py: {scene}: expected one *_par.txt, found {len(files)}")
    cameras = {}
    with open(files[0]) as stream:
        for line in stream.readlines()[1:]:
            fields = line.split()
            values = np.array([float(v) for v in fields[1:22]])
            cameras[fields[0]] = (values[0:9].reshape(3, 3), values[9:18].reshape(3, 3), values[18:21])
    return cameras


def fundamental(camera1, camera2):
    """The true fundamental matrix x2^T F x1 = 0 of two cameras."""
    import numpy as np
    (k1, r1, t1), (k2, r2, t2) = camera1, camera2
    rotation = r2 @ r1.T
    translation = t2 - rotation @ t1
    cross = np.array([[0, -translation[2], translation[1]], [translation[2], 0, -translation[0]],
                      [-translation[1], translation[0], 0]])
    return np.linalg.inv(k2).T @ cross @ rotation @ np.linalg.inv(k1)


def explain_failures(db, names, failed, scene, args):
    """Putative matches of the attempted-but-unverified truth pairs, and how many of them lie
    within --max-epipolar-error pixels (Sampson) of the true epipolar geometry."""
    import numpy as np
    cameras = read_cameras(scene)
    ids = {name: image_id for image_id, name in names.items()}

    def keypoints(image_id):
        rows, cols, data = db.execute("SELECT rows, cols, data FROM keypoints WHERE image_id = ?",
                                      (image_id,)).fetchone()
        return np.frombuffer(data, dtype=np.float32).reshape(rows, cols)[:, :2].astype(np.float64)

    putatives, agreeing = [], []
    for name1, name2 in failed:
        id1, id2 = sorted((ids[name1], ids[name2]))
        row = db.execute("SELECT rows, cols, data FROM matches WHERE pair_id = ?",
                         (id1 * MAX_NUM_IMAGES + id2,)).fetchone()
        if row is None or row[0] == 0:
            putatives.append(0)
            agreeing.append(0)
            continue
        matches = np.frombuffer(row[2], dtype=np.uint32).reshape(row[0], row[1])
        points1 = np.c_[keypoints(id1)[matches[:, 0]], np.ones(row[0])]
        points2 = np.c_[keypoints(id2)[matches[:, 1]], np.ones(row[0])]
        f = fundamental(cameras[names[id1]], cameras[names[id2]])
        line2, line1 = points1 @ f.T, points2 @ f
        sampson = np.sum(points2 * line2, 1) ** 2 / (
            line2[:, 0] ** 2 + line2[:, 1] ** 2 + line1[:, 0] ** 2 + line1[:, 1] ** 2)
        putatives.append(int(row[0]))
        agreeing.append(int(np.sum(sampson < args.max_epipolar_error ** 2)))

    def quartiles(values):
        ordered = sorted(values)
        return [ordered[len(ordered) * q // 4] for q in (1, 2, 3)] if ordered else []

    return {
        "attempted_not_verified": len(failed),
        "putative_matches_quartiles": quartiles(putatives),
        "agreeing_with_truth_quartiles": quartiles(agreeing),
        "with_enough_agreeing": sum(1 for count in agreeing if count >= args.min_num_inliers),
    }


if __name__ == "__main__":
    main()
