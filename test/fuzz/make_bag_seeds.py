#!/usr/bin/python3
"""Writes the seed bags of the bag fuzz target (test/data/fuzz/bag/*.bag): small rig recordings
(torque, preload and joint_states, 1 ms apart, on a few chunks; the Preload message class from
the devel space, so build first) written by python rosbag with each
chunk compression, and a recording cut short (no index); two with accelerometer blocks
(VibrationBlock, 16 frames at 16 kHz, 1 ms apart beside 1 kHz torque): valid_vibration.bag, and
vibration_broken_blocks.bag whose blocks break the rules (BROKEN_BLOCKS; the replay's verdict on
them: test/replay/check_foreign_bags.py). The bag header's 4 KiB of padding is
removed (index_pos and the chunk infos' chunk_pos moved with it), so the mutations land on records,
not on padding. Run with Debian's python3 from anywhere; the seeds are committed, this script says
what they hold."""
import os
import struct
import sys

import rosbag
from geometry_msgs.msg import WrenchStamped
from sensor_msgs.msg import JointState
import rospy

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "data", "fuzz", "bag")


def preload_classes():
    """drivetrain_stiffness/Preload and BearingPreload from the package's devel space (scripts/build)."""
    sys.path.insert(0, os.path.join(HERE, "..", "..", "devel", "lib", "python3", "dist-packages"))
    from drivetrain_stiffness.msg import BearingPreload, Preload
    return Preload, BearingPreload


def write(path, compression):
    classes = preload_classes()
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=1500) as bag:
        t0 = rospy.Time(1767225600, 0)
        p = classes[0]()
        p.header.stamp = t0
        for name in ("pinion_bearing", "gear_bearing"):
            b = classes[1]()
            b.name, b.axial_preload, b.radial_preload = name, 1000.0, 0.0
            p.bearings.append(b)
        bag.write("/preload", p, t0)
        for i in range(1, 21):
            t = t0 + rospy.Duration(0, i * 1000000)
            w = WrenchStamped()
            w.header.stamp, w.header.seq, w.header.frame_id = t, i, "pinion"
            w.wrench.torque.z = 0.5 + 0.05 * (i % 3)
            bag.write("/torque", w, t)
            j = JointState()
            j.header.stamp, j.header.seq = t, i
            j.name = ["pinion", "gear"]
            j.position = [0.1047 * i * 1e-3, -0.05235 * i * 1e-3]
            j.velocity = [104.7, -52.35]
            bag.write("/joint_states", j, t)


def vibration_class():
    sys.path.insert(0, os.path.join(HERE, "..", "..", "devel", "lib", "python3", "dist-packages"))
    from drivetrain_stiffness.msg import VibrationBlock
    return VibrationBlock


GOOD = {"rate": 16000.0, "frames": 16, "channels": ["pinion_bearing", "gear_bearing"]}
# (ms after the start, header.seq, changes to a good block): each line one rule of docs/vibration.md
# "Input"; the replay accepts 6 and refuses 6 (test/replay/check_foreign_bags.py).
BROKEN_BLOCKS = [
    (1, 1, {}),
    (2, 2, {}),
    (4, 4, {}),                                     # seq 3 lost: dropped, a gap
    (5, 4, {}),                                     # seq 4 again: overlaps, refused
    (5, 5, {"nan": 7}),                             # a NaN sample: refused
    (6, 6, {"short": 1}),                           # one value short of whole frames: refused
    (7, 7, {"rate": 0.0}),                          # zero sample rate: refused
    (8, 8, {"rate": -16000.0}),                     # negative sample rate: refused
    (9, 9, {"channels": []}),                       # no channels: refused
    (10, 10, {"channels": ["pinion_bearing", "gear_bearing", "tacho"]}),  # unknown channel: counted
    (11, 11, {"channels": ["pinion_bearing", "gear_bearing", "tacho"], "rate": 8000.0, "frames": 8}),  # new rate
    (12, 12, {"channels": ["pinion_bearing", "gear_bearing", "tacho"], "rate": 8000.0, "frames": 8}),
]


