#!/usr/bin/env python3
"""ROS 1 bag fixtures for kccd's log reader tests, written by ROS 1's own rosbag (Debian's
python3-rosbag, python3-sensor-msgs, python3-roslz4).

Usage: write_ros1.py OUT_DIR   (after `node write_mcap.mjs OUT_DIR`: its truth.json lists the
recording, which this script writes again with ROS 1's message classes)

Writes ros1_none.bag, ros1_bz2.bag and ros1_lz4.bag (small chunks, so there are several): the
joint states, images and camera info of truth.json, with the same header stamps and the MCAP
files' log times as the bag's record times. Image bytes follow the rule the MCAP writer used:
byte j of image i is (7 i + j) mod 256.

Also:
  ros1_publishers.bag   the same recording (chunks none) with /joint_states from three nodes, a
                        connection each (callerids /arm_controller, /gripper_controller,
                        /joint_state_publisher: joint state k from node k mod 3), as
                        `rosbag record` writes a topic several nodes publish (a PR2's /tf)
  ros1_big_none.bag     a 100 Hz log of 3,600 mono8 images (1,000 random bytes each) in rosbag's
                        default chunks of 768 KiB, uncompressed (4 MB, as a real log);
  ros1_big_bz2.bag,     the same in 2 MiB chunks, bz2 and lz4 (several compressed blocks per chunk)
  ros1_big_lz4.bag
  big_truth.json        per big message its log time and where its record ends in ros1_big_none.bag
                        (found by its serialized bytes); per big bag its chunks' offsets (from
                        rosbag's own index); for the compressed ones, cuts inside the first chunk
                        with what Python's streaming decoders (bz2.BZ2Decompressor,
                        roslz4.LZ4Decompressor) make of the bytes before each cut, and how many
                        message records end within that
"""
import bz2
import io
import json
import os
import random
import sys

import genpy
import rosbag
import roslz4
from sensor_msgs.msg import CameraInfo, Image, JointState


def stamp(sec, nsec):
    return genpy.Time(sec, nsec)


