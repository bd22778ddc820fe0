#!/usr/bin/python3
"""drivetrain_rig_sim --scenario load_sweep end to end (docs/tools.md), on the perturbed rig
test/data/perturbed_servo.yaml, every hold scaled so that the sweep lasts 2 s (--duration 2):
 1. the same --seed twice gives the same bag byte for byte; another seed another bag;
 2. the summary's truth is the rig's (mesh scale 0.8, supports 0.7 and 1.3, T_p 1.2 N*m), with a
    knee above zero, a reverse knee below, 19 holds (0, 10 up, 0, 6 down, 0) ending at 2 s, both
    encoders' mounting errors in 10-20 arcsec;
 3. the bag, read back by Python's rosbag: 10000 joint_states (5000 Hz default for load_sweep),
    2000 torque messages (1000 Hz), one preload; joint_states stamps within 20 us of their record
    times and not all on them (the jitter), torque stamps on theirs; published torque within 6
    sigma (0.005 |T| + 1e-3 N*m) of the hold's true torque;
 4. --seed with another scenario is refused, naming the option.
usage: check_rig_sim_load_sweep.py BIN_DIR SOURCE_DIR WORK_DIR"""
import filecmp
import json
import os
import subprocess
import sys

import rosbag

bin_dir, src, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
config = os.path.join(src, "test", "data", "perturbed_servo.yaml")
rig_sim_bin = os.path.join(bin_dir, "drivetrain_rig_sim")
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)


def rig_sim(name, *args):
    bag = os.path.join(work, name + ".bag")
    out = subprocess.run([rig_sim_bin, "--scenario", "load_sweep", "--config", config, "--out", bag, "--duration", "2"]
                         + list(args), check=True, capture_output=True, text=True).stdout
    return bag, json.loads(out)


a, summary = rig_sim("a", "--seed", "3")
b, _ = rig_sim("b", "--seed", "3")
c, _ = rig_sim("c", "--seed", "4")
check(filecmp.cmp(a, b, shallow=False), "--seed 3 twice: the bags differ")
check(not filecmp.cmp(a, c, shallow=False), "--seed 3 and --seed 4: the same bag")

truth = summary["truth"]
for key, value in (("mesh_stiffness_scale", 0.8), ("pinion_bearing_scale", 0.7), ("gear_bearing_scale", 1.3),
                   ("preload_torque", 1.2), ("seed", 3), ("speed_rpm", 120.0), ("joint_rate", 5000.0),
                   ("duration", 2.0)):
    check(truth[key] == value, f"truth {key} = {truth[key]}, expected {value}")
check(truth["knee_torque"] > 0.0 > truth["reverse_knee_torque"], f"knees {truth['knee_torque']}, {truth['reverse_knee_torque']}")
levels = truth["levels"]
check(len(levels) == 19 and levels[-1]["t1"] == 2.0, f"{len(levels)} holds ending at {levels[-1]['t1']}")
check(all(10.0 <= e <= 20.0 for e in truth["eccentricity_arcsec"]), f"eccentricity {truth['eccentricity_arcsec']} arcsec")
check((summary["joint_states"], summary["torque"], summary["preload"]) == (10000, 2000, 1),
      f"messages {summary['joint_states']}, {summary['torque']}, {summary['preload']}")


def true_torque(t):
    for level in levels:
        if level["t0"] <= t < level["t1"]:
            return level["torque"]
    return levels[-1]["torque"]


counts = {}
jittered = 0
with rosbag.Bag(a) as bag:
    for topic, msg, t in bag.read_messages():
        counts[topic] = counts.get(topic, 0) + 1
        offset = (msg.header.stamp - t).to_sec()
        if topic == "/joint_states":
            check(abs(offset) <= 20e-6 + 1e-9, f"joint_states stamp {offset} s off its record time")
            jittered += offset != 0.0
            check(list(msg.name) == ["pinion", "gear"] and len(msg.velocity) == 2, "joint_states names or velocity")
        elif topic == "/torque":
            check(offset == 0.0, f"torque stamp {offset} s off its record time")
            rel = (t.to_nsec() - 1767225600 * 10 ** 9) * 1e-9
            truth_t = true_torque(rel)
            sigma = 0.005 * abs(truth_t) + 1e-3
            check(abs(msg.wrench.torque.z - truth_t) <= 6.0 * sigma, f"torque {msg.wrench.torque.z} at {rel} s, true {truth_t}")
# 2 s of accelerometers at 51.2 kHz in blocks of 1024 samples: 100 (docs/vibration.md).
check(counts == {"/joint_states": 10000, "/torque": 2000, "/preload": 1, "/vibration": 100},
      f"counts {counts}")
check(jittered > 9000, f"only {jittered} of 10000 joint_states stamps jittered")

refused = subprocess.run([rig_sim_bin, "--scenario", "torque_steps", "--config", config, "--out",
                          os.path.join(work, "refused.bag"), "--seed", "3"], capture_output=True, text=True)
check(refused.returncode != 0 and "--seed" in refused.stderr, f"--seed with torque_steps: {refused.returncode} {refused.stderr}")

for f in failures:
    print("FAIL:", f)
print(f"{len(failures)} failed" if failures else "load_sweep bags: reproducible, truth and messages as documented")
sys.exit(1 if failures else 0)