def write_vibration(path, blocks):
    """Preload, torque at 1 kHz over 14 ms, and the accelerometer blocks (ms, seq, changes)."""
    Preload, BearingPreload = preload_classes()
    VibrationBlock = vibration_class()
    with rosbag.Bag(path, "w", compression="none", chunk_threshold=1500) as bag:
        t0 = rospy.Time(1767225600, 0)
        p = Preload()
        p.header.stamp = t0
        for name in ("pinion_bearing", "gear_bearing"):
            b = BearingPreload()
            b.name, b.axial_preload, b.radial_preload = name, 1000.0, 0.0
            p.bearings.append(b)
        bag.write("/preload", p, t0)
        messages = []
        for i in range(1, 15):
            t = t0 + rospy.Duration(0, i * 1000000)
            w = WrenchStamped()
            w.header.stamp, w.header.seq, w.header.frame_id = t, i, "pinion"
            w.wrench.torque.z = 0.5
            messages.append(("/torque", w, t))
        for ms, seq, change in blocks:
            spec = dict(GOOD, **change)
            t = t0 + rospy.Duration(0, int(ms * 1000000) + 500000)
            v = VibrationBlock()
            v.header.stamp, v.header.seq = t, seq
            v.sample_rate = spec["rate"]
            v.channels = list(spec["channels"])
            n = spec["frames"] * len(v.channels)
            v.data = [0.5 * ((i * 7) % 11 - 5) for i in range(n)]
            if "nan" in spec:
                v.data[spec["nan"]] = float("nan")
            if "short" in spec:
                v.data = v.data[:-spec["short"]]
            messages.append(("/vibration", v, t))
        for topic, m, t in sorted(messages, key=lambda x: x[2].to_nsec()):
            bag.write(topic, m, t)


def compact(path):
    """Drops the bag header record's padding, moving every absolute offset after it."""
    data = bytearray(open(path, "rb").read())
    start = 13  # after "#ROSBAG V2.0\n"
    header_len = struct.unpack_from("<I", data, start)[0]
    data_len_at = start + 4 + header_len
    pad = struct.unpack_from("<I", data, data_len_at)[0]
    header = bytes(data[start + 4:data_len_at])
    index_pos_at = start + 4 + header.index(b"index_pos=") + len(b"index_pos=")
    index_pos = struct.unpack_from("<Q", data, index_pos_at)[0]
    struct.pack_into("<Q", data, index_pos_at, index_pos - pad)
    struct.pack_into("<I", data, data_len_at, 0)
    del data[data_len_at + 4:data_len_at + 4 + pad]
    at = index_pos - pad  # chunk info records' chunk_pos
    while True:
        at = data.find(b"chunk_pos=", at)
        if at < 0:
            break
        struct.pack_into("<Q", data, at + 10, struct.unpack_from("<Q", data, at + 10)[0] - pad)
        at += 18
    open(path, "wb").write(bytes(data))


def main():
    os.makedirs(OUT, exist_ok=True)
    for compression in ("none", "lz4", "bz2"):
        path = os.path.join(OUT, "valid_%s.bag" % compression)
        write(path, compression)
        compact(path)
        rosbag.Bag(path).close()  # python rosbag reads the compacted bag through its index
    for name, blocks in (("valid_vibration.bag", [(ms, ms, {}) for ms in range(1, 9)]),
                         ("vibration_broken_blocks.bag", BROKEN_BLOCKS)):
        path = os.path.join(OUT, name)
        write_vibration(path, blocks)
        compact(path)
        rosbag.Bag(path).close()
    # A recording cut short: the uncompressed bag without its index and the last chunk's tail.
    whole = open(os.path.join(OUT, "valid_none.bag"), "rb").read()
    index_pos = struct.unpack_from("<Q", whole, whole.index(b"index_pos=") + 10)[0]
    open(os.path.join(OUT, "invalid_cut_short.bag"), "wb").write(whole[:index_pos - 40])


if __name__ == "__main__":
    main()
