#!/usr/bin/env bash
# The bags under test/data/ are what drivetrain_rig_sim writes for their documented scenarios
# (docs/tools.md, "drivetrain_rig_sim"): regenerate each and compare byte for byte. They predate the
# encoders, so they are regenerated without joint_states (--joint-rate 0): this also shows that the
# encoder readings left the torque and preload messages exactly as they were. Likewise without the
# accelerometers (--vibration-rate 0).
# usage: check_scenario_bags.sh BIN_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
bin=$1 src=$2 work=$3
mkdir -p "$work"
for s in torque_ripple torque_steps preload_ramp faults; do
  "$bin/drivetrain_rig_sim" --scenario "$s" --config "$src/config/gearboxes/seed_servo.yaml" --duration 2 --joint-rate 0 --vibration-rate 0 --out "$work/$s.bag" > /dev/null
  cmp "$work/$s.bag" "$src/test/data/$s.bag"
  echo "$s.bag: identical"
done
