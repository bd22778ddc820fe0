#!/usr/bin/python3
"""Writes a synthetic modal_identification.csv and modal_poles.csv (the formats of the replay's modal
identification stage, docs/vibration.md) for a run-up 0 -> TOP_RPM over DURATION s from EPOCH, so
that the report's modal figures can be drawn without the stage: five identifications, one per fifth
of the run,
the seed gearbox's modes (7,883 Hz, x_g; 9,375 Hz, x_p; the torsional one at 61 kHz above the
Nyquist frequency of 51.2 kHz), the third record with the pinion mode not identified and a mode
matched to no model mode; the poles of model orders 2-40: the modes stable from order 4, spurious
poles, and the mesh orders' poles inside their removed bands. The values are made up for the
figures, not a model's output; fixed seed.

usage: write_modal_csv.py CSV_DIR EPOCH DURATION TOP_RPM"""
import math
import os
import random
import sys

IDENT_HEADER = ("stamp,record_start,record_duration,sample_rate,torque,pinion_speed,status,mode,model_mode,dominant,"
                "predicted_frequency,predicted_low,predicted_high,frequency,frequency_std,damping,damping_std,mac,"
                "orders,unresolved")
POLES_HEADER = "stamp,order,frequency,damping,frequency_std,damping_std,stable,mode,order_band"
RATE, Z_P = 51200.0, 20
# (predicted, low, high, dominant, identified) per model mode: the seed gearbox's resonance.csv bands.
MODEL = ((7884.4, 5576.6, 10192.2, "x_g", 7883.0), (9377.2, 6633.2, 12121.1, "x_p", 9375.0),
         (61257.8, 50055.4, 72460.3, "x", None))


def cells(values):
    return ",".join("" if v is None else (v if isinstance(v, str) else repr(float(v)) if isinstance(v, float) else str(v))
                    for v in values)


def main():
    out, epoch, duration, top_rpm = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
    rng = random.Random(7)
    os.makedirs(out, exist_ok=True)
    ident, poles = [IDENT_HEADER], [POLES_HEADER]
    record = duration / 5
    for i in range(5):
        start = epoch + i * record
        stamp = start + record
        omega = top_rpm * (i + 0.5) * record / duration * 2 * math.pi / 60.0
        f_mesh = Z_P * omega / (2 * math.pi)
        head = ["%.9f" % stamp, "%.9f" % start, record, RATE, 0.1, omega]
        modes = []  # (frequency, std, damping, damping std) of the identified modes, by index
        for m, (pred, lo, hi, dom, f) in enumerate(MODEL):
            if f is None:
                ident.append(cells(head + ["above Nyquist", -1, m, dom, pred, lo, hi] + [None] * 7))
            elif i == 2 and m == 1:
                ident.append(cells(head + ["not identified", -1, m, dom, pred, lo, hi] + [None] * 7))
            else:
                found = (f + rng.gauss(0.0, 3.0), 2.5 + i, 0.0198 + rng.gauss(0.0, 0.001), 0.002)
                ident.append(cells(head + ["identified", len(modes), m, dom, pred, lo, hi] + list(found)
                                   + [0.995, 17, 0]))
                modes.append(found)
        if i == 2:
            found = (12480.0, 40.0, 0.05, 0.01)
            ident.append(cells(head + ["unmatched", len(modes), -1, "", None, None, None] + list(found) + [None, 6, 0]))
            modes.append(found)
        for order in range(2, 41, 2):
            for j, (f, std, z, zstd) in enumerate(modes):
                if order >= 4 or j < 2:
                    poles.append(cells(["%.9f" % stamp, order, f + rng.gauss(0.0, std), z, std, zstd,
                                        int(order >= 4), j, 0]))
            for _ in range(order // 4):
                poles.append(cells(["%.9f" % stamp, order, rng.uniform(50.0, RATE / 2), rng.uniform(0.001, 0.15),
                                    rng.uniform(5.0, 200.0), 0.02, 0, -1, 0]))
            for k in range(1, 4):
                if order >= 6 and k * f_mesh < RATE / 2:
                    poles.append(cells(["%.9f" % stamp, order, k * f_mesh * (1 + rng.gauss(0.0, 0.002)), 1e-4,
                                        1.0, 1e-4, 1, -1, 1]))
    with open(os.path.join(out, "modal_identification.csv"), "w") as f:
        f.write("\n".join(ident) + "\n")
    with open(os.path.join(out, "modal_poles.csv"), "w") as f:
        f.write("\n".join(poles) + "\n")


if __name__ == "__main__":
    main()
