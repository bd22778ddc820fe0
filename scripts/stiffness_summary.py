#!/usr/bin/python3
"""Prints the stiffness estimator's outputs as they arrive (every 0.5 s of stamp time), then, once
no output has come for ~idle_timeout wall seconds (the bag has finished), a final summary with the
input counters from /diagnostics, and exits. Works under sim time (rosbag play --clock)."""
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray
from drivetrain_stiffness.msg import Resonance, Stiffness, TransmissionError

COUNTERS = ("accepted_torque", "rejected_torque", "accepted_preload", "rejected_preload", "rejected_zero_stamp",
            "rejected_out_of_order", "rejected_invalid_value", "clock_jump_resets", "stamp_jump_resets",
            "gap_restarts", "missed_deadlines", "realtime_factor")


class Summary:
    def __init__(self):
        self.count = 0
        self.last = None
        self.first_stamp = None
        self.printed_at = -1.0
        self.te_count = 0
        self.te_peak = 0.0
        self.te_last = None
        self.resonance = None
        self.diagnostics = {}
        self.last_wall = None
        rospy.Subscriber("stiffness", Stiffness, self.on_stiffness, queue_size=1000)
        rospy.Subscriber("transmission_error", TransmissionError, self.on_te, queue_size=10000)
        rospy.Subscriber("resonance", Resonance, self.on_resonance, queue_size=10)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=10)

    def on_te(self, msg):
        self.te_count += 1
        self.te_peak = max(self.te_peak, abs(msg.dynamic_te))
        self.te_last = msg
        self.last_wall = time.monotonic()

    def on_resonance(self, msg):
        self.resonance = msg
        print("resonance at %.3f s: %s; Floquet margin %s" % (
            msg.header.stamp.to_sec(), ", ".join("%.0f Hz (%s)" % (f, d) for f, d in zip(msg.frequencies_hz, msg.dominant_coordinate)),
            "%.3f" % msg.floquet_margin if msg.floquet_valid else "n/a"), flush=True)

    def on_diagnostics(self, msg):
        for status in msg.status:
            if status.name.endswith("stiffness_estimator"):
                self.diagnostics = {kv.key: kv.value for kv in status.values}
                self.diagnostics["level"] = status.level
                self.diagnostics["message"] = status.message

    def on_stiffness(self, msg):
        self.count += 1
        self.last = msg
        self.last_wall = time.monotonic()
        if self.first_stamp is None:
            self.first_stamp = msg.header.stamp
        t = (msg.header.stamp - self.first_stamp).to_sec()
        if t - self.printed_at >= 0.5 or t < self.printed_at:
            self.printed_at = t
            parts = ["%s kr=%.4g N/m (Fr=%.0f N, Fa=%.0f N)" % (b.name, b.radial_stiffness, b.radial_load, b.axial_load)
                     for b in msg.bearings]
            print("t=%5.2f s  T=%.4f N*m  Fm=%.2f N  mesh ks=%.4g N/m (phase %.2f)  %s" % (
                t, msg.torque, msg.mesh_force, msg.mesh_stiffness, msg.mesh_phase, "; ".join(parts)), flush=True)


def main():
    idle = rospy.get_param("~idle_timeout", 2.0)       # [s] wall time without output that ends the run
    give_up = rospy.get_param("~start_timeout", 30.0)  # [s] wall time to wait for the first output
    summary = Summary()
    started = time.monotonic()
    while not rospy.is_shutdown():
        now = time.monotonic()
        if summary.last_wall is None and now - started > give_up:
            break
        if summary.last_wall is not None and now - summary.last_wall > idle:
            break
        time.sleep(0.1)
    time.sleep(1.2)  # one more diagnostics period, so the counters include the last inputs
    if summary.last is None:
        rospy.logerr("no stiffness estimate received")
        raise SystemExit(1)
    print("== summary: %d stiffness estimates; final state:" % summary.count, flush=True)
    for b in summary.last.bearings:
        print("  %-15s radial %.4g N/m  axial %.4g N/m  tilt %.4g N*m/rad  balls in contact %d  p_max %.3g Pa"
              % (b.name, b.radial_stiffness, b.axial_stiffness, b.tilt_stiffness, b.balls_in_contact,
                 b.max_contact_pressure), flush=True)
    if summary.te_last is not None:
        m = summary.te_last
        print("  transmission_error: %d samples; peak |dynamic TE| %.4g m; last: dynamic %.4g m, static %.4g m, "
              "mesh force %.2f N, flanks drive=%s back=%s" % (summary.te_count, summary.te_peak, m.dynamic_te, m.static_te,
                                                             m.mesh_force, m.drive_flank_loaded, m.back_flank_loaded), flush=True)
    if summary.resonance is not None:
        r = summary.resonance
        print("  resonance: " + ", ".join("%.0f Hz (%s, zeta %.3f)" % (f, d, z) for f, d, z in
                                          zip(r.frequencies_hz, r.dominant_coordinate, r.damping_ratios)), flush=True)
    if summary.diagnostics:
        print("  diagnostics (%s): " % summary.diagnostics.get("message", "") +
              ", ".join("%s=%s" % (k, summary.diagnostics[k]) for k in COUNTERS if k in summary.diagnostics), flush=True)
    rospy.signal_shutdown("summary done")


if __name__ == "__main__":
    rospy.init_node("stiffness_summary")
    # ~done_file: written when the summary ends, "ok" or "failed" (also on an exception), so that
    # scripts/demo can stop roslaunch with SIGINT, a normal shutdown, instead of roslaunch's red
    # "REQUIRED process has died" that a required node's end prints. "" = not written.
    done_file = rospy.get_param("~done_file", "")
    status = "failed"
    try:
        main()
        status = "ok"
    finally:
        if done_file:
            with open(done_file, "w") as f:
                f.write(status + "\n")
