#!/usr/bin/env python3
"""rosbag2 sqlite3 fixtures for kccd's log reader tests, written with Python's sqlite3.

Usage: write_db3.py OUT_DIR   (after `node write_mcap.mjs OUT_DIR`, whose messages.jsonl and
definitions.json hold the same serialized messages as its MCAP files)

Writes, in rosbag2's own table layout:
  humble.db3     schema version 3 (Humble): topics, messages; no message definitions stored
  jazzy.db3      schema version 4 (Jazzy): also message_definitions (the ros2msg text per type)
  split/         a bag folder: metadata.yaml listing split_0.db3 and split_1.db3 (Humble layout),
                 the messages divided between them at half
Rows are inserted topic by topic, not in timestamp order: a reader must order them itself.
"""
import base64
import json
import os
import sqlite3
import sys


def write(path, messages, definitions, with_definitions):
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    c = db.cursor()
    c.execute("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL)")
    c.execute("INSERT INTO schema VALUES(?, ?)", (4 if with_definitions else 3, "jazzy" if with_definitions else "humble"))
    c.execute("CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL)")
    topics_sql = ("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
                  "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL"
                  + (", type_description_hash TEXT NOT NULL" if with_definitions else "") + ")")
    c.execute(topics_sql)
    c.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    c.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
    if with_definitions:
        c.execute("CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, encoding TEXT NOT NULL, "
                  "encoded_message_definition TEXT NOT NULL, type_description_hash TEXT NOT NULL)")
        for t, text in definitions.items():
            c.execute("INSERT INTO message_definitions(topic_type, encoding, encoded_message_definition, type_description_hash) "
                      "VALUES(?, 'ros2msg', ?, 'RIHS01_0')", (t, text))
    ids = {}
    # Topic ids from 10 up, in reverse order of first appearance: ids are not positions.
    order = []
    for m in messages:
        if m["topic"] not in order:
            order.append(m["topic"])
    for k, topic in enumerate(reversed(order)):
        t = next(m["type"] for m in messages if m["topic"] == topic)
        ids[topic] = 10 + k
        row = (ids[topic], topic, t, "cdr", "- history: 3\n  depth: 0\n") + (("RIHS01_0",) if with_definitions else ())
        c.execute("INSERT INTO topics VALUES(" + ",".join("?" * len(row)) + ")", row)
    for topic in order:  # topic by topic
        for m in messages:
            if m["topic"] == topic:
                c.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)",
                          (ids[topic], int(m["log_time_ns"]), base64.b64decode(m["data"])))
    db.commit()
    db.close()


def main():
    out = sys.argv[1]
    with open(os.path.join(out, "messages.jsonl")) as f:
        messages = [json.loads(line) for line in f if line.strip()]
    with open(os.path.join(out, "definitions.json")) as f:
        definitions = json.load(f)
    write(os.path.join(out, "humble.db3"), messages, definitions, False)
    write(os.path.join(out, "jazzy.db3"), messages, definitions, True)
    split = os.path.join(out, "split")
    os.makedirs(split, exist_ok=True)
    half = len(messages) // 2
    write(os.path.join(split, "split_0.db3"), messages[:half], definitions, False)
    write(os.path.join(split, "split_1.db3"), messages[half:], definitions, False)
    with open(os.path.join(split, "metadata.yaml"), "w") as f:
        f.write("rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
                "  relative_file_paths:\n    - split_0.db3\n    - split_1.db3\n"
                f"  message_count: {len(messages)}\n")
    print(f"wrote humble.db3, jazzy.db3, split/ ({len(messages)} messages) to {out}")


main()
