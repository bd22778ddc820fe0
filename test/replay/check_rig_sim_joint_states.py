#!/usr/bin/python3
"""drivetrain_rig_sim's encoder options end to end, read back by Python's rosbag (which builds the
message class from the bag's own definition of sensor_msgs/JointState):
 1. --scenario reverse --duration 1 --joint-rate 500 --no-velocity --joint-topic /rig/joint_states
    --pinion-joint motor --gear-joint output: 500 JointState messages on /rig/joint_states named
    [motor, output], no velocity, no effort, empty frame_id, header.seq from 0, stamps = record
    times = epoch + k / 500; positions exact multiples of 2 pi / 2^20 within half a count of the
    reversal's closed form theta = s T sin(2 pi t / T) / (2 pi), s = 1000 rpm = 104.72 rad/s, and
    the gear within half a count of -(20 / 40) theta (seed_servo.yaml's teeth);
 2. --scenario run_up --duration 0.5 (defaults): 500 messages on /joint_states named [pinion, gear]
    with velocity [omega, -omega / 2], omega = 628.3185 rad/s (6000 rpm) t / T;
 3. --joint-rate 0: no joint_states at all.
usage: check_rig_sim_joint_states.py BIN_DIR SOURCE_DIR WORK_DIR"""
import json
import math
import os
import subprocess
import sys

import rosbag

bin_dir, src, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
config = os.path.join(src, "config", "gearboxes", "seed_servo.yaml")
COUNT = 2 * math.pi / 2 ** 20  # one encoder count [rad]
EPOCH = 1767225600  # drivetrain_rig_sim's default --epoch [s]
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)


def rig_sim(name, *args):
    bag = os.path.join(work, name + ".bag")
    out = subprocess.run([os.path.join(bin_dir, "drivetrain_rig_sim"), "--config", config, "--out", bag] + list(args),
                         check=True, capture_output=True, text=True).stdout
    return bag, json.loads(out)


def on_grid(x):
    return abs(x / COUNT - round(x / COUNT)) < 1e-6


# 1. The reversal with every encoder option.
bag, summary = rig_sim("reverse", "--scenario", "reverse", "--duration", "1", "--joint-rate", "500", "--no-velocity",
                       "--joint-topic", "/rig/joint_states", "--pinion-joint", "motor", "--gear-joint", "output")
check(summary["joint_states"] == 500 and summary["torque"] == 1000, "counts %s" % summary)
T, s = 1.0, 1000 * 2 * math.pi / 60
with rosbag.Bag(bag) as b:
    info = b.get_type_and_topic_info()
    check(info.topics["/rig/joint_states"].msg_type == "sensor_msgs/JointState", "type %s" % str(info.topics))
    check("/joint_states" not in info.topics, "/joint_states written despite --joint-topic")
    for k, (topic, m, record) in enumerate(b.read_messages(topics=["/rig/joint_states"])):
        t = k / 500.0
        theta = s * T * math.sin(2 * math.pi * t / T) / (2 * math.pi)
        ok = (list(m.name) == ["motor", "output"] and len(m.position) == 2 and len(m.velocity) == 0
              and len(m.effort) == 0 and m.header.frame_id == "" and m.header.seq == k
              and m.header.stamp == record and abs(m.header.stamp.to_sec() - (EPOCH + t)) < 1e-6
              and all(on_grid(p) for p in m.position) and abs(m.position[0] - theta) <= COUNT / 2 + 1e-12
              and abs(m.position[1] + 0.5 * theta) <= COUNT / 2 + 1e-12)
        if not ok:
            failures.append("reverse message %d: %s" % (k, m))
            break
    check(k == 499, "reverse: %d messages" % (k + 1))

# 2. The run-up with the defaults: /joint_states, [pinion, gear], velocities.
bag, summary = rig_sim("run_up", "--scenario", "run_up", "--duration", "0.5")
T, s1 = 0.5, 6000 * 2 * math.pi / 60  # 628.3185 rad/s
with rosbag.Bag(bag) as b:
    msgs = [m for _, m, _ in b.read_messages(topics=["/joint_states"])]
check(len(msgs) == 500, "run_up: %d messages" % len(msgs))
for k, m in enumerate(msgs):
    t = k / 1000.0
    if not (list(m.name) == ["pinion", "gear"] and len(m.velocity) == 2 and abs(m.velocity[0] - s1 * t / T) < 1e-9
            and m.velocity[1] == -0.5 * m.velocity[0] and abs(m.position[0] - s1 * t * t / (2 * T)) <= COUNT / 2 + 1e-12):
        failures.append("run_up message %d: %s" % (k, m))
        break

# 3. None at all.
bag, summary = rig_sim("none", "--scenario", "run_up", "--duration", "0.5", "--joint-rate", "0",
                       "--vibration-rate", "0")
with rosbag.Bag(bag) as b:
    check(sorted(b.get_type_and_topic_info().topics) == ["/preload", "/torque"], "--joint-rate 0 wrote joint_states")

if failures:
    sys.exit("check_rig_sim_joint_states: " + "; ".join(failures))
print("check_rig_sim_joint_states: joint_states as documented (topic, names, positions, velocity or none)")
