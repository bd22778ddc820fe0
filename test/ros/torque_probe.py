#!/usr/bin/python3
"""Sends torque to the stiffness estimator until its first answer (a numbered rospy publisher, the
rig's frame) and prints, as JSON, the wall time from its first send to that answer. A fresh process
per probe: rospy cannot re-register with a restarted master.
usage: torque_probe.py TIMEOUT_S"""
import json
import sys
import time

import rospy
from drivetrain_stiffness.msg import Stiffness
from geometry_msgs.msg import WrenchStamped

timeout = float(sys.argv[1])
rospy.init_node("torque_probe", anonymous=True, disable_signals=True)
answer = {}
rospy.Subscriber("stiffness", Stiffness, lambda m: answer.setdefault("wall", time.time()))
pub = rospy.Publisher("torque", WrenchStamped, queue_size=100)
msg = WrenchStamped()
msg.header.frame_id = "pinion"
msg.wrench.torque.z = 0.1
first = None
deadline = time.time() + timeout
while "wall" not in answer and time.time() < deadline:
    msg.header.stamp = rospy.Time.now()
    pub.publish(msg)  # rospy numbers header.seq itself
    if first is None:
        first = time.time()
    time.sleep(0.005)
print(json.dumps({"answered": "wall" in answer, "first_input_to_answer_s": answer["wall"] - first if "wall" in answer else None}))
sys.exit(0 if "wall" in answer else 1)
