#!/usr/bin/env bash
# A 20 s run-up 0 -> 6000 rpm (drivetrain_rig_sim --scenario run_up: encoders at 1 kHz) replayed
# with the TE at 10 kHz and a report (issue: "a run-up bag whose TE spectrum peaks follow
# z_p n / 60 within 1 % at each speed"):
#  1. Campbell: in every 0.1 s window above 300 rpm the strongest line of the predicted TE is the
#     mesh frequency z_p n / 60 (z_p = 20, n the encoders' mean speed in the window) within 1 %;
#  2. order spectrum (the TE resampled on the pinion angle): the strongest order is 20, the mesh;
#  3. the report has campbell.png and te_order_spectrum.png.
# usage: check_run_up_spectrum.sh BIN_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
bin=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
sed 's/^output_rate: .*/output_rate: 10000.0/' "$src/config/stiffness_estimator.yaml" > "$work/params.yaml"
"$bin/drivetrain_rig_sim" --scenario run_up --config "$src/config/gearboxes/seed_servo.yaml" --duration 20 \
  --out "$work/run_up.bag" > /dev/null
"$bin/drivetrain_replay" --bag "$work/run_up.bag" --config "$src/config/gearboxes/seed_servo.yaml" \
  --params "$work/params.yaml" --report "$work/report" --plot-script "$src/scripts/plot_replay.py" > "$work/summary.json"
test -s "$work/report/campbell.png" && test -s "$work/report/te_order_spectrum.png"
/usr/bin/python3 - "$src/scripts" "$work" <<'PY'
import csv, sys
sys.path.insert(0, sys.argv[1])
import numpy as np
import motion_analysis as ma
work = sys.argv[2]
enc_t, enc_angle, enc_speed = ma.read_encoder(work + "/run_up.bag")
rows = list(csv.DictReader(open(work + "/report/csv/transmission_error.csv")))
t = np.array([float(r["stamp"]) for r in rows])
x = np.array([float(r["dynamic_te"]) for r in rows])
rpm, peak, _ = ma.campbell(t, x, enc_t, enc_speed)
sel = rpm > 300.0
err = np.abs(peak[sel] - 20.0 * rpm[sel] / 60.0) / (20.0 * rpm[sel] / 60.0)
worst = int(np.argmax(err))
print("campbell: %d windows above 300 rpm, worst %.2e at %.0f rpm (peak %.1f Hz, mesh %.1f Hz), median %.1e"
      % (sel.sum(), err[worst], rpm[sel][worst], peak[sel][worst], 20.0 * rpm[sel][worst] / 60.0, np.median(err)))
orders, amp = ma.order_spectrum(t, x, enc_t, enc_angle)
top = orders[1:][np.argmax(amp[1:])]
print("order spectrum: strongest order %.3f" % top)
if sel.sum() < 300 or err.max() > 0.01 or abs(top - 20.0) > 1e-9:
    sys.exit("check_run_up_spectrum: the TE does not follow the mesh order")
PY
