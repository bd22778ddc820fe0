#!/usr/bin/python3
"""drivetrain_replay on bags another lab would hand it, written here with python rosbag: a torque
in another frame, two kinds of refusal in one bag, only unrelated topics, a topic of the wrong
type, one topic named for two inputs, a directory or a pipe as --bag, gaps with load changes, a
frame id that is not UTF-8, encoders that barely turn, a calibration recording whose torque steps
are too short for a window, accelerometer blocks that break the block rules (on a rig topic, and
the bag fuzz target's seeds). For each: the exit code
(docs/replay_exit_codes.md), the run summary on stderr, summary.json's "inputs", and report.md
with and without plots say what was used, what was not, and why.

usage: check_foreign_bags.py BIN_DIR SOURCE_DIR WORK_DIR   (with the devel space's env.sh)"""
import json
import os
import shutil
import struct
import subprocess
import sys

import rosbag
import rospy
from geometry_msgs.msg import Twist, WrenchStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import String

bin_dir, src, work = sys.argv[1:4]
replay = os.path.join(bin_dir, "drivetrain_replay")
config = os.path.join(src, "config/gearboxes/seed_servo.yaml")
params = os.path.join(src, "config/stiffness_estimator.yaml")  # torque_frame: pinion
T0 = rospy.Time(1767225600, 0)
failures = []


def at(seconds):
    return T0 + rospy.Duration.from_sec(seconds)


def wrench(t, torque, frame="pinion", seq=0):
    m = WrenchStamped()
    m.header.stamp, m.header.frame_id, m.header.seq = t, frame, seq
    m.wrench.torque.z = torque
    return m


def bag_of(name, messages):
    """messages: (topic, message, time) or (topic, (type, raw bytes, md5sum), time) for raw ones."""
    path = os.path.join(work, name + ".bag")
    with rosbag.Bag(path, "w") as bag:
        for topic, m, t in messages:
            if isinstance(m, tuple):
                bag.write(topic, m + (None,), t, raw=True)
            else:
                bag.write(topic, m, t)
    return path


def run(name, bag, *extra, plots=False, params_file=params):
    report = os.path.join(work, name + ".report")
    cmd = [replay, "--bag", bag, "--config", config, "--report", report] + list(extra)
    if params_file:
        cmd += ["--params", params_file]
    if not plots:
        cmd.append("--no-plots")
    p = subprocess.run(cmd, capture_output=True, text=True)
    summary = None
    if os.path.exists(os.path.join(report, "summary.json")):
        with open(os.path.join(report, "summary.json")) as f:
            summary = json.load(f)
    md = ""
    if os.path.exists(os.path.join(report, "report.md")):
        with open(os.path.join(report, "report.md")) as f:
            md = f.read()
    stdout = json.loads(p.stdout) if p.stdout.strip().startswith("{") else None
    return p, summary, md, stdout


def check(name, conditions):
    bad = [what for ok, what in conditions if not ok]
    print("%-28s %s" % (name, "; ".join(bad) or "ok"))
    if bad:
        failures.append(name)


def wrong_frame():
    bag = bag_of("wrong_frame", [("/torque", wrench(at(0.001 * i), 0.1, "base_link"), at(0.001 * i)) for i in range(1, 201)])
    for plots in (False, True):
        name = "wrong_frame" + ("_plots" if plots else "")
        p, s, md, out = run(name, bag, plots=plots)
        refused = ((s or {}).get("inputs", {}).get("torque", {}).get("refused_by_reason", {}).get("wrong frame", {}))
        check(name, [
            (p.returncode == 5, "exit %d, expected 5 (no torque accepted): %s" % (p.returncode, p.stderr[-400:])),
            ("200 refused (wrong frame), found 'base_link' (200)" in p.stderr, "stderr lacks the count and the frame found"),
            ("expected ~torque_frame = 'pinion'" in p.stderr, "stderr lacks the frame expected"),
            ("matplotlib" not in p.stderr, "stderr blames matplotlib"),
            (s is not None and s["status"].startswith("no torque accepted"), "status %r" % (s or {}).get("status")),
            (refused.get("count") == 200 and refused.get("found", {}).get("base_link") == 200, "inputs: %r" % refused),
            (out is not None and out["speed"]["realtime_factor"] is None, "a realtime_factor with no torque accepted"),
            ("**No torque accepted**" in md and "base_link" in md, "report.md does not say why"),
            (not plots or "No figures" in md, "report.md with plots does not say there are no figures"),
        ])


