#!/usr/bin/python3
"""Plots drivetrain_bench's JSON lines: one PNG per scene, relative RMS error of the mesh deflection
against real-time factor, one marker series per method (ours and the peers)."""
import json
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(jsonl, out_dir):
    rows = [json.loads(line) for line in open(jsonl) if line.strip()]
    by_scene = defaultdict(list)
    for r in rows:
        by_scene[r["scene"]].append(r)
    for scene, runs in by_scene.items():
        fig, ax = plt.subplots(figsize=(7, 4.5))
        by_method = defaultdict(list)
        for r in runs:
            if r.get("err_rms_rel") is not None and r.get("rtf") and r["err_rms_rel"] > 0:
                by_method[r["method"]].append((r["rtf"], r["err_rms_rel"]))
        for method, pts in sorted(by_method.items()):
            pts.sort()
            peer = method.startswith(("odeint", "cvode"))
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o--" if peer else "s-", label=method)
        ax.set_xlabel("real-time factor (simulated s / wall s)")
        ax.set_ylabel("RMS error of delta / RMS of delta")
        ax.set_title(f"drivetrain_bench: {scene}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(f"{out_dir}/bench_{scene}.png", dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
