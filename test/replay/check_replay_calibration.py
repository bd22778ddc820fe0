#!/usr/bin/python3
"""The live calibration (docs/ros_api.md, the calibration rule) through drivetrain_replay, end to end:
 1. drivetrain_rig_sim --scenario torque_steps (0.05, 0.1, 0.2, -0.1, 0.1 N*m at 1000 rpm; the first
    step builds the unloaded baseline) with joint_states at 5 kHz (the second mesh harmonic needs
    more than 1 kHz), replayed with test/data/calibration_servo.yaml (a calibration: block) and
    config/stiffness_estimator.yaml, twice: the output bags and every CSV file byte-identical, the
    calibrated gearbox identical but for its "written" line. (The kinematic rig sim has no
    transmission error: the numbers are plumbing, not a calibration.)
 2. calibration.csv, measured_te.csv and mesh_period_stats.csv: the columns are "stamp" and the
    message fields of msg/Calibration.msg, msg/MeasuredTe.msg and msg/MeshPeriodStats.msg in their
    order, one row per message counted in calibration_published, measured_te_published and
    mesh_period_stats_published (all > 0), every number finite;
 3. the bag's /calibration, /measured_te and /mesh_period_stats equal the CSV rows field by field
    (the same conversion), header.seq from 0, frame_id rig, pinion and pinion;
 4. --calibrate: on the kinematic bag the loaded windows are gated (no TE where the model predicts
    one), so it refuses with exit 1 naming why and writes nothing. The same bag with the model's
    own prediction at the prior added to the gear encoder (the kinematic replay's predicted_*
    features) updates on every loaded window, and the gearbox --calibrate writes holds the last
    calibration row's values (mesh.stiffness_scale, the bearings' stiffness_scale by shaft,
    anti_backlash.preload_torque, calibration priors {mean, std}), names the bag and what was not
    identified, and drivetrain_replay runs with it as --config. Refused before the replay: a
    gearbox without a calibration block, ~calibrate false;
 5. ~calibrate false (--params) and a gearbox without a calibration block: header-only CSVs, no
    /calibration in the bag, the counters 0, summary.json's calibration status says why.
usage: check_replay_calibration.py BIN_DIR SOURCE_DIR WORK_DIR"""
import csv
import filecmp
import json
import math
import os
import re
import shutil
import subprocess
import sys

import rosbag
import yaml

bin_dir, src, work = sys.argv[1:4]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
config = os.path.join(src, "test", "data", "calibration_servo.yaml")
params = os.path.join(src, "config", "stiffness_estimator.yaml")
PARAMETERS = ["mesh_stiffness_scale", "pinion_bearing_scale", "gear_bearing_scale", "preload_torque", "te_offset"]
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
    return ok


def msg_fields(name):
    """The fields of msg/NAME.msg after the header, in order, with their types."""
    out = []
    for line in open(os.path.join(src, "msg", name + ".msg")):
        code = line.split("#")[0].split()
        if len(code) >= 2 and code[1] != "header":
            out.append((code[1], code[0]))
    return out


def replay(tag, *args, config=config, expect=0):
    out = os.path.join(work, tag)
    cmd = [os.path.join(bin_dir, "drivetrain_replay"), "--bag", bag, "--config", config, "--out", out + ".bag",
           "--csv", out] + list(args)
    r = subprocess.run(cmd, capture_output=True, text=True)
    check(r.returncode == expect, "%s: exit %d (expected %d): %s" % (tag, r.returncode, expect, r.stderr.strip()))
    return r, (json.loads(r.stdout) if r.stdout.strip() else None)


def rows(path):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        return next(reader), list(reader)


# 1. The bag and two identical replays.
bag = os.path.join(work, "steps.bag")
sim = json.loads(subprocess.run([os.path.join(bin_dir, "drivetrain_rig_sim"), "--scenario", "torque_steps", "--config", config,
                                 "--duration", "2", "--joint-rate", "5000", "--out", bag],
                                check=True, capture_output=True, text=True).stdout)
