#!/usr/bin/env python3
"""The paper's experiment from Python: templeRing reconstructed with its known K, evaluated
against the ground truth, ending with the reprojection error per image before and after
bundle adjustment and the camera trajectory (Zeeshan et al., figures 5-8), using only the
parallax API.

    PYTHONPATH=build/python python3 examples/paper_figures.py \\
        --images ../shared/data/templeRing --output runs/templeRing

templeRing's folder holds the images and templeR_par.txt (K [R | t] per image); K is read from
it. Writes OUT/reprojection_errors.png and OUT/trajectory.png beside the model.
"""

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")  # Files, not windows: runs headless (in a notebook, drop this line).
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import parallax  # noqa: E402


def known_intrinsics(par_file, output):
    """K of the first view of a Middlebury *_par.txt, written as K.txt for the pipeline."""
    first = par_file.read_text().split("\n")[1].split()
    K = np.array(first[1:10], float).reshape(3, 3)
    path = output / "K.txt"
    np.savetxt(path, K)
    return path


def plot_reprojection_errors(summary, path):
    images = [image for image in summary["images"] if image["registered"]]
    names = [image["name"] for image in images]
    before = [image["reprojection_error_before_ba_px"] for image in images]
    after = [image["reprojection_error_after_ba_px"] for image in images]
    positions = np.arange(len(images))
    figure, axes = plt.subplots(figsize=(12, 4))
    axes.bar(positions - 0.2, before, width=0.4, label="before bundle adjustment")
    axes.bar(positions + 0.2, after, width=0.4, label="after bundle adjustment")
    axes.set_xticks(positions, names, rotation=90, fontsize=7)
    axes.set_ylabel("mean reprojection error (px)")
    axes.legend()
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def plot_trajectory(model, path):
    # Centres in the order the photos were taken (their names), as the paper draws the path.
    ids = sorted(model.reg_image_ids(), key=lambda image_id: model.images[image_id].name)
    centers = model.projection_centers()[[model.reg_image_ids().index(i) for i in ids]]
    xyz = model.point3D_xyz()
    colors = model.point3D_colors() / 255.0
    keep = np.linalg.norm(xyz - np.median(xyz, axis=0), axis=1) < 3 * np.linalg.norm(
        centers - centers.mean(axis=0), axis=1).mean()
    # The model's frame is arbitrary: shown in the cameras' principal axes, whose last one is
    # the normal of the plane they move in, so that plane is the plot's ground.
    mean = centers.mean(axis=0)
    axes_of_motion = np.linalg.svd(centers - mean)[2]
    centers, xyz = (centers - mean) @ axes_of_motion.T, (xyz - mean) @ axes_of_motion.T
    figure = plt.figure(figsize=(7, 7))
    axes = figure.add_subplot(projection="3d")
    axes.scatter(*xyz[keep].T, c=colors[keep], s=0.5)
    axes.plot(*centers.T, "-o", color="tab:red", markersize=3, label="camera centres")
    # The same scale on every axis, so the scene keeps its shape.
    extent = np.vstack([xyz[keep], centers])
    axes.set_box_aspect(np.ptp(extent, axis=0))
    axes.set_title(f"{model.num_reg_images()} cameras, {model.num_points3D()} points")
    axes.legend()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--images", type=pathlib.Path, required=True)
    parser.add_argument("--output", type=pathlib.Path, required=True)
    parser.add_argument("--gt", type=pathlib.Path, help="*_par.txt (default: the one in --images)")
    args = parser.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    gt = args.gt or next(args.images.glob("*_par.txt"))

    def progress(stage, done, total):
        print(f"\r{stage}: {done}/{total}   ", end="", flush=True)

    parallax.set_log_level("warning")
    result = parallax.reconstruct(args.images, args.output, ground_truth=gt,
                                  intrinsics=known_intrinsics(gt, args.output), progress=progress)
    print()
    model = result.models[0]
    metrics = result.evaluation
    print(f"registered {model.num_reg_images()}/{metrics['images_gt']} images, "
          f"{model.num_points3D()} points, mean track length {model.mean_track_length():.2f}")
    print(f"median rotation error {metrics['rotation_error_deg']['median']:.4f} deg, "
          f"median centre error {metrics['center_error']['median']:.5f} (GT units)")
    print(f"time: {result.summary['timings_s']['total']:.1f} s")
    plot_reprojection_errors(result.summary, args.output / "reprojection_errors.png")
    plot_trajectory(model, args.output / "trajectory.png")
    print(f"wrote {args.output / 'reprojection_errors.png'} and {args.output / 'trajectory.png'}")


if __name__ == "__main__":
    main()
