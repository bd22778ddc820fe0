#!/usr/bin/python3
"""Prints a summary of the stiffness estimates every 0.5 s and a final table, then exits."""
import rospy
from drivetrain_stiffness.msg import Stiffness, TransmissionError


class Summary:
    def __init__(self):
        self.count = 0
        self.last = None
        self.first_stamp = None
        self.printed_at = -1.0
        self.te_count = 0
        self.te_peak = 0.0
        self.te_last = None
        rospy.Subscriber("stiffness", Stiffness, self.on_stiffness, queue_size=1000)
        rospy.Subscriber("transmission_error", TransmissionError, self.on_te, queue_size=10000)

    def on_te(self, msg):
        self.te_count += 1
        self.te_peak = max(self.te_peak, abs(msg.dynamic_te))
        self.te_last = msg

    def on_stiffness(self, msg):
        self.count += 1
        self.last = msg
        if self.first_stamp is None:
            self.first_stamp = msg.header.stamp
        t = (msg.header.stamp - self.first_stamp).to_sec()
        if t - self.printed_at >= 0.5:
            self.printed_at = t
            parts = ["%s kr=%.4g N/m (Fr=%.0f N, Fa=%.0f N)" % (b.name, b.radial_stiffness, b.radial_load, b.axial_load)
                     for b in msg.bearings]
            print("t=%5.2f s  T=%.4f N*m  Fm=%.2f N  mesh ks=%.4g N/m (phase %.2f)  %s" % (
                t, msg.torque, msg.mesh_force, msg.mesh_stiffness, msg.mesh_phase, "; ".join(parts)), flush=True)


def main():
    rospy.init_node("stiffness_summary")
    duration = rospy.get_param("~duration", 4.0)
    summary = Summary()
    deadline = rospy.Time.now() + rospy.Duration(duration + 15.0)
    while not rospy.is_shutdown() and rospy.Time.now() < deadline:
        if summary.last is not None and (summary.last.header.stamp - summary.first_stamp).to_sec() >= duration - 0.05:
            break
        rospy.sleep(0.1)
    if summary.last is None:
        rospy.logerr("no stiffness estimate received")
        raise SystemExit(1)
    print("received %d stiffness estimates; final state:" % summary.count, flush=True)
    for b in summary.last.bearings:
        print("  %-15s radial %.4g N/m  axial %.4g N/m  tilt %.4g N*m/rad  balls in contact %d  p_max %.3g Pa"
              % (b.name, b.radial_stiffness, b.axial_stiffness, b.tilt_stiffness, b.balls_in_contact,
                 b.max_contact_pressure), flush=True)
    if summary.te_last is not None:
        m = summary.te_last
        print("transmission_error: %d samples; peak |dynamic TE| %.4g m; last: dynamic %.4g m, static %.4g m, "
              "mesh force %.2f N, flanks drive=%s back=%s" % (summary.te_count, summary.te_peak, m.dynamic_te, m.static_te,
                                                             m.mesh_force, m.drive_flank_loaded, m.back_flank_loaded), flush=True)
    rospy.signal_shutdown("summary done")


if __name__ == "__main__":
    main()
