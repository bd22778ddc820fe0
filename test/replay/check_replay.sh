#!/usr/bin/env bash
# drivetrain_replay on the bundled fault-injection bag (drivetrain_rig_sim --scenario faults):
#  1. twice: the output bags and every CSV file are byte-identical (the pipeline reads no clock);
#  2. the counters show each injected fault under its own rule (docs/ros_api.md, "Time and input rules"):
#     NaN, Inf and absurd torque and a negative preload -> invalid value (4); one zero stamp; one
#     stamp 0.5 s late -> out of order; five equal stamps -> accepted; the 1.2 s jump back of the
#     stamps -> one stamp reset; a torque in the gear's frame -> wrong frame; a gap of 3 in the
#     torque's header.seq -> 3 dropped; nothing else rejected, every message accounted for;
#  3. summary.json's dynamics_work (where the dynamics' time went) is the same in both runs, and on
#     preload_ramp.bag (axial preload 200 -> 2000 N in 20 steps at 0.1 N*m, 1000 rpm) it shows the
#     bearing changes moving the dynamics onto the sliced propagation: more than 10 model updates
#     (each step of the ramp moves the bearings' stiffness by more than the 1 % the dynamics follow:
#     docs/model.md), slices crossed, and no contact change nor dopri5 interval (0.1 N*m is far below
#     the anti-backlash knee, 6.95 N*m: both flanks stay loaded).
# usage: check_replay.sh BIN_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
bin=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
for run in a b; do
  "$bin/drivetrain_replay" --bag "$src/test/data/faults.bag" --config "$src/config/gearboxes/seed_servo.yaml" \
    --params "$src/config/stiffness_estimator.yaml" --out "$work/$run.bag" --csv "$work/$run" > "$work/$run.json"
done
cmp "$work/a.bag" "$work/b.bag"
for f in stiffness transmission_error te_spectrum resonance measured_te calibration mesh_period_stats; do cmp "$work/a/$f.csv" "$work/b/$f.csv"; done
/usr/bin/python3 - "$work/a.json" "$work/a/transmission_error.csv" <<'PY'
import csv, json, math, sys
d = json.load(open(sys.argv[1]))
c = d["counters"]
expected = {"rejected_invalid_value": 4, "rejected_zero_stamp": 1, "rejected_out_of_order": 1, "stamp_jump_resets": 1,
            "rejected_wrong_frame": 1, "dropped_torque": 3, "dropped_preload": 0, "rejected_stamp_range": 0,
            "stiffness_shed": 0, "rejected_torque": 6, "rejected_preload": 1, "unreachable_loads": 0,
            "dynamics_errors": 0, "clock_jump_resets": 0}
bad = {k: (c[k], v) for k, v in expected.items() if c[k] != v}
# Every message is either accepted or rejected: 2000 clean torque + 2 preload + 13 injected.
total = c["accepted_torque"] + c["rejected_torque"] + c["accepted_preload"] + c["rejected_preload"]
if total != d["messages"] or d["messages"] != 2015:
    bad["accounted"] = (total, d["messages"])
rows = list(csv.DictReader(open(sys.argv[2])))
if any(not math.isfinite(float(r["dynamic_te"])) for r in rows) or len(rows) != c["transmission_error_published"]:
    bad["te_rows"] = len(rows)
print("counters:", json.dumps(c))
if bad:
    sys.exit("unexpected (got, expected): %s" % bad)
print("check_replay: bit-identical outputs; every fault counted under its rule")
PY
"$bin/drivetrain_replay" --bag "$src/test/data/preload_ramp.bag" --config "$src/config/gearboxes/seed_servo.yaml" \
  --params "$src/config/stiffness_estimator.yaml" > "$work/ramp.json"
/usr/bin/python3 - "$work/a.json" "$work/b.json" "$work/ramp.json" <<'PY'
import json, sys
a, b, ramp = (json.load(open(f)) for f in sys.argv[1:4])
if a["dynamics_work"] != b["dynamics_work"]:
    sys.exit("dynamics_work differs between two runs: %s, %s" % (a["dynamics_work"], b["dynamics_work"]))
w = ramp["dynamics_work"]
print("preload_ramp dynamics_work:", json.dumps(w))
if not (w["model_updates"] > 10 and w["slices_crossed"] > 0 and w["contact_changes"] == 0 and w["dopri5_intervals"] == 0):
    sys.exit("preload_ramp: unexpected dynamics_work")
print("check_replay: dynamics_work deterministic and as the preload ramp implies")
PY
