#!/usr/bin/env bash
# A 20 s run-up 0 -> 6000 rpm (drivetrain_rig_sim --scenario run_up: encoders at 1 kHz) replayed
# with the TE at 10 kHz and a report; the TE's spectrum peaks follow z_p n / 60 within 1 % at each
# speed:
#  1. Campbell: in every 0.1 s window above 300 rpm the strongest line of the predicted TE is the
#     mesh frequency z_p n / 60 (z_p = 20, n the encoders' mean speed in the window) within 1 %;
#  2. order spectrum (the TE resampled on the pinion angle): the strongest order is 20, the mesh;
#  3. the report has campbell.png and te_order_spectrum.png;
#  4. so has the report of a 5 s run-up whose encoders are named otherwise (joints motor and output
#     on /encoders, ~pinion_joint and ~gear_joint to match): the plots read the topic, the joint
#     and the tooth count the replay took (summary.json "encoders"), not the defaults. That one runs
#     at the default 1 kHz output, whose Nyquist frequency the mesh itself passes at 1500 rpm: its
#     report.md names mesh order 1 among the folded lines; at 10 kHz only orders 3 and 4 fold
#     (above 5000 and 3750 rpm), and the note says so without order 1 or 2.
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
sed -e 's/^pinion_joint: .*/pinion_joint: motor/' -e 's/^gear_joint: .*/gear_joint: output/' "$src/config/stiffness_estimator.yaml" \
  > "$work/params_named.yaml"
"$bin/drivetrain_rig_sim" --scenario run_up --config "$src/config/gearboxes/seed_servo.yaml" --duration 5 \
  --pinion-joint motor --gear-joint output --joint-topic /encoders --out "$work/run_up_named.bag" > /dev/null
"$bin/drivetrain_replay" --bag "$work/run_up_named.bag" --config "$src/config/gearboxes/seed_servo.yaml" \
  --params "$work/params_named.yaml" --joint-states-topic encoders --report "$work/report_named" \
  --plot-script "$src/scripts/plot_replay.py" > "$work/summary_named.json"
/usr/bin/python3 - "$work" <<'PY'
import json, os, sys
work = sys.argv[1]
s = json.load(open(work + "/summary_named.json"))
enc = s["encoders"]
want = {"topic": "encoders", "pinion_joint": "motor", "gear_joint": "output", "pinion_teeth": 20, "gear_teeth": 40}
if enc != want:
    sys.exit("check_run_up_spectrum: summary encoders %s, expected %s" % (enc, want))
if s["counters"]["accepted_joint_states"] < 4000:
    sys.exit("check_run_up_spectrum: the named encoders were not taken (%d readings)" % s["counters"]["accepted_joint_states"])
for name in ("campbell.png", "te_order_spectrum.png"):
    if not os.path.getsize(os.path.join(work, "report_named", name)):
        sys.exit("check_run_up_spectrum: %s missing with named encoders" % name)
note = lambda d: [l for l in open(os.path.join(work, d, "report.md")).read().splitlines() if l.startswith("**Aliasing:**")]
slow, fast = note("report_named"), note("report")
if not slow or "mesh order 1 above 1500 rpm" not in slow[0]:
    sys.exit("check_run_up_spectrum: the 1 kHz report should name mesh order 1 folding above 1500 rpm: %s" % slow)
if not fast or "mesh order 4 above 3750 rpm" not in fast[0] or "mesh order 2" in fast[0] or "mesh order 1" in fast[0]:
    sys.exit("check_run_up_spectrum: the 10 kHz report should name orders 4 and 3 only: %s" % fast)
print("named encoders: %d readings, campbell.png and te_order_spectrum.png written; 1 kHz output: aliasing noted"
      % s["counters"]["accepted_joint_states"])
PY
