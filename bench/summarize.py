#!/usr/bin/env python3
"""Tabulates a bench/run.sh output folder: markdown on stdout, OUT/results.json.

    bench/summarize.py OUT DATASET...
"""
import json
import os
import re
import sys


def read_time(path):
    """Wall seconds, CPU seconds and peak resident MiB from a `/usr/bin/time -v` report."""
    if not os.path.exists(path):
        return None
    text = open(path).read()
    result = {}
    match = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", text)
    if match:
        seconds = 0.0
        for part in match.group(1).split(":"):
            seconds = seconds * 60 + float(part)
        result["wall_s"] = seconds
    user = re.search(r"User time \(seconds\): (\S+)", text)
    system = re.search(r"System time \(seconds\): (\S+)", text)
    if user and system:
        result["cpu_s"] = float(user.group(1)) + float(system.group(1))
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", text)
    if rss:
        result["peak_rss_mib"] = int(rss.group(1)) / 1024.0
    status = re.search(r"Exit status: (\d+)", text)
    result["exit_status"] = int(status.group(1)) if status else None
    return result


def read_json(path):
    return json.load(open(path)) if os.path.exists(path) else None


def model_stats(evaluation):
    """Registered images, points, reprojection error and GT accuracy of an evaluate --json."""
    if not evaluation:
        return {}
    return {
        "images_registered": evaluation.get("images_registered"),
        "images_total": evaluation.get("images_gt"),
        "points3D": evaluation.get("points3D"),
        "observations": evaluation.get("observations"),
        "mean_track_length": evaluation.get("mean_track_length"),
        "mean_reprojection_error_px": evaluation.get("mean_reprojection_error_px"),
        "center_error_median": (evaluation.get("center_error") or {}).get("median"),
        "center_error_relative_median": (evaluation.get("center_error_relative") or {}).get("median"),
        "rotation_error_deg_median": (evaluation.get("rotation_error_deg") or {}).get("median"),
    }


def summarize(run):
    result = {"parallax": {}, "colmap": {}, "mapping_only": {}}
    parallax = result["parallax"]
    process = read_time(os.path.join(run, "parallax.time")) or {}
    summary = read_json(os.path.join(run, "parallax", "summary.json")) or {}
    timings = summary.get("timings_s", {})
    parallax.update({
        "features_s": timings.get("features"),
        "matching_s": timings.get("matching"),
        "mapping_s": timings.get("mapping"),
        "total_s": process.get("wall_s"),
        "cpu_s": process.get("cpu_s"),
        "peak_rss_mib": process.get("peak_rss_mib"),
        "pairs_verified": summary.get("matching", {}).get("pairs_verified"),
    })
    log = os.path.join(run, "parallax.log")
    if os.path.exists(log):
        match = re.search(r"thread time: matching (\S+) s, verification (\S+) s\)", open(log).read())
        if match:
            parallax["matching_thread_s"] = float(match.group(1))
            parallax["verification_thread_s"] = float(match.group(2))
    stats = model_stats(read_json(os.path.join(run, "eval_parallax.json")))
    if not stats and summary:
        stats = {"images_registered": summary.get("images_registered_largest_model"),
                 "images_total": summary.get("images_total"),
                 "points3D": summary.get("points3D"),
                 "mean_reprojection_error_px": summary.get("mean_reprojection_error_px")}
    parallax.update(stats)

    stages = {name: read_time(os.path.join(run, f"colmap_{name}.time"))
              for name in ("features", "matching", "mapping")}
    if any(stages.values()):
        colmap = result["colmap"]
        for name, measured in stages.items():
            colmap[f"{name}_s"] = measured.get("wall_s") if measured else None
        walls = [measured.get("wall_s") for measured in stages.values() if measured]
        colmap["total_s"] = sum(walls) if len(walls) == 3 else None
        colmap["cpu_s"] = sum(measured.get("cpu_s", 0) for measured in stages.values() if measured)
        colmap["peak_rss_mib"] = max(measured.get("peak_rss_mib", 0)
                                     for measured in stages.values() if measured)
        colmap.update(model_stats(read_json(os.path.join(run, "eval_colmap.json"))))
        # The mapping stage alone on COLMAP's database (the same matches for both mappers).
        mapper = read_time(os.path.join(run, "parallax_mapper.time")) or {}
        result["mapping_only"] = {
            "parallax_s": mapper.get("wall_s"),
            "parallax_peak_rss_mib": mapper.get("peak_rss_mib"),
            "colmap_s": colmap.get("mapping_s"),
            "colmap_peak_rss_mib": (stages["mapping"] or {}).get("peak_rss_mib"),
            "parallax_model": model_stats(read_json(os.path.join(run, "eval_parallax_mapper.json"))),
        }
    return result