calibrated = {run: os.path.join(work, run + "_calibrated", "gearbox.yaml") for run in "ab"}
results = {}
for run in "ab":
    r = subprocess.run([os.path.join(bin_dir, "drivetrain_replay"), "--bag", bag, "--config", config, "--params", params,
                        "--out", os.path.join(work, run + ".bag"), "--csv", os.path.join(work, run),
                        "--calibrate", calibrated[run]], capture_output=True, text=True)
    results[run] = r
summary = json.loads(results["a"].stdout)
c = summary["counters"]
cal = summary["calibration"]
print("counters: measured_te_published %d, calibration_published %d, calibration_errors %d; calibration: %s"
      % (c["measured_te_published"], c["calibration_published"], c["calibration_errors"], json.dumps(cal)))
check(filecmp.cmp(os.path.join(work, "a.bag"), os.path.join(work, "b.bag"), shallow=False), "output bags differ")
for f in ["stiffness", "transmission_error", "te_spectrum", "resonance", "measured_te", "calibration", "mesh_period_stats"]:
    check(filecmp.cmp(os.path.join(work, "a", f + ".csv"), os.path.join(work, "b", f + ".csv"), shallow=False),
          f + ".csv differs between two replays")
check(c["accepted_joint_states"] == sim["joint_states"] > 0 and c["rejected_joint_states"] == 0,
      "joint_states: %d accepted of %d" % (c["accepted_joint_states"], sim["joint_states"]))
check(c["calibration_errors"] == 0, "calibration_errors %d: %s" % (c["calibration_errors"], c["last_event"]))

# 2. The CSV files: the message fields as columns, one row per message, finite numbers.
tables = {}
for topic, msg, counter in [("calibration", "Calibration", "calibration_published"),
                            ("measured_te", "MeasuredTe", "measured_te_published"),
                            ("mesh_period_stats", "MeshPeriodStats", "mesh_period_stats_published")]:
    fields = msg_fields(msg)
    header, body = rows(os.path.join(work, "a", topic + ".csv"))
    tables[topic] = (fields, header, body)
    check(header == ["stamp"] + [f for f, _ in fields],
          "%s.csv columns %s are not the fields of msg/%s.msg %s" % (topic, header, msg, [f for f, _ in fields]))
    check(len(body) == c[counter] and len(body) > 0, "%s.csv: %d rows, %s = %d" % (topic, len(body), counter, c[counter]))
    for row in body:
        for (name, kind), value in zip(fields, row[1:]):
            if kind != "string" and not math.isfinite(float(value)):
                check(False, "%s.csv: %s = %s" % (topic, name, value))
    print("%s.csv: %d rows, %d columns" % (topic, len(body), len(header)))
cal_fields, cal_header, cal_rows = tables["calibration"]
outcomes = sorted({r[cal_header.index("outcome")] for r in cal_rows})
print("calibration outcomes:", outcomes)
check("baseline" in outcomes, "no baseline window (torque_steps' 0.05 N*m step)")

# 3. The bag's topics equal the CSV rows.
with rosbag.Bag(os.path.join(work, "a.bag")) as b:
    for topic, frame in [("calibration", "rig"), ("measured_te", "pinion"), ("mesh_period_stats", "pinion")]:
        fields, header, body = tables[topic]
        msgs = [m for _, m, _ in b.read_messages(topics=["/" + topic])]
        check(len(msgs) == len(body), "/%s: %d messages, %d CSV rows" % (topic, len(msgs), len(body)))
        for k, (m, row) in enumerate(zip(msgs, body)):
            check(m.header.seq == k and m.header.frame_id == frame, "/%s[%d] header %s" % (topic, k, m.header))
            check("%d.%09d" % (m.header.stamp.secs, m.header.stamp.nsecs) == row[0], "/%s[%d] stamp" % (topic, k))
            for (name, kind), value in zip(fields, row[1:]):
                v = getattr(m, name)
                same = v == value if kind == "string" else float(v) == float(value)
                if not check(same, "/%s[%d].%s = %r, CSV %r" % (topic, k, name, v, value)):
                    break

