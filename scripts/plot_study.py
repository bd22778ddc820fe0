#!/usr/bin/python3
"""Draws one seed parameter study (drivetrain_cli study) from its CSV: a surface for the bearing
stiffness studies (seed 000 Figs 4, 5), curves for the resonance and RMS studies (Figs 9-11).

usage: plot_study.py STUDY.csv STUDY.png   (the study name is the CSV's file stem)
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

TITLES = {
    "bearing_shrink": "Bearing radial stiffness vs shrink range (seed 000 Fig 4)",
    "bearing_preload": "Bearing radial stiffness vs preload (seed 000 Fig 5)",
    "rms_sweep": "RMS response over the torque sweep (seed 000 Fig 9)",
    "resonance_shrink": "Natural frequencies vs outer-ring shrink range (seed 000 Fig 10)",
    "resonance_preload": "Natural frequencies vs radial preload (seed 000 Fig 11)",
}
SCALE = {"_m": (1e3, "mm"), "_N": (1.0, "N"), "_hz": (1.0, "Hz")}
DOMINANT = ["x_p", "x_g", "x"]


def label(column):
    for suffix, (factor, unit) in SCALE.items():
        if column.endswith(suffix):
            return column[: -len(suffix)].replace("_", " ") + f" [{unit}]", factor
    return column.replace("_", " "), 1.0


def main(csv_path, png_path):
    name = os.path.splitext(os.path.basename(csv_path))[0]
    with open(csv_path) as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    fig = plt.figure(figsize=(7, 5))
    if name.startswith("bearing_"):
        xs, ys = np.unique(data[:, 0]), np.unique(data[:, 1])
        z = data[:, 2].reshape(len(xs), len(ys)).T * 1e-6  # N/m -> N/um for the colour bar
        xl, xf = label(header[0])
        yl, yf = label(header[1])
        ax = fig.add_subplot(projection="3d")
        X, Y = np.meshgrid(xs * xf, ys * yf)
        ax.plot_surface(X, Y, z, cmap="viridis")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_zlabel("radial stiffness [N/um]")
    elif name == "rms_sweep":
        ax = fig.add_subplot()
        for c in range(1, 4):
            ax.semilogy(data[:, 0], data[:, c] * 1e6, label=header[c].replace("rms_", "").replace("_m", ""))
        ax.set_xlabel("torque fluctuation frequency [Hz]")
        ax.set_ylabel("RMS [um]")
        ax.legend()
        ax.grid(True, which="both", alpha=0.3)
    else:
        # Two panels: the mesh mode sits an order of magnitude above the bearing modes.
        top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [1, 2]})
        xl, xf = label(header[0])
        for k in range(3):
            f = data[:, header.index(f"f{k + 1}_hz")] * 1e-3
            dom = data[:, header.index(f"f{k + 1}_dominant")].astype(int)
            names = sorted({DOMINANT[d] for d in dom})
            ax = top if "x" in names else bottom
            ax.plot(data[:, 0] * xf, f, marker="o", ms=3, label=f"mode {k + 1} (dominant {'/'.join(names)})")
        for ax in (top, bottom):
            ax.set_ylabel("natural frequency [kHz]")
            ax.legend()
            ax.grid(True, alpha=0.3)
        bottom.set_xlabel(xl)
    fig.suptitle(TITLES.get(name, name))
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
