#!/usr/bin/python3
"""The plotting entry points name real, flat, numeric message fields: every topic path in
config/drivetrain.perspective (rqt_plot) and every `rostopic echo -p` / PlotJuggler field that
docs/ros_api.md (section "Plotting") or README.md names as `/topic/field` must exist in msg/*.msg
as a scalar number (rqt_plot plots float(field)).
usage: check_plot_fields.py SOURCE_DIR"""
import ast
import json
import os
import re
import sys

src = sys.argv[1]
TOPIC_TYPES = {"/transmission_error": "TransmissionError", "/stiffness": "Stiffness", "/resonance": "Resonance",
               "/te_spectrum": "SpectralPeaks", "/measured_te": "MeasuredTe", "/calibration": "Calibration",
               "/mesh_period_stats": "MeshPeriodStats"}
NUMERIC = {"float64", "float32", "int32", "uint32", "int64", "uint64", "bool", "uint8", "int8"}


def fields(msg):
    out = {}
    for line in open(os.path.join(src, "msg", msg + ".msg")):
        line = line.split("#")[0].strip()
        if line:
            t, name = line.split()[:2]
            out[name] = t
    return out


perspective = json.load(open(os.path.join(src, "config", "drivetrain.perspective")))
groups = perspective["groups"]["pluginmanager"]["groups"]
paths = []
for name, group in groups.items():
    if name.startswith("plugin__rqt_plot__Plot__"):
        paths += ast.literal_eval(group["groups"]["plugin"]["keys"]["topics"]["repr"])
PATH_RE = r"`(/(?:transmission_error|stiffness|resonance|te_spectrum|measured_te|calibration|mesh_period_stats)/[a-z0-9_]+)`"
documented = re.findall(PATH_RE, open(os.path.join(src, "docs", "ros_api.md")).read())
if not documented:
    sys.exit("docs/ros_api.md lists no plot paths (section \"Plotting\")")
paths += documented + re.findall(PATH_RE, open(os.path.join(src, "README.md")).read())
bad = []
for p in paths:
    topic, field = p.rsplit("/", 1)
    t = fields(TOPIC_TYPES[topic]).get(field)
    if t not in NUMERIC:
        bad.append("%s (%s)" % (p, t))
if bad or not paths:
    sys.exit("not a flat numeric field: " + ", ".join(bad))
print("check_plot_fields: %d plot paths, all flat numeric fields" % len(paths))
