#!/usr/bin/python3
"""Summarises drivetrain_bench JSON lines as a Markdown table: per scene and method family, the
fastest run (real-time factor) whose relative RMS error of delta is <= the bound."""
import json
import sys
from collections import defaultdict


def main(path, bound=1e-6):
    rows = [json.loads(line) for line in open(path) if line.strip()]
    best = defaultdict(dict)
    for r in rows:
        err, rtf = r.get("err_rms_rel"), r.get("rtf")
        if err is None or rtf is None or err > bound:
            continue
        key = r["method"]
        if key not in best[r["scene"]] or rtf > best[r["scene"]][key]["rtf"]:
            best[r["scene"]][key] = r
    # A column per method that ran in this file (exponential needs a constant speed, sliced_exact a
    # scene whose speed changes: a file of one kind of scene lacks the other).
    ran = {r["method"] for r in rows if r.get("rtf") is not None}
    methods = [m for m in ["exponential", "sliced_exact", "auto", "dopri5", "rk4", "trapezoidal", "odeint_dopri5",
                           "odeint_rosenbrock4", "cvode_bdf"] if m in ran]
    print(f"Fastest run with err_rms_rel <= {bound:g} (real-time factor; '-' = no setting met the bound)\n")
    print("| scene | " + " | ".join(methods) + " | best ours / best peer |")
    print("|---" * (len(methods) + 2) + "|")
    for scene in dict.fromkeys(r["scene"] for r in rows):
        cells, ours, peers = [], 0.0, 0.0
        for m in methods:
            r = best[scene].get(m)
            cells.append(f"{r['rtf']:.3g}" if r else "-")
            if r and m.startswith(("odeint", "cvode")):
                peers = max(peers, r["rtf"])
            elif r:
                ours = max(ours, r["rtf"])
        ratio = f"{ours / peers:.3g}x" if ours and peers else "-"
        print(f"| {scene} | " + " | ".join(cells) + f" | {ratio} |")


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 1e-6)
