"""DIR/report.md with PNG plots: each calibrated quantity against the bag's start with its 95 %
band, the natural frequencies and the TE RMS against time, and the flagged and refused bags."""

import datetime
import math
import os

from .detector import MONITORED, finite_number as _float, usable

LABELS = {
    "mesh_stiffness_scale": "mesh stiffness scale [-]",
    "pinion_bearing_scale": "pinion bearing scale [-]",
    "gear_bearing_scale": "gear bearing scale [-]",
    "preload_torque": "anti-backlash preload torque T_p [N·m]",
}
Z95 = 1.959963984540054  # two-sided 95 % quantile of the normal distribution


def _when(stamp):
    return datetime.datetime.fromtimestamp(stamp, datetime.timezone.utc)


def _plots(out_dir, rows, references, fraction):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dated = [r for r in rows if _float(r.get("start")) is not None]
    written = []
    fig, axes = plt.subplots(len(MONITORED), 1, figsize=(9, 2.4 * len(MONITORED)), sharex=True)
    for ax, name in zip(axes, MONITORED):
        for identified in (True, False):
            t, x, s = [], [], []
            for r in dated:
                value, std = _float(r.get(name)), _float(r.get(name + "_std"))
                if value is None or std is None or (usable(r, name) is not None) != identified:
                    continue
                t.append(_when(r["start"]))
                x.append(value)
                s.append(Z95 * std)
            if t:
                ax.errorbar(t, x, yerr=s, fmt="o" if identified else "x", ms=4, capsize=2,
                            color="C0" if identified else "0.6",
                            label="estimate, 95 % band" if identified else "not identified (prior)")
        ref = references.get(name, {}).get("value")
        if ref is not None:
            ax.axhline(ref, color="k", lw=0.8, label="reference")
            ax.axhspan(ref * (1 - fraction), ref * (1 + fraction), color="C2", alpha=0.12,
                       label=f"reference ±{100 * fraction:g} %")
        for r in dated:
            if r.get("alarm"):
                ax.axvline(_when(r["start"]), color="C3", lw=0.6, alpha=0.5)
        ax.set_ylabel(LABELS[name], fontsize=8)
        ax.grid(alpha=0.3)
    for ax in axes:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="best")
    axes[-1].set_xlabel("bag start (UTC); red lines: bags with alarm")
    fig.autofmt_xdate()
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "calibration_trend.png"), dpi=110)
    plt.close(fig)
    written.append("calibration_trend.png")

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True)
    for i in range(3):
        pts = [(_when(r["start"]), _float(r.get(f"natural_frequency_{i + 1}"))) for r in dated]
        pts = [p for p in pts if p[1] is not None]
        if pts:
            ax1.plot(*zip(*pts), "o-", ms=3, label=f"mode {i + 1}")
    ax1.set_ylabel("natural frequency [Hz]")
    ax1.set_yscale("log")
    if ax1.get_legend_handles_labels()[0]:
        ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3, which="both")
    pts = [(_when(r["start"]), _float(r.get("te_rms"))) for r in dated]
    pts = [(t, 1e6 * v) for t, v in pts if v is not None]
    if pts:
        ax2.plot(*zip(*pts), "o-", ms=3, color="C1")
    ax2.set_ylabel("dynamic TE RMS [µm]\n(per mesh period, about its mean)")
    ax2.set_xlabel("bag start (UTC)")
    ax2.grid(alpha=0.3)
    fig.autofmt_xdate()
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "modes_and_te.png"), dpi=110)
    plt.close(fig)
    written.append("modes_and_te.png")
    return written


def _cell(x):
    return "" if x is None else str(x).replace("|", "\\|")


def write_report(out_dir, rows, references, options):
    fraction = options.get("fraction", 0.05)
    lines = ["# Campaign report", "",
             f"{len(rows)} bags; columns and rules in docs/campaign.md; the table is `campaign.csv`.", ""]
    lines += ["## Reference and change detector", "",
              f"Alarm when a quantity has moved by more than {100 * fraction:g} % from its reference (the "
              f"first {options.get('reference_bags', 3)} bags that identify it), CUSUM decision interval "
              f"{options.get('threshold', 5.0):g}.", "",
              "| quantity | reference | std | bags |", "|---|---|---|---|"]
    for name in MONITORED:
        ref = references.get(name, {})
        value, std = ref.get("value"), ref.get("std")
        value_text = "" if value is None else f"{value:.6g}"
        std_text = "" if std is None else f"{std:.3g}"
        lines.append(f"| {name} | {value_text} | {std_text} | {ref.get('bags', 0)} |")
    try:
        for png in _plots(out_dir, rows, references, fraction):
            lines += ["", f"![{png}]({png})"]
    except ImportError as e:  # matplotlib missing: the tables still stand
        lines += ["", f"(no plots: {e})"]
    flagged = [r for r in rows if r.get("alarm") or r.get("out_of_family") or str(r.get("status", "")).startswith(("refused", "incomplete"))
               or (_float(r.get("wrong_type")) or 0) > 0 or r.get("duplicates")]
    lines += ["", "## Flagged and refused bags", ""]
    if not flagged:
        lines.append("None.")
    else:
        lines += ["| bag | start (UTC) | status | alarm or out of family | duplicates | report |", "|---|---|---|---|---|---|"]
        for r in flagged:
            start = _float(r.get("start"))
            when = _when(start).strftime("%Y-%m-%d %H:%M:%S") if start is not None else ""
            alarm = "; ".join(x for x in (r.get("alarm_reason"), r.get("family_reason")) if x)
            report = f"[{r['report']}]({r['report']}/report.md)" if r.get("report") else ""
            lines.append(f"| {_cell(r['bag'])} | {when} | {_cell(r.get('status'))} | {_cell(alarm)} | "
                         f"{_cell(r.get('duplicates'))} | {report} |")
    with open(os.path.join(out_dir, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