# 4. --calibrate. On the kinematic bag (no TE): the loaded windows are expected to be gated, and
# then --calibrate refuses; should one update, the file is checked as below.
def check_calibrated(path, last, first, bag, tag):
    """The gearbox --calibrate wrote holds the last calibration row's values: each prior's mean, its
    std where identified and the drawing's spread (the first row's std, before any update; for a
    bearing scale at the calibrated mean) where not, and the drawing's spread as reference_std."""
    text = open(path).read()
    check(bag in text, tag + ": the calibrated gearbox does not name the bag")
    not_identified = [p for p in PARAMETERS if last[p + "_identified"] != "1"]
    line = [l for l in text.splitlines() if l.startswith("# Not identified")]
    check(line and line[0].endswith(": " + (", ".join(not_identified) or "none")),
          "%s: not-identified line %s vs %s" % (tag, line, not_identified))
    g = yaml.safe_load(text)
    value = lambda p: float(last[p])
    check(float(g["mesh"]["stiffness_scale"]) == value("mesh_stiffness_scale"), tag + ": mesh.stiffness_scale")
    for entry in g["bearings"]:
        p = "pinion_bearing_scale" if entry.get("shaft", "pinion") == "pinion" else "gear_bearing_scale"
        check(float(entry["stiffness_scale"]) == value(p), "%s: bearings %s stiffness_scale" % (tag, entry["name"]))
        check(os.path.isabs(entry["file"]) and os.path.exists(entry["file"]), "%s: bearing file %s" % (tag, entry["file"]))
    check(float(g["anti_backlash"]["preload_torque"]) == value("preload_torque"), tag + ": anti_backlash.preload_torque")
    for p in PARAMETERS:
        prior = g["calibration"][p]
        drawing = float(first[p + "_std"])
        if p in ("pinion_bearing_scale", "gear_bearing_scale"):
            # Kept in compliance (the filter's 1/s): read at the calibrated mean, x (s' / s)^2.
            ratio = value(p) / float(first[p])
            drawing = drawing * ratio * ratio  # in the writer's order: the same bits
        std = value(p + "_std") if last[p + "_identified"] == "1" else drawing
        check(float(prior["mean"]) == value(p) and float(prior["std"]) == std and float(prior["reference_std"]) == drawing,
              "%s: calibration.%s = %s" % (tag, p, prior))
    check(g["calibration"]["baseline_torque"] == 0.06, tag + ": calibration.baseline_torque not kept")
    # The node's loader takes it: the replay runs with it as its gearbox.
    replay(tag + "_reloaded", "--params", params, config=path)
    return not_identified


last = dict(zip(cal_header, cal_rows[-1]))
if int(float(last["updates"])) > 0:
    for run in "ab":
        check(results[run].returncode == 0, "--calibrate: exit %d: %s" % (results[run].returncode, results[run].stderr))
    strip = lambda t: [l for l in t.splitlines() if not l.startswith("# written ")]
    check(strip(open(calibrated["a"]).read()) == strip(open(calibrated["b"]).read()),
          "the calibrated gearboxes differ beyond their 'written' line")
    check_calibrated(calibrated["a"], last, dict(zip(cal_header, cal_rows[0])), bag, "kinematic")
else:
    for run in "ab":
        check(results[run].returncode == 1 and "no window of the bag updated the calibration" in results[run].stderr,
              "--calibrate without an update: exit %d, %s" % (results[run].returncode, results[run].stderr))
        check(not os.path.exists(calibrated[run]), "--calibrate without an update wrote " + calibrated[run])
    print("--calibrate on the kinematic bag: no update (%s): refused as expected" % last["outcome"])

