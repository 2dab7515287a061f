#!/usr/bin/env python3
"""What the Python module costs over the command line (issue 16's figures).

    PYTHONPATH=build/python python3 bench/python_overhead.py [--runs 2] [--dataset templeRing]

1. `parallax reconstruct` on a data set with its known K, by the CLI (build/parallax, a
   process per run) and by parallax.reconstruct in this process, alternated, fresh output
   folders each run; prints each wall time and the ratio of the medians.
2. Reading a model of 100,000 points (written by this script: 20 images, three observations
   per point) into numpy: Reconstruction.read plus point3D_xyz, point3D_colors,
   point3D_errors and projection_centers; the median of five reads.
"""

import argparse
import os
import pathlib
import statistics
import subprocess
import tempfile
import time

import numpy as np

import parallax

REPO = pathlib.Path(__file__).resolve().parents[1]


def known_k(dataset_dir, output):
    """K.txt of the data set, or the first K of its Middlebury *_par.txt."""
    if (dataset_dir / "K.txt").exists():
        return dataset_dir / "K.txt"
    par = next(dataset_dir.glob("*_par.txt"))
    K = np.array(par.read_text().split("\n")[1].split()[1:10], float).reshape(3, 3)
    path = output / "K.txt"
    np.savetxt(path, K)
    return path


def time_reconstruct(binary, images, K, work, runs):
    cli_times, python_times = [], []
    for run in range(runs):
        start = time.perf_counter()
        subprocess.run([str(binary), "reconstruct", "--images", str(images), "--output",
                        str(work / f"cli-{run}"), "--intrinsics", str(K), "--quiet"], check=True)
        cli_times.append(time.perf_counter() - start)
        start = time.perf_counter()
        parallax.reconstruct(images, work / f"python-{run}", intrinsics=K)
        python_times.append(time.perf_counter() - start)
        print(f"run {run + 1}: CLI {cli_times[-1]:.2f} s, Python {python_times[-1]:.2f} s")
    ratio = statistics.median(python_times) / statistics.median(cli_times)
    print(f"median: CLI {statistics.median(cli_times):.2f} s, Python "
          f"{statistics.median(python_times):.2f} s, Python / CLI = {ratio:.3f}")


def write_large_model(directory, num_points=100_000, num_images=20, track_length=3):
    """A consistent text model: every point seen by `track_length` images, then as .bin."""
    rng = np.random.default_rng(0)
    text = directory / "text"
    text.mkdir()
    (text / "cameras.txt").write_text("1 PINHOLE 640 480 500 500 320 240\n")
    observers = np.stack([rng.choice(num_images, track_length, replace=False)
                          for _ in range(num_points)])
    keypoint_index = np.zeros((num_points, track_length), int)
    per_image = [[] for _ in range(num_images)]
    for point in range(num_points):
        for slot, image in enumerate(observers[point]):
            keypoint_index[point, slot] = len(per_image[image])
            per_image[image].append(point + 1)
    lines = []
    for image in range(num_images):
        lines.append(f"{image + 1} 1 0 0 0 {image * 0.1} 0 0 1 view{image:03d}.png")
        xy = rng.uniform(0, 480, size=(len(per_image[image]), 2))
        lines.append(" ".join(f"{x:.2f} {y:.2f} {p}" for (x, y), p in zip(xy, per_image[image])))
    (text / "images.txt").write_text("\n".join(lines) + "\n")
    xyz = rng.normal(size=(num_points, 3)) + [0, 0, 5]
    rows = []
    for point in range(num_points):
        track = " ".join(f"{observers[point, s] + 1} {keypoint_index[point, s]}"
                         for s in range(track_length))
        rows.append(f"{point + 1} {xyz[point, 0]:.6f} {xyz[point, 1]:.6f} {xyz[point, 2]:.6f} "
                    f"128 128 128 0.5 {track}")
    (text / "points3D.txt").write_text("\n".join(rows) + "\n")
    binary = directory / "binary"
    parallax.read_model(text).write(binary)
    return binary


def time_model_read(directory):
    model_dir = write_large_model(directory)
    times = []
    for _ in range(5):
        start = time.perf_counter()
        model = parallax.read_model(model_dir)
        xyz, colors = model.point3D_xyz(), model.point3D_colors()
        errors, centers = model.point3D_errors(), model.projection_centers()
        times.append(time.perf_counter() - start)
    assert xyz.shape == (100_000, 3) and colors.shape == (100_000, 3)
    assert errors.shape == (100_000,) and centers.shape == (20, 3)
    print(f"read 100,000 points into numpy: median {statistics.median(times):.3f} s "
          f"(runs: {', '.join(f'{t:.3f}' for t in times)})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--dataset", default="templeRing")
    parser.add_argument("--binary", type=pathlib.Path,
                        default=pathlib.Path(os.environ.get("PARALLAX_BINARY",
                                                            REPO / "build" / "parallax")))
    args = parser.parse_args()
    data = pathlib.Path(os.environ.get("PARALLAX_DATA", REPO.parent / "shared" / "data"))
    parallax.set_log_level("warning")
    with tempfile.TemporaryDirectory() as work:
        work = pathlib.Path(work)
        dataset = data / args.dataset
        images = dataset / "images" if (dataset / "images").is_dir() else dataset
        time_reconstruct(args.binary, images, known_k(dataset, work), work, args.runs)
        (work / "model").mkdir()
        time_model_read(work / "model")


if __name__ == "__main__":
    main()