def log_time(ns):
    ns = int(ns)
    return genpy.Time(ns // 1000000000, ns % 1000000000)


def main():
    out = sys.argv[1]
    with open(os.path.join(out, "truth.json")) as f:
        truth = json.load(f)
    records = []
    for k, j in enumerate(truth["joint_states"]):
        m = JointState()
        m.header.seq = k
        m.header.stamp = stamp(j["stamp_sec"], j["stamp_nanosec"])
        m.header.frame_id = j["frame_id"]
        m.name, m.position, m.velocity, m.effort = j["name"], j["position"], j["velocity"], j["effort"]
        records.append((int(j["log_time_ns"]), 0, "/joint_states", m))
    for i, w in enumerate(truth["images"]):
        m = Image()
        m.header.seq = i
        m.header.stamp = stamp(w["stamp_sec"], w["stamp_nanosec"])
        m.header.frame_id = w["frame_id"]
        m.height, m.width, m.encoding, m.is_bigendian, m.step = w["height"], w["width"], w["encoding"], w["is_bigendian"], w["step"]
        m.data = bytes((i * 7 + j) % 256 for j in range(w["step"] * w["height"]))
        assert sum(m.data) == w["data_sum"]
        records.append((int(w["log_time_ns"]), 1, "/camera/image_raw", m))
    for i, w in enumerate(truth["camera_infos"]):
        m = CameraInfo()
        m.header.stamp = log_time(int(w["log_time_ns"]) - 35000000)
        m.header.frame_id = "camera"
        m.width, m.height, m.distortion_model, m.D, m.K = w["width"], w["height"], w["distortion_model"], w["d"], w["k"]
        records.append((int(w["log_time_ns"]), 2, "/camera/camera_info", m))
    records.sort(key=lambda r: (r[0], r[1]))
    for compression in ("none", "bz2", "lz4"):
        path = os.path.join(out, f"ros1_{compression}.bag")
        with rosbag.Bag(path, "w", compression=compression, chunk_threshold=16 * 1024) as bag:
            for t, _, topic, m in records:
                bag.write(topic, m, t=log_time(t))
    write_publishers(os.path.join(out, "ros1_publishers.bag"), records)
    write_big(out)
    print(f"wrote ros1_none.bag, ros1_bz2.bag, ros1_lz4.bag ({len(records)} messages), ros1_publishers.bag, "
          f"ros1_big_*.bag to {out}")


PUBLISHERS = ["/arm_controller", "/gripper_controller", "/joint_state_publisher"]


def write_as(bag, topic, msg, t, callerid, connections):
    """Writes `msg` on the connection of publisher `callerid`. rosbag record opens a connection per
    publisher; Python's Bag.write keeps one per topic and ignores later connection headers, so the
    topic is pointed at this publisher's connection, or at none for write to open one."""
    if (topic, callerid) in connections:
        bag._topic_connections[topic] = connections[(topic, callerid)]
    else:
        bag._topic_connections.pop(topic, None)
    header = {"topic": topic, "type": msg._type, "md5sum": msg._md5sum, "message_definition": msg._full_text,
              "callerid": callerid, "latching": "0"}
    bag.write(topic, msg, t=t, connection_header=header)
    connections[(topic, callerid)] = bag._topic_connections[topic]


def write_publishers(path, records):
    connections = {}
    with rosbag.Bag(path, "w", chunk_threshold=16 * 1024) as bag:
        k = 0
        for t, _, topic, m in records:
            caller = PUBLISHERS[k % 3] if topic == "/joint_states" else "/camera"
            k += topic == "/joint_states"
            write_as(bag, topic, m, log_time(t), caller, connections)
    # rosbag's own reader sees a connection per publisher, each with its messages.
    text = lambda v: v.decode() if isinstance(v, bytes) else v
    with rosbag.Bag(path) as bag:
        joints = [c for c in bag._connections.values() if c.topic == "/joint_states"]
        assert sorted(text(c.header["callerid"]) for c in joints) == PUBLISHERS
        counts = {}
        for _, _, _, header in bag.read_messages(topics=["/joint_states"], return_connection_header=True):
            counts[text(header["callerid"])] = counts.get(text(header["callerid"]), 0) + 1
        assert counts == {"/arm_controller": 67, "/gripper_controller": 67, "/joint_state_publisher": 66}, counts


def prefix_cuts(bag, compression, serialized):
    """Cuts at 20, 60 and 97 % of the first chunk's compressed bytes: the byte of each cut, how many
    bytes Python's streaming decoder makes of what is before it, and how many message records end
    within those (each found in the whole chunk by its serialized bytes)."""
    bag._file.seek(bag._chunks[0].pos)
    header = bag._reader.read_chunk_header()
    bag._file.seek(header.data_pos)
    data = bag._file.read(header.compressed_size)
    whole = bz2.decompress(data) if compression == "bz2" else roslz4.decompress(data)
    ends, at = [], 0
    for b in serialized:
        found = whole.find(b, at)
        if found < 0:
            break
        at = found + len(b)
        ends.append(at)
    cuts = []
    for fraction in (0.2, 0.6, 0.97):
        keep = int(len(data) * fraction)
        decoder = bz2.BZ2Decompressor() if compression == "bz2" else roslz4.LZ4Decompressor()
        prefix = len(decoder.decompress(data[:keep]))
        cuts.append({"cut": header.data_pos + keep, "decompressed": prefix, "chunk_size": header.uncompressed_size,
                     "messages": sum(e <= prefix for e in ends)})
    return cuts


def write_big(out):
    rng = random.Random(2024)
    messages = []
    for k in range(3600):
        t = 1700000000 * 10**9 + k * 10**7
        m = Image()
        m.header.seq = k
        m.header.stamp = log_time(t - 10**6)
        m.header.frame_id = "camera"
        m.height, m.width, m.encoding, m.is_bigendian, m.step = 25, 40, "mono8", 0, 40
        m.data = rng.randbytes(1000)  # random: the compressed chunks hold several blocks
        messages.append((t, m))
    serialized = []
    for _, m in messages:
        buf = io.BytesIO()
        m.serialize(buf)
        serialized.append(buf.getvalue())
    truth = {"messages": [], "bags": {}}
    for compression, threshold in (("none", 768 * 1024), ("bz2", 2 << 20), ("lz4", 2 << 20)):
        name = f"ros1_big_{compression}.bag"
        path = os.path.join(out, name)
        with rosbag.Bag(path, "w", compression=compression, chunk_threshold=threshold) as bag:
            for t, m in messages:
                bag.write("/camera/image_mono", m, t=log_time(t))
        with rosbag.Bag(path) as bag:
            assert bag.get_message_count() == len(messages)
            truth["bags"][name] = {"chunks": [c.pos for c in bag._chunks], "size": os.path.getsize(path)}
            if compression != "none":
                truth["bags"][name]["cuts"] = prefix_cuts(bag, compression, serialized)
    # Where each message record ends in the uncompressed bag: its data (the record's last part) found
    # by the message's own serialized bytes, in order.
    with open(os.path.join(out, "ros1_big_none.bag"), "rb") as f:
        data = f.read()
    end = 0
    for (t, _), b in zip(messages, serialized):
        at = data.find(b, end)
        assert at >= 0
        end = at + len(b)
        truth["messages"].append({"log_time_ns": str(t), "record_end": end})
    with open(os.path.join(out, "big_truth.json"), "w") as f:
        json.dump(truth, f, indent=0)


main()