def torque_refused_among_other_inputs():
    """Encoders and a preload accepted, every torque refused (another frame): still nothing estimated."""
    msgs = [("/preload", light_preload(), at(0.0001))]
    for i in range(1, 201):
        t = at(0.001 * i)
        msgs.append(("/torque", wrench(t, 0.1, "base_link"), t))
        msgs.append(("/joint_states", joint_state(t, 0.1047 * 0.001 * i), t))
    p, s, _, _ = run("torque_refused_among_others", bag_of("torque_refused_among_others", msgs))
    c = (s or {}).get("counters", {})
    check("torque_refused_among_others", [
        (p.returncode == 5, "exit %d, expected 5 (no torque accepted)" % p.returncode),
        (c.get("accepted_joint_states") == 200 and c.get("accepted_preload") == 1, "the other inputs: %r" % c),
        ("no torque accepted" in (s or {}).get("status", ""), "status %r" % (s or {}).get("status")),
    ])


def plot_script_fails():
    """A plot script that fails: exit 1, its own message, every other output written, and the run
    summary says exit code 1."""
    script = os.path.join(work, "failing_plot.py")
    with open(script, "w") as f:
        f.write("import sys\nsys.exit('failing_plot.py: no plots today')\n")
    p, s, md, out = run("plot_script_fails", os.path.join(src, "test/data/torque_steps.bag"), "--plot-script", script,
                        plots=True)
    check("plot_script_fails", [
        (p.returncode == 1, "exit %d, expected 1" % p.returncode),
        ("no plots today" in p.stderr and "failed with exit code 1" in p.stderr, "stderr: %s" % p.stderr[-300:]),
        ("matplotlib" not in p.stderr, "stderr blames matplotlib"),
        ("exit code 1: refused" in p.stderr, "the run summary's exit code is not the process's"),
        (s is not None and out is not None and "## Inputs" in md, "the other outputs are not written"),
    ])


def report_cannot_be_written():
    report = os.path.join(work, "unwritable.report")
    os.makedirs(os.path.join(report, "summary.json"))  # a directory where the file goes
    p = subprocess.run([replay, "--bag", os.path.join(src, "test/data/torque_steps.bag"), "--config", config,
                        "--report", report, "--no-plots"], capture_output=True, text=True)
    check("report_cannot_be_written", [(p.returncode == 1 and "cannot write '%s/summary.json'" % report in p.stderr,
                                        "exit %d: %s" % (p.returncode, p.stderr[-300:]))])


def two_refusals():
    msgs = [("/torque", wrench(at(0.001 * i), 0.1, "base_link"), at(0.001 * i)) for i in range(1, 101)]
    msgs += [("/torque", wrench(at(0.1 + 0.001 * i), float("nan")), at(0.1 + 0.001 * i)) for i in range(1, 51)]
    msgs += [("/torque", wrench(at(0.2 + 0.001 * i), 0.1), at(0.2 + 0.001 * i)) for i in range(1, 101)]
    p, s, md, _ = run("two_refusals", bag_of("two_refusals", msgs))
    reasons = (s or {}).get("inputs", {}).get("torque", {}).get("refused_by_reason", {})
    check("two_refusals", [
        (p.returncode == 0, "exit %d, expected 0 (some refused among many accepted)" % p.returncode),
        (reasons.get("wrong frame", {}).get("count") == 100, "wrong frame: %r" % reasons.get("wrong frame")),
        (reasons.get("invalid value", {}).get("count") == 50, "invalid value: %r" % reasons.get("invalid value")),
        ("100 refused (wrong frame)" in p.stderr and "50 refused (invalid value)" in p.stderr, "stderr lacks a reason"),
        ("## Inputs" in md and "50 refused (invalid value)" in md, "report.md without --no-plots' inputs"),
    ])


def unrelated_topics():
    msgs = []
    for i in range(1, 101):
        msgs.append(("/chatter", String(data="hello %d" % i), at(0.001 * i)))
        msgs.append(("/ft_sensor/wrench", wrench(at(0.001 * i), 0.1), at(0.001 * i)))
    bag = bag_of("unrelated", msgs)
    p, s, md, _ = run("unrelated_topics", bag)
    listed = [t["topic"] for t in (s or {}).get("inputs", {}).get("bag_topics", [])]
    check("unrelated_topics", [
        (p.returncode == 5, "exit %d, expected 5" % p.returncode),
        ("'/chatter' std_msgs/String, 100 messages" in p.stderr, "stderr does not list the bag's topics"),
        ("'/ft_sensor/wrench' holds 100 geometry_msgs/WrenchStamped messages: --torque-topic /ft_sensor/wrench reads them"
         in p.stderr, "stderr does not point at the topic of the wanted type"),
        (sorted(listed) == ["/chatter", "/ft_sensor/wrench"], "bag_topics %r" % listed),
        ("not in the bag" in md, "report.md does not say the topic is absent"),
    ])
    p, s, _, _ = run("unrelated_topics_named", bag, "--torque-topic", "/ft_sensor/wrench")
    check("unrelated_topics_named", [(p.returncode == 0 and (s or {}).get("counters", {}).get("accepted_torque") == 100,
                                      "exit %d, %r" % (p.returncode, (s or {}).get("counters", {}).get("accepted_torque")))])


