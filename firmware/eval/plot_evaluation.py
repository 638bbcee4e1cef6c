#!/usr/bin/python3
"""Plots of `stria eval`'s CSV, after the paper's figures 8 and 9.

usage: plot_evaluation.py EVALUATION.csv OUTDIR
       plot_evaluation.py --markdown EVALUATION.csv   (the table of docs/evaluation.md)

Writes OUTDIR/eval-error.png (mean error and standard deviation of the inliers
over noise, one line per contrast: figure 8), OUTDIR/eval-inliers.png (inliers
and outliers of both decoders: figure 9) and OUTDIR/eval-time.png (decode time
per frame). Values are averaged over scenes and seeds. Each PNG is written to a
temporary file and renamed, so a reader never sees half an image.
"""
import csv
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)
import numpy as np  # noqa: E402

METHODS = (("graph", "graph (ours)", "-", "o"), ("dp", "DP baseline", "--", "s"))


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"plot_evaluation: {path} has no rows")
    for needed in ("noise", "contrast", "ideal", "graph_available", "dp_available", "dp_inliers"):
        if needed not in rows[0]:
            sys.exit(f"plot_evaluation: {path} has no column '{needed}'")
    return rows


def average(rows, method, field):
    """{contrast: (noise levels, mean of field over scenes and seeds)}; frames where
    the method is unavailable (or the value empty) are left out."""
    groups = defaultdict(list)
    for r in rows:
        if r[f"{method}_available"] != "1" or r[f"{method}_{field}"] == "":
            continue
        groups[(float(r["contrast"]), float(r["noise"]))].append(float(r[f"{method}_{field}"]))
    curves = defaultdict(lambda: ([], []))
    for (contrast, noise), values in sorted(groups.items()):
        curves[contrast][0].append(noise)
        curves[contrast][1].append(float(np.mean(values)))
    return dict(curves)


def ideal_curve(rows):
    groups = defaultdict(list)
    for r in rows:
        groups[float(r["noise"])].append(float(r["ideal"]))
    noise = sorted(groups)
    return noise, [float(np.mean(groups[n])) for n in noise]


def contrast_colours(rows):
    contrasts = sorted({float(r["contrast"]) for r in rows}, reverse=True)
    cmap = plt.get_cmap("viridis")
    return {c: cmap(i / max(1, len(contrasts) - 1) * 0.9) for i, c in enumerate(contrasts)}


def panel(ax, rows, field, colours, methods, title, ylabel):
    for method, label, style, marker in methods:
        for contrast, (noise, values) in sorted(average(rows, method, field).items(), reverse=True):
            ax.plot(noise, values, style, marker=marker, color=colours[contrast], label=f"{label}, contrast {contrast:g}")
    ax.set_title(title)
    ax.set_xlabel("noise sigma (8-bit digits)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)


def available_methods(rows):
    return [m for m in METHODS if any(r[f"{m[0]}_available"] == "1" for r in rows)]


def save(fig, outdir, name):
    path = os.path.join(outdir, name)
    tmp = os.path.join(outdir, f".{name}.tmp")
    fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    os.replace(tmp, path)


def subtitle(rows, methods):
    scenes = sorted({f"{r['scene']} ({r['albedo']})" for r in rows})
    seeds = len({r["seed"] for r in rows})
    text = f"scenes: {', '.join(scenes)}; {seeds} seed(s) each"
    if not any(m[0] == "graph" for m in methods):
        text += "; graph decoder unavailable in this run"
    return text


def cell(rows, method, field, fmt):
    values = [float(r[f"{method}_{field}"]) for r in rows
              if r[f"{method}_available"] == "1" and r[f"{method}_{field}"] != ""]
    return fmt.format(np.mean(values)) if values else "n/a"


def markdown(rows):
    """One line per noise x contrast, averaged over scenes and seeds."""
    print("| noise | contrast | ideal | graph inliers | graph outliers | graph mean / sd (mm) | graph ms "
          "| DP inliers | DP outliers | DP mean / sd (mm) | DP ms |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    keys = sorted({(float(r["noise"]), float(r["contrast"])) for r in rows}, key=lambda k: (-k[1], k[0]))
    for noise, contrast in keys:
        group = [r for r in rows if float(r["noise"]) == noise and float(r["contrast"]) == contrast]
        line = [f"{noise:g}", f"{contrast:g}", f"{np.mean([float(r['ideal']) for r in group]):.0f}"]
        for method in ("graph", "dp"):
            line += [cell(group, method, "inliers", "{:.0f}"), cell(group, method, "outliers", "{:.0f}"),
                     cell(group, method, "mean_error_mm", "{:+.2f}") + " / " + cell(group, method, "std_dev_mm", "{:.2f}"),
                     cell(group, method, "decode_ms", "{:.0f}")]
        print("| " + " | ".join(line) + " |")


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--markdown":
        markdown(load(sys.argv[2]))
        return
    if len(sys.argv) != 3:
        sys.exit("usage: plot_evaluation.py EVALUATION.csv OUTDIR | --markdown EVALUATION.csv")
    rows = load(sys.argv[1])
    outdir = sys.argv[2]
    methods = available_methods(rows)
    colours = contrast_colours(rows)
    note = subtitle(rows, methods)

    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    panel(axes[0], rows, "mean_error_mm", colours, methods, "(a) mean error of the inliers", "mean error (mm)")
    panel(axes[1], rows, "std_dev_mm", colours, methods, "(b) standard deviation of the inliers", "std dev (mm)")
    axes[1].legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Measurement error over noise and contrast\n{note}", fontsize=10)
    fig.tight_layout()
    save(fig, outdir, "eval-error.png")

    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    panel(axes[0], rows, "inliers", colours, methods, "(a) inliers (error <= 1% of distance)", "points per frame")
    noise, ideal = ideal_curve(rows)
    axes[0].plot(noise, ideal, ":", color="grey", label="ideal (edge crossings)")
    axes[0].set_ylim(bottom=0)
    axes[0].legend(fontsize=7, loc="lower left")
    panel(axes[1], rows, "outliers", colours, methods, "(b) outliers", "points per frame")
    axes[1].set_yscale("symlog", linthresh=10)
    fig.suptitle(f"Inliers and outliers of both decoders\n{note}", fontsize=10)
    fig.tight_layout()
    save(fig, outdir, "eval-inliers.png")

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for method, label, style, marker in methods:
        times = [float(r[f"{method}_decode_ms"]) for r in rows if r[f"{method}_available"] == "1"]
        noise = sorted({float(r["noise"]) for r in rows if r[f"{method}_available"] == "1"})
        per_noise = [np.median([float(r[f"{method}_decode_ms"]) for r in rows
                                if r[f"{method}_available"] == "1" and float(r["noise"]) == n]) for n in noise]
        ax.plot(noise, per_noise, style, marker=marker, color="black",
                label=f"{label}: median {np.median(times):.1f} ms per frame")
    ax.set_yscale("log")
    ax.set_xlabel("noise sigma (8-bit digits)")
    ax.set_ylabel("decode time per frame (ms, log scale)")
    ax.set_title(f"Decode time, 780x580 frames, same run\n{note}", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save(fig, outdir, "eval-time.png")


if __name__ == "__main__":
    main()