def fmt(value, digits=2):
    if value is None:
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def ratio(numerator, denominator, digits=1):
    if numerator is None or denominator is None or denominator == 0:
        return "–"
    return f"{numerator / denominator:.{digits}f}×"


def table(dataset, result):
    p, c, m = result["parallax"], result["colmap"], result["mapping_only"]
    lines = [f"### {dataset}", "",
             "| | Parallax | COLMAP 3.8 | COLMAP / Parallax |", "|---|---:|---:|---:|"]

    def row(label, key, digits=2, better_low=True, show_ratio=True):
        pv, cv = p.get(key), c.get(key)
        lines.append(f"| {label} | {fmt(pv, digits)} | {fmt(cv, digits)} | "
                     f"{ratio(cv, pv) if show_ratio else ''} |")

    row("features (s)", "features_s")
    row("matching + verification (s)", "matching_s")
    row("mapping (s)", "mapping_s")
    row("**total wall (s)**", "total_s")
    row("CPU time, all threads (s)", "cpu_s")
    row("peak memory (MiB)", "peak_rss_mib", 0)
    lines.append(f"| registered images | {fmt(p.get('images_registered'))} / {fmt(p.get('images_total'))} "
                 f"| {fmt(c.get('images_registered'))} / {fmt(c.get('images_total'))} | |")
    row("3D points", "points3D", 0, show_ratio=False)
    row("observations", "observations", 0, show_ratio=False)
    row("mean track length", "mean_track_length", 2, show_ratio=False)
    row("mean reprojection error (px)", "mean_reprojection_error_px", 3, show_ratio=False)
    row("median centre error (GT units)", "center_error_median", 5, show_ratio=False)
    row("median rotation error (deg)", "rotation_error_deg_median", 3, show_ratio=False)
    if m:
        model = m.get("parallax_model") or {}
        lines.append(f"| mapping alone on COLMAP's database (s) | {fmt(m.get('parallax_s'))} "
                     f"| {fmt(m.get('colmap_s'))} | {ratio(m.get('colmap_s'), m.get('parallax_s'))} |")
        lines.append(f"| — its registered images / points / mean track length / median centre error | "
                     f"{fmt(model.get('images_registered'))} / {fmt(model.get('points3D'))} / "
                     f"{fmt(model.get('mean_track_length'))} / "
                     f"{fmt(model.get('center_error_median'), 5)} | "
                     f"{fmt(c.get('images_registered'))} / {fmt(c.get('points3D'))} / "
                     f"{fmt(c.get('mean_track_length'))} / "
                     f"{fmt(c.get('center_error_median'), 5)} | |")
    if "verification_thread_s" in p:
        lines.append("")
        lines.append(f"Parallax thread time: descriptor matching {p['matching_thread_s']:.2f} s, "
                     f"geometric verification {p['verification_thread_s']:.2f} s; "
                     f"{fmt(p.get('pairs_verified'))} verified pairs.")
    return "\n".join(lines)


def main():
    out, datasets = sys.argv[1], sys.argv[2:]
    results = {dataset: summarize(os.path.join(out, dataset)) for dataset in datasets}
    with open(os.path.join(out, "results.json"), "w") as file:
        json.dump(results, file, indent=2, sort_keys=True)
    print("\n\n".join(table(dataset, results[dataset]) for dataset in datasets))
    print(f"\n(JSON: {os.path.join(out, 'results.json')})")


if __name__ == "__main__":
    main()