# The same bag with a transmission error on the gear encoder: on each loaded step the model's own
# prediction at the prior (the kinematic replay's predicted_* features: mean TE and mesh harmonics
# above the baseline) as r_b,g delta theta_g = mean + |C_1| cos(2 pi phase) + |C_2| cos(4 pi phase),
# phase = z_p theta_p / 2 pi. Every loaded window should then update, and --calibrate write.
features = {}
for r in cal_rows:
    r = dict(zip(cal_header, r))
    if r["outcome"] != "baseline":
        features[round(float(r["window_torque"]), 9)] = [float(r[k]) for k in
                                                         ("predicted_mean_te", "predicted_mesh_harmonic_1", "predicted_mesh_harmonic_2")]
gear = yaml.safe_load(open(config))["gears"]
z_p, z_g = gear["teeth"]
r_bg = float(gear["module"]) * z_g * math.cos(math.radians(float(gear["pressure_angle_deg"]))) / 2.0
te_bag = os.path.join(work, "steps_te.bag")
held = 0.0
with rosbag.Bag(bag) as b, rosbag.Bag(te_bag, "w") as out:
    for topic, m, t in b.read_messages():
        if topic == "/torque":
            held = m.wrench.torque.z
        elif topic == "/joint_states" and round(held, 9) in features:
            mean, c1, c2 = features[round(held, 9)]
            phase = (z_p * m.position[0] / (2.0 * math.pi)) % 1.0
            te = mean + c1 * math.cos(2.0 * math.pi * phase) + c2 * math.cos(4.0 * math.pi * phase)
            m.position = [m.position[0], m.position[1] + te / r_bg]
        out.write(topic, m, t)
te_calibrated = os.path.join(work, "te_calibrated.yaml")  # beside the bag: another directory than the config's
bag_kinematic = bag
bag = te_bag
r, s_te = replay("te", "--params", params, "--calibrate", te_calibrated)
bag = bag_kinematic
if s_te:
    header, body = rows(os.path.join(work, "te", "calibration.csv"))
    last_te = dict(zip(header, body[-1]))
    print("TE bag: %s windows, %s updates, %s gated; last NIS %s" % (last_te["windows"], last_te["updates"], last_te["gated"], last_te["nis"]))
    if check(int(float(last_te["updates"])) > 0 and os.path.exists(te_calibrated),
             "the model's own TE did not update the calibration (last: %s): %s" % (last_te["outcome"], r.stderr.strip())):
        check(s_te["calibrated_gearbox"] == te_calibrated, "summary.json: calibrated_gearbox")
        not_identified = check_calibrated(te_calibrated, last_te, dict(zip(header, body[0])), te_bag, "te")
        print("--calibrate on the TE bag: written; not identified: %s" % (", ".join(not_identified) or "none"))
        # The stiffness and resonance outputs carry the calibration's 95 % bounds once it updated:
        # low <= calibrated <= high, a band of nonzero width; the calibrated mesh stiffness is the
        # mesh scale times the drawing's (within the flank-state definitions, 2 %).
        header, body = rows(os.path.join(work, "te", "stiffness.csv"))
        st = dict(zip(header, body[-1]))
        check(float(st["calibrated"]) == 1.0, "stiffness.csv: last row not calibrated")
        for q in ["mesh_stiffness_mean", "pinion_bearing_stiffness", "gear_bearing_stiffness"]:
            lo, mid, hi = float(st[q + "_low"]), float(st[q + "_calibrated"]), float(st[q + "_high"])
            check(lo <= mid <= hi and hi > lo, "stiffness.csv %s: bounds %s %s %s" % (q, lo, mid, hi))
        ratio = float(st["mesh_stiffness_mean_calibrated"]) / float(st["mesh_stiffness_mean"])
        check(abs(ratio / float(last_te["mesh_stiffness_scale"]) - 1.0) < 0.02,
              "stiffness.csv: calibrated/drawing mesh stiffness %s against the scale %s" % (ratio, last_te["mesh_stiffness_scale"]))
        header, body = rows(os.path.join(work, "te", "resonance.csv"))
        rs = dict(zip(header, body[-1]))
        for k in ["f1_hz", "f2_hz", "f3_hz"]:
            lo, mid, hi = float(rs[k + "_low"]), float(rs[k + "_calibrated"]), float(rs[k + "_high"])
            check(lo <= mid <= hi and hi > lo, "resonance.csv %s: bounds %s %s %s" % (k, lo, mid, hi))

