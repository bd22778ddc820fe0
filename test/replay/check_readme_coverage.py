#!/usr/bin/python3
"""docs/ros_api.md documents the whole ROS interface: every message field (msg/*.msg), every
private parameter the node reads (get("...") / readParam(pnh, "...") in the sources), every launch
argument (launch/*.launch) and every dynamic_reconfigure setting (cfg/Estimator.cfg) is named in
it. (The README is the front door and links to it.) Fails with the list of what is missing.
usage: check_readme_coverage.py SOURCE_DIR"""
import glob
import os
import re
import sys
import xml.etree.ElementTree as ET

src = sys.argv[1]
DOC = os.path.join("docs", "ros_api.md")
doc = open(os.path.join(src, DOC)).read()
missing = []
for path in sorted(glob.glob(os.path.join(src, "msg", "*.msg"))):
    for line in open(path):
        code = line.split("#")[0].split()
        if len(code) >= 2 and "`%s`" % code[1] not in doc:
            missing.append("field %s.%s" % (os.path.basename(path)[:-4], code[1]))
sources = [os.path.join(src, p) for p in ("include/drivetrain_stiffness/ros/node_parameters.hpp",
                                           "src/ros/stiffness_estimator_ros.cpp")]
params = set()
for p in sources:
    text = open(p).read()
    params |= set(re.findall(r'\bget\("([a-z_]+)"', text)) | set(re.findall(r'readParam(?:<[^>]+>)?\(pnh, "([a-z_]+)"', text))
for name in sorted(params):
    if "~" + name not in doc:
        missing.append("parameter ~" + name)
for path in sorted(glob.glob(os.path.join(src, "launch", "*.launch"))):
    for arg in ET.parse(path).getroot().iter("arg"):
        if arg.get("value") is not None:
            continue  # computed inside the file, not an argument for users
        if "`%s`" % arg.get("name") not in doc:
            missing.append("launch arg %s:%s" % (os.path.basename(path), arg.get("name")))
for name in re.findall(r'gen\.add\("([a-z_]+)"', open(os.path.join(src, "cfg", "Estimator.cfg")).read()):
    if "`%s`" % name not in doc and "`~%s`" % name not in doc:
        missing.append("reconfigure " + name)
if missing or len(params) < 20:
    sys.exit(DOC + " misses: " + ", ".join(missing) +
             (" (found only %d parameters in the sources)" % len(params) if len(params) < 20 else ""))
print("check_readme_coverage: %d parameters, all fields, launch args and settings documented" % len(params))