def wrong_type():
    p, s, _, _ = run("wrong_type", bag_of("wrong_type", [("/torque", Twist(), at(0.001 * i)) for i in range(1, 358)]))
    check("wrong_type", [
        (p.returncode == 3, "exit %d, expected 3" % p.returncode),
        ("torque topic 'torque' (--torque-topic): 357 messages of type geometry_msgs/Twist, expected "
         "geometry_msgs/WrenchStamped" in p.stderr, "stderr does not name topic, found and expected type: " + p.stderr[-300:]),
        ((s or {}).get("inputs", {}).get("torque", {}).get("wrong_type") == {"geometry_msgs/Twist": 357}, "summary wrong_type"),
    ])


def bad_arguments():
    bag = os.path.join(src, "test/data/torque_steps.bag")
    report = os.path.join(work, "one_topic_twice.report")
    p = subprocess.run([replay, "--bag", bag, "--config", config, "--torque-topic", "/x", "--joint-states-topic", "x",
                        "--report", report], capture_output=True, text=True)
    check("one_topic_for_two_inputs", [
        (p.returncode == 1, "exit %d, expected 1" % p.returncode),
        ("--torque-topic = '/x' and --joint-states-topic = 'x' name one topic for two inputs" in p.stderr, p.stderr.strip()),
        (not os.path.exists(report), "refused after it began writing"),
    ])
    fifo = os.path.join(work, "pipe.bag")
    os.mkfifo(fifo)
    for name, path, said in (("bag_is_a_directory", work, "a directory, not a bag file"),
                             ("bag_does_not_exist", os.path.join(work, "no_such.bag"), "no such file"),
                             ("bag_is_a_pipe", fifo, "not a regular file")):
        try:
            p = subprocess.run([replay, "--bag", path, "--config", config], capture_output=True, text=True, timeout=20)
        except subprocess.TimeoutExpired:
            check(name, [(False, "still reading after 20 s")])
            continue
        check(name, [(p.returncode == 1 and ("--bag = '%s': %s" % (path, said)) in p.stderr,
                      "exit %d: %s" % (p.returncode, p.stderr.strip()))])


def light_preload():
    from drivetrain_stiffness.msg import BearingPreload, Preload
    light = Preload()
    light.header.stamp = at(0.0001)
    light.bearings = [BearingPreload(name=n, axial_preload=100.0) for n in ("pinion_bearing", "gear_bearing")]
    return light


def joint_state(t, pinion):
    j = JointState()
    j.header.stamp = t
    j.name, j.position = ["pinion", "gear"], [pinion, -0.5 * pinion]
    return j


def gaps_and_load_changes():
    """Torques off the 1 ms output grid; three pauses of 1.5 s (more than ~max_gap), each followed
    by a load that moves the bearing stiffness by more than the 1 % the dynamics take up (a light
    preload of 100 N, so that the mesh force counts)."""
    msgs, t = [("/preload", light_preload(), at(0.0001))], 0.0
    for load in (0.1, 8.0, 0.1, 8.0):
        for i in range(200):
            t += 0.00100041
            msgs.append(("/torque", wrench(at(t), load), at(t)))
        t += 1.5
    p, s, _, _ = run("gaps_and_load_changes", bag_of("gaps", msgs))
    c = (s or {}).get("counters", {})
    check("gaps_and_load_changes", [
        (p.returncode == 0, "exit %d" % p.returncode),
        (c.get("gap_restarts") == 3 and c.get("dynamics_errors") == 0,
         "gap_restarts %r, dynamics_errors %r: %s" % (c.get("gap_restarts"), c.get("dynamics_errors"), c.get("last_event"))),
    ])


