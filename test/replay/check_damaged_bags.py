#!/usr/bin/python3
"""drivetrain_replay on truncated and corrupt bags, made here from the bundled torque_ripple.bag
(one uncompressed chunk) and from an LZ4 copy with 16 KiB chunks written by python rosbag.

For every damaged bag: exit code 4 (docs/replay_exit_codes.md); the error on stderr and the status
in summary.json name the file and the expected byte offset; the outputs are valid (the output bag
is closed and indexed, python rosbag opens it, and it and the CSV file hold as many transmission
error messages as the counters say); and the torque inputs accepted equal the torque messages
before the damage. Those expectations come from python rosbag reading the ORIGINAL bag: its index
gives every message's chunk and offset, its own record reader the record's end, so a message
counts when its record (uncompressed) or its whole chunk (compressed) lies before the damage.
A text file is refused with exit 1 naming it; the intact bag gives exit 0 and status "ok".

Damage that crashed librosbag or made roscpp_serialization allocate gigabytes, each read up to the
damage instead (exit 4, file and offset named): an index entry pointing past its chunk, a
JointState whose name[] claims 4294967280 strings (read through the index, and without it), and
60 seeded 16-byte flips over a rig-sim bag with encoders and an LZ4 copy of it: no signal, an exit
code of the table, summary.json valid JSON, the file named on exit 4, and the largest resident
size of any replay under 1 GiB.

usage: check_damaged_bags.py BIN_DIR SOURCE_DIR WORK_DIR   (with the devel space's env.sh)"""
import json
import os
import random
import resource
import shutil
import struct
import subprocess
import sys

import rosbag
import rosbag.bag as rb

bin_dir, src, work = sys.argv[1:4]
replay = os.path.join(bin_dir, "drivetrain_replay")
config = os.path.join(src, "config/gearboxes/seed_servo.yaml")
params = os.path.join(src, "config/stiffness_estimator.yaml")
original = os.path.join(src, "test/data/torque_ripple.bag")
failures = []


def layout(path):
    """Python rosbag's view of a closed bag: its chunks (pos, data start, data end, compression) and
    its messages (topic, record time, record start, end of the record or of its compressed chunk)."""
    bag = rosbag.Bag(path)
    f = bag._file
    chunks = {}
    for c in bag._chunks:
        f.seek(c.pos)
        h = bag._reader.read_chunk_header()
        chunks[c.pos] = (c.pos, h.data_pos, h.data_pos + h.compressed_size, h.compression)
    messages = []
    for conn_id, entries in bag._connection_indexes.items():
        topic = bag._connections[conn_id].topic
        for e in entries:
            pos, data_pos, data_end, compression = chunks[e.chunk_pos]
            start = end = None
            if compression == "none":
                start = data_pos + e.offset
                f.seek(start)
                rb._read_header(f)
                rb._skip_sized(f)
                end = f.tell()
            messages.append({"topic": topic, "time": e.time, "chunk": pos, "offset": e.offset, "start": start,
                             "end": end if end is not None else data_end})
    messages.sort(key=lambda m: (m["chunk"], m["offset"]))  # file order
    times = [m["time"] for m in messages]
    assert times == sorted(times), "the test assumes file order is record-time order (rosbag::View's order)"
    return bag._index_data_pos, sorted(chunks.values()), messages


def torque_before(messages, offset):
    return sum(1 for m in messages if m["topic"] == "/torque" and m["end"] <= offset)


def patch(path, offset, data):
    with open(path, "r+b") as f:
        f.seek(offset)
        f.write(data)


def prefix(source, n, name):
    path = os.path.join(work, name)
    with open(source, "rb") as f, open(path, "wb") as out:
        out.write(f.read(n))
    return path


def copy(source, name):
    path = os.path.join(work, name)
    shutil.copyfile(source, path)
    return path