# --calibrate refused before the replay.
off = os.path.join(work, "calibrate_off.yaml")
with open(params) as f, open(off, "w") as g:
    text = re.sub(r"(?m)^calibrate:.*$", "calibrate: false", f.read())
    check("calibrate: false" in text, "config/stiffness_estimator.yaml has no calibrate: line")
    g.write(text)
seed = os.path.join(src, "test", "data", "perturbed_servo.yaml")  # a gearbox with no calibration: block
for tag, cfg, p, why in [("refused_no_block", seed, params, "off: the gearbox has no calibration block"),
                         ("refused_off", config, off, "off: ~calibrate is false")]:
    r, _ = replay(tag, "--params", p, "--calibrate", os.path.join(work, tag + ".yaml"), config=cfg, expect=1)
    check("--calibrate = '" in r.stderr and why in r.stderr, "%s: %s" % (tag, r.stderr.strip()))
    check(not os.path.exists(os.path.join(work, tag + ".bag")), tag + ": replayed anyway")

# 5. No calibration: ~calibrate false, or no calibration block.
for tag, cfg, p, why in [("no_block", seed, params, "off: the gearbox has no calibration block"),
                         ("off", config, off, "off: ~calibrate is false")]:
    _, s = replay(tag, "--params", p, config=cfg)
    if not s:
        continue
    check(s["calibration"]["status"] == why, "%s: status %s" % (tag, s["calibration"]))
    check(s["counters"]["calibration_published"] == 0 and s["counters"]["measured_te_published"] == 0, tag + ": counters")
    for topic in ["calibration", "measured_te"]:
        header, body = rows(os.path.join(work, tag, topic + ".csv"))
        check(header == tables[topic][1] and not body, "%s: %s.csv not header-only" % (tag, topic))
    with rosbag.Bag(os.path.join(work, tag + ".bag")) as b:
        topics = b.get_type_and_topic_info().topics
        check("/calibration" not in topics and "/measured_te" not in topics, "%s: calibration topics in the bag" % tag)
    # Without a calibration the bands repeat the drawing's model with zero width.
    header, body = rows(os.path.join(work, tag, "stiffness.csv"))
    st = dict(zip(header, body[-1]))
    check(float(st["calibrated"]) == 0.0 and st["mesh_stiffness_mean_low"] == st["mesh_stiffness_mean_high"] ==
          st["mesh_stiffness_mean_calibrated"] == st["mesh_stiffness_mean"], "%s: stiffness bands without a calibration" % tag)

# 6. --topics (a campaign's bag reports keep only what they need): exactly the chosen topics go to
# the bag and the CSV directory, each with the same bytes and messages as in the full replay "a";
# the summary says which; an unknown name is refused before anything is written.
chosen = ["calibration", "mesh_period_stats"]
_, s = replay("topics", "--params", params, "--topics", ",".join(chosen))
if s:
    check(s["topics"] == ",".join(chosen), "--topics: summary topics %r" % s.get("topics"))
    check(json.loads(results["a"].stdout)["topics"] == "all", "full replay: summary topics not 'all'")
    check(sorted(os.listdir(os.path.join(work, "topics"))) == sorted(t + ".csv" for t in chosen),
          "--topics: CSV files %s" % sorted(os.listdir(os.path.join(work, "topics"))))
    for t in chosen:
        check(filecmp.cmp(os.path.join(work, "a", t + ".csv"), os.path.join(work, "topics", t + ".csv"), shallow=False),
              "--topics: %s.csv differs from the full replay's" % t)
    with rosbag.Bag(os.path.join(work, "topics.bag")) as b, rosbag.Bag(os.path.join(work, "a.bag")) as full:
        check(sorted(b.get_type_and_topic_info().topics) == sorted("/" + t for t in chosen),
              "--topics: bag topics %s" % sorted(b.get_type_and_topic_info().topics))
        for t in chosen:
            mine = [(m._type, str(m)) for _, m, _ in b.read_messages(topics=["/" + t])]
            theirs = [(m._type, str(m)) for _, m, _ in full.read_messages(topics=["/" + t])]
            check(mine == theirs and mine, "--topics: /%s differs from the full replay's (%d, %d messages)"
                  % (t, len(mine), len(theirs)))