def non_utf8_frame():
    """A frame id with the byte 0x85 (not UTF-8), written raw: the JSON summary and the console escape it."""
    frame = b"base\x85link"
    msgs = []
    for i in range(1, 51):
        t = at(0.001 * i)
        data = struct.pack("<III", i, t.secs, t.nsecs) + struct.pack("<I", len(frame)) + frame + struct.pack("<6d", 0, 0, 0, 0, 0, 0.1)
        msgs.append(("/torque", ("geometry_msgs/WrenchStamped", data, WrenchStamped._md5sum), t))
    p, s, _, out = run("non_utf8_frame", bag_of("non_utf8", msgs))
    check("non_utf8_frame", [
        (p.returncode == 5, "exit %d: %s" % (p.returncode, p.stderr[-300:])),
        (s is not None and out is not None, "summary.json or stdout is not valid JSON"),
        ("found 'base\\x85link' (50)" in p.stderr, "stderr does not escape the byte"),
    ])


def encoders_barely_turn():
    msgs = []
    for i in range(1, 2001):
        t = at(0.001 * i)
        msgs.append(("/torque", wrench(t, 0.1), t))
        j = JointState()
        j.header.stamp = t
        j.name, j.position, j.velocity = ["pinion", "gear"], [1e-4 * i * 1e-3, -0.5e-4 * i * 1e-3], [1e-4, -0.5e-4]
        msgs.append(("/joint_states", j, t))
    p, s, md, _ = run("encoders_barely_turn", bag_of("standstill", msgs), plots=True)
    check("encoders_barely_turn", [
        (p.returncode == 0, "exit %d: %s" % (p.returncode, p.stderr[-300:])),
        ("No TE order spectrum: the pinion turns" in md, "report.md drops the order spectrum without a note"),
        ("No Campbell diagram: the encoders' speed spans" in md, "report.md drops the Campbell diagram without a note"),
    ])


def calibration_without_a_window():
    """A load sweep at 60 rpm whose torque steps last 2 s, one gear turn of the 20/40 pair: no loaded
    window can close, and the replay says so with the numbers."""
    bag = os.path.join(work, "sweep_60rpm.bag")
    subprocess.run([os.path.join(bin_dir, "drivetrain_rig_sim"), "--scenario", "load_sweep", "--config",
                    os.path.join(src, "test/data/perturbed_servo.yaml"), "--out", bag, "--speed-rpm", "60",
                    "--duration", "38.4", "--seed", "3"], check=True, capture_output=True)
    p, s, md, _ = run("calibration_without_a_window", bag)
    waiting = ((s or {}).get("calibration") or {}).get("waiting") or ""
    said = "a window needs one gear turn, 2.00 s at 60 rpm"
    check("calibration_without_a_window", [
        (p.returncode == 0, "exit %d: %s" % (p.returncode, p.stderr[-300:])),
        (said in waiting, "summary.json calibration.waiting: %r" % waiting),
        (said in p.stderr, "stderr does not say why no window closed"),
        (said in md, "report.md does not say why no window closed"),
    ])


def vibration_block(t, seq, frames=1024, channels=("pinion_bearing", "gear_bearing", "tacho"), value=0.5):
    from drivetrain_stiffness.msg import VibrationBlock
    v = VibrationBlock()
    v.header.stamp, v.header.seq = t, seq
    v.sample_rate = 51200.0
    v.channels = list(channels)
    v.data = [value] * (frames * len(channels))
    return v