def field_value(path, name, start):
    """Offset of a record header field's value (b'name=' searched from `start`)."""
    with open(path, "rb") as f:
        data = f.read()
    return data.index(name + b"=", start) + len(name) + 1


def run(bag, name, plots=False):
    report = os.path.join(work, name + ".report")
    cmd = [replay, "--bag", bag, "--config", config, "--params", params, "--report", report]
    p = subprocess.run(cmd + ([] if plots else ["--no-plots"]), capture_output=True, text=True)
    return p, report


def check_damaged(name, bag, offset, torque, plots=False):
    p, report = run(bag, name, plots)
    bad = []
    if p.returncode != 4:
        bad.append("exit code %d, expected 4 (stderr: %s)" % (p.returncode, p.stderr.strip()))
    where = "'%s' at byte %d:" % (bag, offset)
    if where not in p.stderr:
        bad.append("stderr does not name %s: %s" % (where, p.stderr.strip()))
    try:
        s = json.load(open(os.path.join(report, "summary.json")))
        c = s["counters"]
        if not s["status"].startswith("incomplete: " + where):
            bad.append("status %r" % s["status"])
        if s["damage"]["offset"] != offset or s["damage"]["messages_before"] != s["messages"]:
            bad.append("damage %r" % s["damage"])
        if c["accepted_torque"] != torque:
            bad.append("accepted_torque %d, expected %d" % (c["accepted_torque"], torque))
        out = rosbag.Bag(os.path.join(report, "outputs.bag"))  # raises if not closed (no index)
        te = out.get_message_count("/transmission_error")
        with open(os.path.join(report, "csv/transmission_error.csv")) as f:
            rows = sum(1 for _ in f) - 1
        if not te == rows == c["transmission_error_published"]:
            bad.append("outputs: bag %d, csv %d, counter %d" % (te, rows, c["transmission_error_published"]))
        if plots:
            with open(os.path.join(report, "report.md")) as f:
                top = f.read().split("\n")[:5]
            if not any(line.startswith("**Incomplete replay**") for line in top) or not any(where in line for line in top):
                bad.append("report.md does not say incomplete at the top: %r" % top)
    except Exception as e:  # noqa: BLE001 - any missing or unreadable output is the failure to report
        bad.append("outputs: %s: %s" % (type(e).__name__, e))
    print("%-26s exit %d, offset %d, torque %d: %s" % (name, p.returncode, offset, torque, "; ".join(bad) or "ok"))
    if bad:
        failures.append(name)


def index_entries(path, chunk_end, topic):
    """(file offset of each index entry's 4-byte chunk offset, record time) for `topic` in the index
    data records that follow the chunk ending at chunk_end."""
    bag = rosbag.Bag(path)
    conns = [c.id for c in bag._connections.values() if c.topic == topic]
    f = bag._file
    f.seek(chunk_end)
    out = []
    while True:
        pos = f.tell()
        try:
            header = rb._read_header(f)
        except Exception:  # noqa: BLE001 - past the index data records
            break
        if header.get("op") != b"\x04":
            break
        conn, count = struct.unpack("<I", header["conn"])[0], struct.unpack("<I", header["count"])[0]
        data_len = struct.unpack("<I", f.read(4))[0]
        start = f.tell()
        if conn in conns:
            for i in range(count):
                sec, nsec = struct.unpack_from("<II", open(path, "rb").read()[start + 12 * i:start + 12 * i + 8])
                out.append((start + 12 * i + 8, (sec, nsec)))
        f.seek(start + data_len)
        del pos
    bag.close()
    return out


def joint_state_bomb(source, name):
    """A copy of `source` whose 1001st /joint_states message's name[] length is 0xFFFFFFF0 (uncompressed
    chunks): returns its path and that message's record offset."""
    _, _, msgs = layout(source)
    victim = [m for m in msgs if m["topic"] == "/joint_states"][1000]
    path = copy(source, name)
    with open(path, "rb") as f:
        f.seek(victim["start"])
        header_len = struct.unpack("<I", f.read(4))[0]
        f.seek(victim["start"] + 4 + header_len + 4 + 12)  # the message: seq, stamp, then frame_id
        frame_len = struct.unpack("<I", f.read(4))[0]
        names_at = f.tell() + frame_len
    patch(path, names_at, struct.pack("<I", 0xFFFFFFF0))
    return path, victim