# summary.json's mesh_periods (a campaign row's speed, torque and TE columns) against the blocks of
# mesh_period_stats.csv summed here: the same numbers to the last bit (the same operations in the
# same order: speed 2 pi f / z_p, duration-weighted squares and forces, the largest peak-to-peak).
header, body = rows(os.path.join(work, "a", "mesh_period_stats.csv"))
blocks = [dict(zip(header, (float(v) for v in row))) for row in body]
z_p = int(yaml.safe_load(open(config))["gears"]["teeth"][0])
speeds = [2.0 * math.pi * b["mesh_frequency"] / z_p for b in blocks]
torques = [b["torque"] for b in blocks]
weight = square = force = p2p = 0.0
for b in blocks:
    weight += b["duration"]
    square += b["duration"] * (b["te_rms"] * b["te_rms"])
    force += b["duration"] * b["mesh_force_mean"]
    p2p = max(p2p, b["te_peak_to_peak"])
expected = {"blocks": len(blocks), "speed_min": min(speeds), "speed_max": max(speeds), "torque_min": min(torques),
            "torque_max": max(torques), "te_rms": math.sqrt(square / weight), "te_peak_to_peak": p2p,
            "mesh_force_mean": force / weight}
check(len(blocks) > 0 and summary["mesh_periods"] == expected,
      "summary mesh_periods %s != %s from mesh_period_stats.csv" % (summary.get("mesh_periods"), expected))
# A report whose plots would miss their topics is refused before anything is read.
r, _ = replay("topics_no_plots", "--topics", "calibration", "--report", os.path.join(work, "topics_report"), expect=1)
check("the report's plots read" in r.stderr and "--no-plots" in r.stderr, "report without plot topics: " + r.stderr.strip())
# --csv-topics: the CSV directory alone gets its own list.
_, s = replay("csv_topics", "--topics", "calibration,resonance", "--csv-topics", "calibration")
if s:
    check(sorted(os.listdir(os.path.join(work, "csv_topics"))) == ["calibration.csv"],
          "--csv-topics: CSV files %s" % sorted(os.listdir(os.path.join(work, "csv_topics"))))
    with rosbag.Bag(os.path.join(work, "csv_topics.bag")) as b:
        check(sorted(b.get_type_and_topic_info().topics) == ["/calibration", "/resonance"], "--csv-topics: bag topics")
    check(s["topics"] == "resonance,calibration" and s["csv_topics"] == "calibration",
          "--csv-topics: summary %r %r" % (s.get("topics"), s.get("csv_topics")))
r, _ = replay("topics_unknown", "--topics", "calibration,measured_tee", expect=1)
check("--topics = 'calibration,measured_tee': unknown topic 'measured_tee'" in r.stderr, "unknown topic: " + r.stderr.strip())
check(not os.path.exists(os.path.join(work, "topics_unknown.bag")), "unknown topic: replayed anyway")

if failures:
    sys.exit("check_replay_calibration:\n  " + "\n  ".join(failures))
print("check_replay_calibration: bit-identical; CSV columns = message fields, finite; bag = CSV; --calibrate and --topics checked")