def vibration_on_a_rig_topic():
    """Accelerometer blocks on the rig's own topic: 1024 samples at 51.2 kHz (20 ms) with an unknown
    'tacho' channel; block 10 lost (a gap), block 15 with a NaN, block 20 one value short."""
    msgs = [("/torque", wrench(at(0.001 * i), 0.1), at(0.001 * i)) for i in range(1, 601)]
    block = 1024 / 51200.0
    for k in range(25):
        if k == 10:
            continue
        v = vibration_block(at(0.01 + k * block), k + 1)
        if k == 15:
            v.data[7] = float("nan")
        if k == 20:
            v.data = v.data[:-1]
        msgs.append(("/daq/accel", v, at(0.01 + k * block)))
    bag = bag_of("vibration", sorted(msgs, key=lambda m: m[2].to_nsec()))
    p, s, md, _ = run("vibration_unnamed", bag)
    check("vibration_topic_unnamed", [
        (p.returncode == 0, "exit %d" % p.returncode),
        ("'/daq/accel' holds 24 drivetrain_stiffness/VibrationBlock messages: --vibration-topic /daq/accel reads them"
         in p.stderr, "stderr does not point at the accelerometers' topic: " + p.stderr[-400:]),
    ])
    p, s, md, _ = run("vibration_named", bag, "--vibration-topic", "/daq/accel")
    c = (s or {}).get("counters", {})
    reasons = (s or {}).get("inputs", {}).get("vibration", {}).get("refused_by_reason", {})
    check("vibration_topic_named", [
        (p.returncode == 0, "exit %d" % p.returncode),
        (c.get("accepted_vibration") == 22 and c.get("rejected_vibration") == 2, "accepted/rejected %r/%r" % (
            c.get("accepted_vibration"), c.get("rejected_vibration"))),
        (reasons.get("invalid value", {}).get("count") == 2, "refusals %r" % reasons),
        ("channel 'gear_bearing', sample 2) = nan" in reasons.get("invalid value", {}).get("first_reason", ""),
         "the NaN's field not named: %r" % reasons.get("invalid value")),
        (c.get("dropped_vibration") == 1, "dropped (header.seq) %r" % c.get("dropped_vibration")),
        # block 10 lost (header.seq jumps); blocks 15 and 20 refused: the next block starts a new record
        (c.get("vibration_gaps") == 3, "gaps %r" % c.get("vibration_gaps")),
        (c.get("vibration_samples") == 22 * 1024, "samples %r" % c.get("vibration_samples")),
        (c.get("vibration_unknown_channels") == 22, "unknown channels %r" % c.get("vibration_unknown_channels")),
        ((s or {}).get("vibration", {}).get("unknown_channels") == ["tacho"],
         "summary vibration %r" % (s or {}).get("vibration")),
        ("22 accepted" in md or "22 accepted" in p.stderr, "the summary does not count the blocks"),
    ])


def vibration_fuzz_seeds():
    """The bag fuzz target's seeds with accelerometer blocks (test/fuzz/make_bag_seeds.py): the valid
    one accepted whole; of the broken one's 12 blocks, 6 refused (the same header.seq again, a NaN,
    one value short, zero and negative rates, no channels) and 6 accepted: one seq lost (dropped, a
    gap), an unknown channel (counted on each of the 3 blocks that carry it, a channel change), then
    8 kHz (a rate change): 3 x 16 + 1 x 16 + 2 x 8 frames. Exit 0: the torque was accepted."""
    seeds = os.path.join(src, "test/data/fuzz/bag")
    p, s, md, _ = run("fuzz_valid_vibration", os.path.join(seeds, "valid_vibration.bag"))
    c = (s or {}).get("counters", {})
    check("fuzz_seed_valid_vibration", [
        (p.returncode == 0, "exit %d: %s" % (p.returncode, p.stderr[-300:])),
        ((c.get("accepted_vibration"), c.get("rejected_vibration"), c.get("vibration_samples")) == (8, 0, 128),
         "accepted/rejected/samples %r" % c),
    ])
    p, s, md, _ = run("fuzz_broken_vibration", os.path.join(seeds, "vibration_broken_blocks.bag"))
    c = (s or {}).get("counters", {})
    expected = {"accepted_vibration": 6, "rejected_vibration": 6, "dropped_vibration": 1, "vibration_gaps": 1,
                "vibration_overlaps": 1, "vibration_rate_changes": 1, "vibration_channel_changes": 1,
                "vibration_unknown_channels": 3, "vibration_samples": 80}
    reasons = (s or {}).get("inputs", {}).get("vibration", {}).get("refused_by_reason", {})
    check("fuzz_seed_broken_vibration", [
        (p.returncode == 0, "exit %d: %s" % (p.returncode, p.stderr[-300:])),
        ((s or {}).get("status") == "ok", "status %r" % (s or {}).get("status")),
        ({k: c.get(k) for k in expected} == expected, "counters %r, expected %r" % ({k: c.get(k) for k in expected},
                                                                                    expected)),
        (reasons.get("invalid value", {}).get("count") == 6, "refusals %r" % reasons),
        ((s or {}).get("vibration", {}).get("unknown_channels") == ["tacho"],
         "summary vibration %r" % (s or {}).get("vibration")),
    ])


def main():
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    wrong_frame()
    torque_refused_among_other_inputs()
    plot_script_fails()
    report_cannot_be_written()
    two_refusals()
    unrelated_topics()
    wrong_type()
    bad_arguments()
    gaps_and_load_changes()
    non_utf8_frame()
    encoders_barely_turn()
    calibration_without_a_window()
    vibration_on_a_rig_topic()
    vibration_fuzz_seeds()
    if failures:
        sys.exit("check_foreign_bags: failed: %s" % ", ".join(failures))
    print("check_foreign_bags: every foreign bag's replay says what it used, what it did not, and why")


if __name__ == "__main__":
    main()
