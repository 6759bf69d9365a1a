#!/usr/bin/env python3
"""ROS 1 bag fixtures for kccd's log reader tests, written by ROS 1's own rosbag (Debian's
python3-rosbag, python3-sensor-msgs, python3-roslz4).

Usage: write_ros1.py OUT_DIR   (after `node write_mcap.mjs OUT_DIR`: its truth.json lists the
recording, which this script writes again with ROS 1's message classes)

Writes ros1_none.bag, ros1_bz2.bag and ros1_lz4.bag (small chunks, so there are several): the
joint states, images and camera info of truth.json, with the same header stamps and the MCAP
files' log times as the bag's record times. Image bytes follow the rule the MCAP writer used:
byte j of image i is (7 i + j) mod 256.
"""
import json
import os
import sys

import genpy
import rosbag
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
    print(f"wrote ros1_none.bag, ros1_bz2.bag, ros1_lz4.bag ({len(records)} messages) to {out}")


main()
