#!/usr/bin/env python3
"""Draws the error-versus-time curves written by bench/error-vs-time.sh.

    python3 bench/plot-error-vs-time.py docs/error-vs-time.csv docs/error-vs-time.png

One panel per scene, log-log: relative MSE (the reference's own noise taken
out, see the script) against wall time, one line per integrator. The photon
mapper's default settings are marked with a star.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {"path": ("tab:blue", "o"), "photon": ("tab:orange", "s"), "sppm": ("tab:green", "^")}


def main(csv_path, png_path):
    rows = list(csv.DictReader(open(csv_path)))
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(5 * len(scenes), 4.2), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        for integrator, (colour, marker) in STYLE.items():
            pts = [r for r in rows if r["scene"] == scene and r["integrator"] == integrator]
            default = [r for r in pts if r["budget"] == "default"]
            pts = sorted((r for r in pts if r["budget"] != "default"), key=lambda r: float(r["seconds"]))
            # Errors at or below zero (the reference's noise estimate exceeded the
            # error) cannot be drawn on a log scale.
            pts = [r for r in pts if float(r["rel_mse"]) > 0]
            if pts:
                ax.plot(
                    [float(r["seconds"]) for r in pts],
                    [float(r["rel_mse"]) for r in pts],
                    color=colour,
                    marker=marker,
                    label=integrator,
                )
            for r in default:
                if float(r["rel_mse"]) > 0:
                    ax.plot(float(r["seconds"]), float(r["rel_mse"]), color=colour, marker="*", markersize=14,
                            linestyle="none", label=f"{integrator} (default)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(scene)
        ax.set_xlabel("wall time (s)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0][0].set_ylabel("relative MSE vs path-traced reference")
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
