#!/usr/bin/python3
"""Generates a rig input stream for demos: pinion torque (geometry_msgs/WrenchStamped, torque.z in
N*m) at 1 kHz with a mesh-frequency ripple, and bearing preload settings at 5 Hz ramping the axial
preload of both supports from 400 N to 2000 N (seed 000 section 4.1 range). Stamps are ROS time."""
import math

import rospy
from geometry_msgs.msg import WrenchStamped
from drivetrain_stiffness.msg import BearingPreload, Preload

SUPPORTS = ("pinion_bearing", "gear_bearing")


def main():
    rospy.init_node("rig_input_generator")
    duration = rospy.get_param("~duration", 4.0)
    mean_torque = rospy.get_param("~mean_torque", 0.1)      # N*m, seed 000 Table 1 drive torque
    ripple = rospy.get_param("~ripple", 0.02)               # N*m amplitude
    speed_rpm = rospy.get_param("~speed_rpm", 1000.0)       # seed 000 Table 1
    teeth = rospy.get_param("~pinion_teeth", 20)
    torque_pub = rospy.Publisher("torque", WrenchStamped, queue_size=100)
    preload_pub = rospy.Publisher("preload", Preload, queue_size=10)
    while not rospy.is_shutdown() and (torque_pub.get_num_connections() == 0 or preload_pub.get_num_connections() == 0):
        rospy.sleep(0.05)
    rospy.sleep(0.5)  # let the summary node connect too
    mesh_hz = speed_rpm / 60.0 * teeth
    start = rospy.Time.now()
    rate = rospy.Rate(1000)
    last_preload = -1.0
    while not rospy.is_shutdown():
        now = rospy.Time.now()
        t = (now - start).to_sec()
        if t > duration:
            break
        if t - last_preload >= 0.2:
            last_preload = t
            msg = Preload()
            msg.header.stamp = now
            axial = 400.0 + 1600.0 * min(t / duration, 1.0)
            for name in SUPPORTS:
                msg.bearings.append(BearingPreload(name=name, axial_preload=axial, radial_preload=1000.0,
                                                   inner_interference=5e-6, outer_interference=5e-6))
            preload_pub.publish(msg)
        w = WrenchStamped()
        w.header.stamp = now
        w.header.frame_id = "pinion"
        w.wrench.torque.z = mean_torque + ripple * math.sin(2.0 * math.pi * mesh_hz * t)
        torque_pub.publish(w)
        rate.sleep()


if __name__ == "__main__":
    main()