def check_bomb(name, bag, offset, torque):
    p, report = run(bag, name)
    ok = p.returncode == 4 and ("'%s' at byte %d:" % (bag, offset)) in p.stderr and "claims 4294967280 elements" in p.stderr
    s = json.load(open(os.path.join(report, "summary.json")))
    ok = ok and s["counters"]["accepted_torque"] == torque
    print("%-26s exit %d: %s" % (name, p.returncode, "ok" if ok else p.stderr.strip()[-600:]))
    if not ok:
        failures.append(name)


def seeded_flips(bags, cases):
    """`cases` replays of copies of `bags` with 16 bytes overwritten at a seeded offset each."""
    rng = random.Random(20261127)
    bad = []
    for n in range(cases):
        source = bags[n % len(bags)]
        size = os.path.getsize(source)
        offset = rng.randrange(0, size - 16)
        path = copy(source, "flip_%02d.bag" % n)
        patch(path, offset, bytes(rng.randrange(256) for _ in range(16)))
        p, report = run(path, "flip_%02d" % n)
        why = []
        if p.returncode not in (0, 1, 3, 4, 5):
            why.append("exit %d" % p.returncode)
        if p.returncode == 4 and "'%s' at byte " % path not in p.stderr:
            why.append("exit 4 without the file and offset")
        if p.returncode != 1:
            try:
                json.load(open(os.path.join(report, "summary.json")))
            except Exception as e:  # noqa: BLE001
                why.append("summary.json: %s" % e)
        elif "'%s'" % path not in p.stderr:
            why.append("refused without naming the file: %s" % p.stderr.strip()[-200:])
        if why:
            bad.append("flip %d at byte %d of %s: %s" % (n, offset, os.path.basename(source), ", ".join(why)))
        else:
            os.remove(path)
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
    print("%-26s %d cases, largest resident size %.0f MiB: %s"
          % ("seeded_byte_flips", cases, peak / 2**20, "; ".join(bad) or "ok"))
    if bad or peak > 2**30:
        failures.append("seeded_byte_flips")


def raw_record(fields, data):
    header = b"".join(struct.pack("<I", len(k) + 1 + len(v)) + k + b"=" + v for k, v in fields)
    return struct.pack("<I", len(header)) + header + struct.pack("<I", len(data)) + data


