#!/usr/bin/python3
"""A speed sweep through the resonances, end to end: drivetrain_rig_sim writes the speed_sweep
scenario (mesh-order torque ripple, 5 % of 0.1 N*m, chirped 5 -> 11 kHz over 0.4 s, 25 kHz
samples), drivetrain_replay runs the node's pipeline on it (transmission_error at 25 kHz), and the
RMS envelope of the gear and pinion transverse displacements x_g, x_p over 5 ms windows must peak
where the chirp crosses the node's own modal estimates: the gear mode (dominant x_g, 7.88 kHz on
the seed rig) and the pinion mode (x_p, 9.38 kHz), within 3 % (a linear chirp through a mode with
zeta 0.02 peaks slightly late; the window is 75 Hz of chirp). The peaks must also stand at least
3x above the envelope at the sweep's start, i.e. be resonances rather than ripple.
usage: check_speed_sweep.py BIN_DIR SOURCE_DIR WORK_DIR [PLOT.png]"""
import csv
import json
import math
import os
import subprocess
import sys

bin_dir, src, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
config = os.path.join(src, "config", "gearboxes", "seed_servo.yaml")
bag = os.path.join(work, "speed_sweep.bag")
duration, f0, f1 = 0.4, 5000.0, 11000.0  # rig_scenarios.cpp: the chirp runs 5 -> 11 kHz over the duration
subprocess.run([os.path.join(bin_dir, "drivetrain_rig_sim"), "--scenario", "speed_sweep", "--config", config,
                "--duration", str(duration), "--rate", "25000", "--out", bag], check=True, stdout=subprocess.DEVNULL)
params = os.path.join(work, "params.yaml")
with open(params, "w") as f:
    f.write("output_rate: 25000.0\n")
summary = json.loads(subprocess.run([os.path.join(bin_dir, "drivetrain_replay"), "--bag", bag, "--config", config,
                                     "--params", params, "--csv", os.path.join(work, "csv"), "--no-plots"],
                                    check=True, capture_output=True, text=True).stdout)
rows = list(csv.DictReader(open(os.path.join(work, "csv", "transmission_error.csv"))))
t0 = float(rows[0]["stamp"])
modes = summary["final_resonance_hz"]
print("modal estimates [Hz]:", modes)
failures = []
curves = {}
for key, mode in (("x_g", modes[0]), ("x_p", modes[1])):
    samples = [(float(r["stamp"]) - t0, float(r[key])) for r in rows]
    envelope = []
    window = 0.005
    for i in range(int(duration / window)):
        seg = [x for t, x in samples if i * window <= t < (i + 1) * window]
        mean = sum(seg) / len(seg)
        rms = math.sqrt(sum((x - mean) ** 2 for x in seg) / len(seg))
        envelope.append((f0 + (f1 - f0) * (i + 0.5) * window / duration, rms))
    curves[key] = envelope
    f_peak, peak = max(envelope, key=lambda e: e[1])
    print("%s: envelope peak %.3g m at %.0f Hz (mode %.0f Hz, %+.2f %%), %.1fx the start" %
          (key, peak, f_peak, mode, 100 * (f_peak / mode - 1), peak / envelope[0][1]))
    if abs(f_peak / mode - 1) > 0.03 or peak < 3 * envelope[0][1]:
        failures.append(key)
if len(sys.argv) > 4:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4))
    for key, envelope in curves.items():
        ax.plot([f / 1e3 for f, _ in envelope], [1e9 * r for _, r in envelope], label=key + " RMS (5 ms windows)")
    for k, (mode, label) in enumerate(((modes[0], "gear mode"), (modes[1], "pinion mode"))):
        ax.axvline(mode / 1e3, color="C%d" % k, ls="--", lw=0.8, label="%s estimate %.0f Hz" % (label, mode))
    ax.set_xlabel("chirp frequency of the torque ripple [kHz]")
    ax.set_ylabel("transverse displacement RMS [nm]")
    ax.set_title("speed_sweep bag replayed: response against the node's resonance estimates")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[4], dpi=110)
if failures:
    sys.exit("resonance not where the modal estimate is: " + ", ".join(failures))
print("check_speed_sweep: both transverse modes found where the node estimates them")
