#!/usr/bin/env bash
# A 20 s run-up 0 -> 6000 rpm (drivetrain_rig_sim --scenario run_up: encoders at 1 kHz) replayed
# with the TE at 10 kHz and a report; the TE's spectrum peaks follow z_p n / 60 within 1 % at each
# speed:
#  1. Campbell: in every 0.1 s window above 300 rpm the strongest line of the predicted TE is the
#     mesh frequency z_p n / 60 (z_p = 20, n the encoders' mean speed in the window) within 1 %;
#  2. order spectrum (the TE resampled on the pinion angle): the strongest order is 20, the mesh;
#  3. the report has campbell.png and te_order_spectrum.png, and, from the run-up's accelerometers
#     (the modal stage's CSV files), stabilisation.png, with no note that a modal plot is left out;
#     every identified mode of the run-up lies within 0.3 % and 3.5 std of a true transverse mode
#     (drivetrain_cli modes: 7884 and 9377 Hz) while the mesh orders cross them;
#  4. the Campbell diagram's mesh-order amplitudes (regression on the mesh phase) are alias-free: on
#     a synthetic TE of known amplitudes at mesh orders 1-6 (up to 12 kHz) sampled at 1 kHz during a
#     0 -> 6000 rpm run-up, every fitted window returns the known amplitudes within 1e-6, and at
#     least 95 % of the windows are fitted;
#  5. so has the report of a 5 s run-up whose encoders are named otherwise (joints motor and output
#     on /encoders, ~pinion_joint and ~gear_joint to match): the plots read the topic, the joint
#     and the tooth count the replay took (summary.json "encoders"), not the defaults. That one runs
#     at the default 1 kHz output, below the mesh frequency above 1500 rpm: the diagram has no
#     folded lines to note;
#  6. with synthetic modal_identification.csv and modal_poles.csv (write_modal_csv.py) beside that
#     replay's CSV files, plot_replay.py draws the stabilisation diagram and the Campbell diagram
#     with the poles, and report.md holds the identification's table.
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
md = open(work + "/report/report.md").read()
import os
if not os.path.getsize(work + "/report/stabilisation.png") or "No stabilisation diagram" in md \
        or "No identified poles" in md:
    sys.exit("check_run_up_spectrum: the run-up's report leaves out the modal plots")
true_modes = (7884.4, 9377.2)  # drivetrain_cli modes --config seed_servo.yaml (mesh_mean)
with open(work + "/report/csv/modal_identification.csv") as f:
    modal = [r for r in csv.DictReader(f) if r["status"] in ("identified", "unmatched")]
def off(r):  # (relative error, error in std) against the nearest true mode
    f = float(r["frequency"])
    m = min(true_modes, key=lambda m: abs(f - m))
    return abs(f - m) / m, abs(f - m) / float(r["frequency_std"])
worst = max(off(r)[0] for r in modal)
worst_std = max(off(r)[1] for r in modal)
print("run-up modes: %d identified, worst %.2e off a true mode, %.2f std" % (len(modal), worst, worst_std))
# A 4 s record's std is about 0.1 %: within 0.3 % and 3.5 of its own std.
if len(modal) < 8 or worst > 3e-3 or worst_std > 3.5:
    sys.exit("check_run_up_spectrum: a run-up pole off the true modes")
# Known mesh orders, sampled at 1 kHz while the mesh frequency runs 0 -> 2 kHz.
ts = np.arange(0.0, 20.0, 1e-3)
phase = np.cumsum(2000.0 * ts / 20.0) * 1e-3
known = np.array([40.0, 15.0, 5.0, 12.0, 3.0, 1.0]) * 1e-9
signal = sum(a * np.cos(2 * np.pi * (k + 1) * phase + 0.3 * k) for k, a in enumerate(known))
_, amp = ma.mesh_order_amplitudes(ts, signal, phase % 1.0, max_order=6)
fitted = np.isfinite(amp).all(axis=1)
worst = np.max(np.abs(amp[fitted] - known) / known)
print("mesh-order amplitudes at 1 kHz up to 12 kHz: %d of %d windows fitted, worst relative error %.1e"
      % (fitted.sum(), len(fitted), worst))
if fitted.sum() < 0.95 * len(fitted) or worst > 1e-6:
    sys.exit("check_run_up_spectrum: the mesh-order amplitudes are not those of the signal")
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
for d in ("report", "report_named"):
    if "**Aliasing:**" in open(os.path.join(work, d, "report.md")).read():
        sys.exit("check_run_up_spectrum: %s/report.md notes folded lines" % d)
print("named encoders: %d readings, campbell.png and te_order_spectrum.png written" % s["counters"]["accepted_joint_states"])
PY
mkdir -p "$work/report_modal/csv"
cp "$work/report_named/summary.json" "$work/report_modal/"
/usr/bin/python3 "$src/test/replay/write_modal_csv.py" "$work/report_modal/csv" \
  "$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["start"])' "$work/summary_named.json")" 5 6000
/usr/bin/python3 "$src/scripts/plot_replay.py" "$work/report_named/outputs.bag" "$work/report_modal" "$work/run_up_named.bag"
/usr/bin/python3 - "$work/report_modal" <<'PY'
import os, sys
d = sys.argv[1]
md = open(os.path.join(d, "report.md")).read()
for name in ("campbell.png", "stabilisation.png"):
    if not os.path.getsize(os.path.join(d, name)) or "(%s)" % name not in md:
        sys.exit("check_run_up_spectrum: %s missing with the modal identification's CSV files" % name)
for text in ("| 0 | identified | x_g | 7884.4", "| 2 | above Nyquist | x |", "5 identifications in all"):
    if text not in md:
        sys.exit("check_run_up_spectrum: report.md lacks '%s'" % text)
if "No stabilisation diagram" in md or "No identified poles" in md or "No accelerometer" in md:
    sys.exit("check_run_up_spectrum: report.md leaves out a modal figure with the CSV files and accelerometers")
print("modal identification: campbell.png with the poles, stabilisation.png and the table written")
PY