def duplicate_connection_bag(path):
    """Bag format 2.0 written byte by byte: five JointStates on connection 0 in one chunk, the third
    index entry pointing far past the chunk, and an index that defines connection 0 twice, first as
    /joint_states (librosbag keeps the first) and then as /other. A check that took the last
    definition skipped /joint_states' entries and let librosbag parse a header at the wild offset."""
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String
    import io

    def connection(cid, topic, cls):
        header = [(b"topic", topic), (b"type", cls._type.encode()), (b"md5sum", cls._md5sum.encode()),
                  (b"message_definition", cls._full_text.encode())]
        data = b"".join(struct.pack("<I", len(k) + 1 + len(v)) + k + b"=" + v for k, v in header)
        return raw_record([(b"op", b"\x07"), (b"conn", struct.pack("<I", cid)), (b"topic", topic)], data)
    chunk, entries = connection(0, b"/joint_states", JointState), []
    for i in range(1, 6):
        m = JointState(name=["pinion", "gear"], position=[0.0, 0.0])
        m.header.stamp.secs, m.header.stamp.nsecs = 1767225600, i * 1000000
        buf = io.BytesIO()
        m.serialize(buf)
        entries.append((1767225600, i * 1000000, 0x7FF00000 if i == 3 else len(chunk)))
        chunk += raw_record([(b"op", b"\x02"), (b"conn", struct.pack("<I", 0)),
                             (b"time", struct.pack("<II", 1767225600, i * 1000000))], buf.getvalue())

    def bag_header(index_pos):
        return raw_record([(b"op", b"\x03"), (b"index_pos", struct.pack("<Q", index_pos)), (b"conn_count", struct.pack("<I", 2)),
                           (b"chunk_count", struct.pack("<I", 1))], b"")
    out = b"#ROSBAG V2.0\n" + bag_header(0)
    chunk_pos = len(out)
    out += raw_record([(b"op", b"\x05"), (b"compression", b"none"), (b"size", struct.pack("<I", len(chunk)))], chunk)
    out += raw_record([(b"op", b"\x04"), (b"ver", struct.pack("<I", 1)), (b"conn", struct.pack("<I", 0)),
                       (b"count", struct.pack("<I", len(entries)))], b"".join(struct.pack("<III", *e) for e in entries))
    index_pos = len(out)
    out += connection(0, b"/joint_states", JointState) + connection(0, b"/other", String)
    out += raw_record([(b"op", b"\x06"), (b"ver", struct.pack("<I", 1)), (b"chunk_pos", struct.pack("<Q", chunk_pos)),
                       (b"start_time", struct.pack("<II", 1767225600, 1000000)),
                       (b"end_time", struct.pack("<II", 1767225600, 5000000)), (b"count", struct.pack("<I", 1))],
                      struct.pack("<II", 0, len(entries)))
    out = b"#ROSBAG V2.0\n" + bag_header(index_pos) + out[len(b"#ROSBAG V2.0\n") + len(bag_header(0)):]
    with open(path, "wb") as f:
        f.write(out)
    return chunk_pos


def check_intact(name, bag, torque, joint_states=0):
    p, report = run(bag, name)
    ok = p.returncode == 0
    try:
        s = json.load(open(os.path.join(report, "summary.json")))
        c = s["counters"]
        ok = ok and s["status"] == "ok" and c["accepted_torque"] == torque and c["accepted_joint_states"] == joint_states
    except Exception:  # noqa: BLE001
        ok = False
    print("%-26s exit %d: %s" % (name, p.returncode, "ok" if ok else p.stderr.strip()[-400:]))
    if not ok:
        failures.append(name)


