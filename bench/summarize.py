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
    if result["exit_status"]:
        # A failed command's time measures nothing worth comparing.
        result["wall_s"] = None
        result["failed"] = True
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


# The COLMAPs run.sh may have run, with the names the tables give them.
COLMAPS = [("colmap38", "COLMAP 3.8"), ("colmap42", "COLMAP 4.2")]


def summarize(run):
    result = {"parallax": {}}
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

    for tool, _ in COLMAPS:
        stages = {name: read_time(os.path.join(run, f"{tool}_{name}.time"))
                  for name in ("features", "matching", "mapping")}
        if not any(stages.values()):
            continue
        colmap = result[tool] = {}
        for name, measured in stages.items():
            colmap[f"{name}_s"] = measured.get("wall_s") if measured else None
        walls = [measured.get("wall_s") for measured in stages.values() if measured]
        colmap["total_s"] = sum(walls) if len(walls) == 3 else None
        colmap["cpu_s"] = sum(measured.get("cpu_s", 0) for measured in stages.values() if measured)
        colmap["peak_rss_mib"] = max(measured.get("peak_rss_mib", 0)
                                     for measured in stages.values() if measured)
        colmap.update(model_stats(read_json(os.path.join(run, f"eval_{tool}.json"))))
        # The mapping stage alone on this COLMAP's database (the same matches for both mappers).
        mapper = read_time(os.path.join(run, f"parallax_mapper_{tool}.time")) or {}
        colmap["mapping_only"] = {
            "parallax_s": mapper.get("wall_s"),
            "parallax_failed": mapper.get("failed", False),
            "parallax_peak_rss_mib": mapper.get("peak_rss_mib"),
            "colmap_s": colmap.get("mapping_s"),
            "colmap_peak_rss_mib": (stages["mapping"] or {}).get("peak_rss_mib"),
            "parallax_model": model_stats(
                read_json(os.path.join(run, f"eval_parallax_mapper_{tool}.json"))),
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


def table(title, result):
    p = result["parallax"]
    tools = [(tool, label) for tool, label in COLMAPS if tool in result]
    header = "| | Parallax | " + " | ".join(label for _, label in tools) + " | " + \
        " | ".join(f"{label} / Parallax" for _, label in tools) + " |"
    lines = [f"### {title}", "", header, "|---|" + "---:|" * (1 + 2 * len(tools))]

    def row(label, key, digits=2, show_ratio=True):
        values = [fmt(p.get(key), digits)] + [fmt(result[tool].get(key), digits) for tool, _ in tools]
        ratios = [ratio(result[tool].get(key), p.get(key)) if show_ratio else "" for tool, _ in tools]
        lines.append(f"| {label} | " + " | ".join(values + ratios) + " |")

    row("features (s)", "features_s")
    row("matching + verification (s)", "matching_s")
    row("mapping (s)", "mapping_s")
    row("**total wall (s)**", "total_s")
    row("CPU time, all threads (s)", "cpu_s")
    row("peak memory (MiB)", "peak_rss_mib", 0)
    registered = [f"{fmt(p.get('images_registered'))} / {fmt(p.get('images_total'))}"] + [
        f"{fmt(result[tool].get('images_registered'))} / {fmt(result[tool].get('images_total'))}"
        for tool, _ in tools]
    lines.append("| registered images | " + " | ".join(registered + [""] * len(tools)) + " |")
    row("3D points", "points3D", 0, show_ratio=False)
    row("observations", "observations", 0, show_ratio=False)
    row("mean track length", "mean_track_length", 2, show_ratio=False)
    row("mean reprojection error (px)", "mean_reprojection_error_px", 3, show_ratio=False)
    row("median centre error (GT units)", "center_error_median", 5, show_ratio=False)
    row("median rotation error (deg)", "rotation_error_deg_median", 3, show_ratio=False)
    for tool, label in tools:
        m = result[tool]["mapping_only"]
        model = m.get("parallax_model") or {}
        lines.append("")
        if m.get("parallax_failed"):
            lines.append(f"Mapping alone on {label}'s database: Parallax failed "
                         f"(parallax_mapper_{tool}.log).")
            continue
        lines.append(f"Mapping alone on {label}'s database: Parallax {fmt(m.get('parallax_s'))} s, "
                     f"{label} {fmt(m.get('colmap_s'))} s ({ratio(m.get('colmap_s'), m.get('parallax_s'))}); "
                     f"Parallax's model {fmt(model.get('images_registered'))} images, "
                     f"{fmt(model.get('points3D'))} points, mean track length "
                     f"{fmt(model.get('mean_track_length'))}, median centre error "
                     f"{fmt(model.get('center_error_median'), 5)}.")
    if "verification_thread_s" in p:
        lines.append("")
        lines.append(f"Parallax thread time: descriptor matching {p['matching_thread_s']:.2f} s, "
                     f"geometric verification {p['verification_thread_s']:.2f} s; "
                     f"{fmt(p.get('pairs_verified'))} verified pairs.")
    return "\n".join(lines)


def main():
    out, datasets = sys.argv[1], sys.argv[2:]
    results = {}
    tables = []
    for dataset in datasets:
        runs = sorted(name for name in os.listdir(os.path.join(out, dataset))
                      if name.startswith("run-"))
        results[dataset] = {run: summarize(os.path.join(out, dataset, run)) for run in runs}
        tables += [table(f"{dataset}, {run}", results[dataset][run]) for run in runs]
    with open(os.path.join(out, "results.json"), "w") as file:
        json.dump(results, file, indent=2, sort_keys=True)
    print("\n\n".join(tables))
    print(f"\n(JSON: {os.path.join(out, 'results.json')})")


if __name__ == "__main__":
    main()