def main():
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    index_pos, chunks, msgs = layout(original)
    torque = [m for m in msgs if m["topic"] == "/torque"]
    assert len(torque) == 2000 and len(chunks) == 1 and chunks[0][3] == "none"
    first, mid = torque[40], torque[1200]

    # Truncations of the uncompressed bag: inside the first chunk, mid-file, just before the index.
    check_damaged("truncated_first_chunk", prefix(original, first["start"] + 20, "t_first.bag"), first["start"],
                  torque_before(msgs, first["start"]))
    check_damaged("truncated_mid_file", prefix(original, mid["start"] + 20, "t_mid.bag"), mid["start"],
                  torque_before(msgs, mid["start"]), plots=True)
    check_damaged("truncated_before_index", prefix(original, index_pos, "t_index.bag"), index_pos, 2000)

    # A recording cut by a power loss as rosbag record leaves it: the bag header's index_pos and the
    # open chunk's sizes still hold the zeros written when they were opened.
    unclosed = prefix(original, mid["start"] + 20, "unclosed.bag")
    patch(unclosed, field_value(unclosed, b"index_pos", 0), bytes(8))
    chunk_pos, data_pos = chunks[0][0], chunks[0][1]
    patch(unclosed, field_value(unclosed, b"size", chunk_pos), bytes(4))
    patch(unclosed, data_pos - 4, bytes(4))
    check_damaged("unclosed_recording", unclosed, mid["start"], torque_before(msgs, mid["start"]))

    # Garbage over a message record's header inside the chunk: rosbag::View fails there.
    garbage = copy(original, "garbage_record.bag")
    patch(garbage, mid["start"], b"GARBAGE!GARBAGE!")
    check_damaged("garbage_record", garbage, mid["start"], torque_before(msgs, mid["start"]))

    # A damaged bag header: nothing can be read.
    header = copy(original, "bad_header.bag")
    patch(header, field_value(header, b"op", 0) - 3, b"xx")  # "op=" -> "xx=": no op field
    check_damaged("bad_bag_header", header, 13, 0, plots=True)

    # LZ4 chunks: truncated inside one, and garbage inside one's compressed data.
    lz4 = os.path.join(work, "lz4.bag")
    with rosbag.Bag(original) as i, rosbag.Bag(lz4, "w", compression="lz4", chunk_threshold=16 * 1024) as o:
        for topic, raw, t, conn in i.read_messages(raw=True, return_connection_header=True):
            o.write(topic, raw, t, raw=True, connection_header=conn)
    _, lz4_chunks, lz4_msgs = layout(lz4)
    assert len(lz4_chunks) >= 6 and all(c[3] == "lz4" for c in lz4_chunks)
    victim = lz4_chunks[len(lz4_chunks) // 2]
    check_damaged("lz4_truncated_in_chunk", prefix(lz4, (victim[1] + victim[2]) // 2, "lz4_t.bag"), victim[0],
                  torque_before(lz4_msgs, victim[0]))
    corrupt = copy(lz4, "lz4_corrupt.bag")
    patch(corrupt, (victim[1] + victim[2]) // 2, b"GARBAGE!GARBAGE!")
    check_damaged("lz4_corrupt_chunk", corrupt, victim[0], torque_before(lz4_msgs, victim[0]))

    # An index entry of the uncompressed bag pointing past its chunk: rosbag::View parsed a record
    # header there (SIGSEGV in Bag::readHeaderFromBuffer); the view now stops before that message.
    entries = index_entries(original, chunks[0][2], "/torque")
    pointer, _ = entries[1200]
    wild = copy(original, "wild_index_entry.bag")
    patch(wild, pointer, struct.pack("<I", 0xFFFFFF00))
    check_damaged("wild_index_entry", wild, chunks[0][0], 1200)

    # A JointState's name[] length damaged to 0xFFFFFFF0 in a rig-sim bag with encoders, read
    # through the index and as a recording cut short there (no index): roscpp_serialization resized
    # the array before checking the bytes. Now refused before it deserializes, at the record.
    sim = os.path.join(work, "sim.bag")
    subprocess.run([os.path.join(bin_dir, "drivetrain_rig_sim"), "--scenario", "torque_ripple", "--config", config,
                    "--out", sim, "--duration", "2"], check=True, capture_output=True)
    _, sim_chunks, sim_msgs = layout(sim)
    bomb, victim = joint_state_bomb(sim, "joint_state_bomb.bag")
    before = sum(1 for m in sim_msgs if m["topic"] == "/torque" and m["time"] < victim["time"])
    check_bomb("joint_state_bomb", bomb, victim["start"], before)
    cut = prefix(bomb, victim["end"] + 100, "joint_state_bomb_cut.bag")
    check_bomb("joint_state_bomb_unindexed", cut, victim["start"],
               sum(1 for m in sim_msgs if m["topic"] == "/torque" and m["end"] <= victim["start"]))

    # Seeded byte flips over the rig-sim bag and an LZ4 copy with 16 KiB chunks.
    sim_lz4 = os.path.join(work, "sim_lz4.bag")
    with rosbag.Bag(sim) as i, rosbag.Bag(sim_lz4, "w", compression="lz4", chunk_threshold=16 * 1024) as o:
        for topic, raw, t, conn in i.read_messages(raw=True, return_connection_header=True):
            o.write(topic, raw, t, raw=True, connection_header=conn)
    seeded_flips([sim, sim_lz4], 60)

    # A connection defined twice in the index (librosbag keeps the first): the check reads the
    # topic the view will visit, so the wild entry behind it stops the replay instead of a SIGSEGV.
    dup = os.path.join(work, "duplicate_connection.bag")
    dup_chunk = duplicate_connection_bag(dup)
    p, report = run(dup, "duplicate_connection")
    ok = p.returncode == 4 and ("'%s' at byte %d:" % (dup, dup_chunk)) in p.stderr
    print("%-26s exit %d: %s" % ("duplicate_connection", p.returncode, "ok" if ok else p.stderr.strip()[-400:]))
    if not ok:
        failures.append("duplicate_connection")

    # The first torque record damaged: the summary says the topic is in the bag and was cut off.
    first_bad = copy(original, "first_torque_damaged.bag")
    patch(first_bad, torque[0]["start"], b"GARBAGE!GARBAGE!")
    p, report = run(first_bad, "first_torque_damaged")
    ok = p.returncode == 4 and "2000 in the bag, none read before the damage" in p.stderr
    print("%-26s exit %d: %s" % ("first_torque_damaged", p.returncode, "ok" if ok else p.stderr.strip()[-400:]))
    if not ok:
        failures.append("first_torque_damaged")

    # Valid bags the check must pass whole: the rig-sim bag with LZ4 and with bz2 chunks of 16 KiB,
    # and a bz2 bag holding an 8 MiB message of zeros (bz2 expands it more than a million-fold).
    from std_msgs.msg import UInt8MultiArray
    sim_bz2 = os.path.join(work, "sim_bz2.bag")
    zeros = os.path.join(work, "zeros_bz2.bag")
    with rosbag.Bag(sim) as i, rosbag.Bag(sim_bz2, "w", compression="bz2", chunk_threshold=16 * 1024) as o, \
            rosbag.Bag(zeros, "w", compression="bz2") as z:
        for n, (topic, raw, t, conn) in enumerate(i.read_messages(raw=True, return_connection_header=True)):
            o.write(topic, raw, t, raw=True, connection_header=conn)
            z.write(topic, raw, t, raw=True, connection_header=conn)
            if n == 100:
                z.write("/map", UInt8MultiArray(data=bytes(8 << 20)), t)
    sim_torque = sum(1 for m in sim_msgs if m["topic"] == "/torque")
    sim_joints = sum(1 for m in sim_msgs if m["topic"] == "/joint_states")
    check_intact("intact_lz4_chunks", sim_lz4, sim_torque, sim_joints)
    check_intact("intact_bz2_chunks", sim_bz2, sim_torque, sim_joints)
    check_intact("intact_bz2_8_mib_of_zeros", zeros, sim_torque, sim_joints)

    # Not a bag at all: refused, naming the file.
    text = os.path.join(work, "notes.txt")
    with open(text, "w") as f:
        f.write("torque log, not a bag\n")
    p, _ = run(text, "not_a_bag")
    ok = p.returncode == 1 and "'%s'" % text in p.stderr
    print("%-26s exit %d: %s" % ("not_a_bag", p.returncode, "ok" if ok else p.stderr.strip()))
    if not ok:
        failures.append("not_a_bag")

    # The intact bag: status ok, exit 0.
    p, report = run(original, "intact")
    s = json.load(open(os.path.join(report, "summary.json")))
    ok = p.returncode == 0 and s["status"] == "ok" and "damage" not in s and s["counters"]["accepted_torque"] == 2000
    print("%-26s exit %d, status %s: %s" % ("intact", p.returncode, s["status"], "ok" if ok else "unexpected"))
    if not ok:
        failures.append("intact")

    if failures:
        sys.exit("check_damaged_bags: failed: %s" % ", ".join(failures))
    print("check_damaged_bags: every damaged bag read up to its damage, named, flagged and closed")


if __name__ == "__main__":
    main()
