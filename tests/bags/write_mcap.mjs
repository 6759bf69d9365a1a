// write_mcap.mjs — independent ROS 2 MCAP test fixtures for kccd's own MCAP reader.
//
// Usage: node write_mcap.mjs OUT_DIR
//
// Writes, with other projects' writers (Foxglove's @mcap/core McapWriter and
// @foxglove/rosmsg2-serialization CDR MessageWriter), four MCAP files holding the
// same ROS 2 content, so kccd's reader is tested on files it did not write:
//   joint_plain.mcap          no chunks
//   joint_zstd.mcap           chunked (4 KiB), zstd  (@foxglove/wasm-zstd)
//   joint_lz4.mcap            chunked (4 KiB), lz4 frame (lz4js; @foxglove/wasm-lz4
//                             only decompresses, it is used here to verify each frame)
//   joint_chunked_none.mcap   chunked (4 KiB), no compression
//   joint_overlap.mcap        the same messages topic by topic in zstd chunks: chunk time
//                             ranges overlap (not in truth.json: its file order differs)
//   joint_publishers.mcap     the same messages, /joint_states on three channels (callerids)
//   split_mcap/               the same messages as a rosbag2 folder of 11 MCAP files (zstd)
// plus truth.json: what each file holds and every decoded message, for the tests.
// Content: 200 sensor_msgs/msg/JointState on /joint_states at 1 kHz, one CameraInfo and 10
// sensor_msgs/msg/Image (64x48 rgb8) on /camera/image_raw at 30 Hz, interleaved by
// log time. Fully deterministic: no randomness, no wall clock.
import fs from "node:fs";
import path from "node:path";
import { McapWriter, LIBRARY_IDENTIFIER } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4Decompress from "@foxglove/wasm-lz4";
import lz4js from "lz4js";

const outDir = process.argv[2];
// Smaller files (the fuzz targets' seeds): KCCD_MCAP_JOINTS, KCCD_MCAP_IMAGES, KCCD_MCAP_CHUNK.
const N_JOINTS = Number(process.env.KCCD_MCAP_JOINTS ?? 200);
const N_IMAGES = Number(process.env.KCCD_MCAP_IMAGES ?? 10);
const CHUNK = Number(process.env.KCCD_MCAP_CHUNK ?? 4096);
if (!outDir) {
  console.error("usage: node write_mcap.mjs OUT_DIR");
  process.exit(2);
}

// ---- complete ros2msg definitions (main type, then "====…" + "MSG: pkg/Type" per dependency)
const SEP = "=".repeat(80);
const TIME = "# Time in seconds and nanoseconds since the epoch\nint32 sec\nuint32 nanosec\n";
const HEADER = "# Standard metadata for higher-level stamped data types.\nbuiltin_interfaces/Time stamp\n\n# Transform frame with which this data is associated.\nstring frame_id\n";
const deps = `${SEP}\nMSG: std_msgs/Header\n${HEADER}${SEP}\nMSG: builtin_interfaces/Time\n${TIME}`;
const JOINT_STATE_DEF =
  "# This is a message that holds data to describe the state of a set of torque controlled joints.\n" +
  "std_msgs/Header header\n\nstring[] name\n# rad or m\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n" + deps;
const ROI = "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n";
const CAMERA_INFO_DEF =
  "# Meta information for a camera.\nstd_msgs/Header header\nuint32 height\nuint32 width\n" +
  "string distortion_model\nfloat64[] d\nfloat64[9]  k # 3x3 row-major matrix\nfloat64[9]  r\nfloat64[12] p\n" +
  "uint32 binning_x\nuint32 binning_y\nRegionOfInterest roi\n" +
  `${SEP}\nMSG: sensor_msgs/RegionOfInterest\n${ROI}` + deps;
const IMAGE_DEF =
  "# This message contains an uncompressed image\n# (0, 0) is at top-left corner of image\n" +
  "std_msgs/Header header\n\nuint32 height # image height, that is, number of rows\nuint32 width\n\n" +
  "string encoding\nuint8 is_bigendian\nuint32 step # Full row length in bytes\nuint8[] data\n" + deps;

// ---- deterministic content
const BASE = 1700000000_000000000n;
const split = (ns) => ({ sec: Number(ns / 1_000_000_000n), nanosec: Number(ns % 1_000_000_000n) });
const joints = [];
for (let i = 0; i < N_JOINTS; i++) {
  const log = BASE + BigInt(i) * 1_000_000n;
  const ks = Array.from({ length: 7 }, (_, j) => ((j + i) % 7) + 1); // order rotates by i % 7
  joints.push({
    log,
    header: { stamp: split(log - 2_000_000n), frame_id: "" },
    name: ks.map((k) => `joint${k}`),
    position: ks.map((k) => 0.1 * k + 0.001 * i),
    velocity: ks.map((k) => 0.01 * k),
    effort: i % 2 === 0 ? [] : ks.map((k) => -k),
  });
}
const images = [];
for (let i = 0; i < N_IMAGES; i++) {
  const log = BASE + BigInt(Math.round((i * 1e9) / 30));
  const data = Uint8Array.from({ length: 64 * 48 * 3 }, (_, j) => (i * 7 + j) % 256);
  images.push({
    log,
    header: { stamp: split(log - 35_000_000n), frame_id: "" },
    height: 48, width: 64, encoding: "rgb8", is_bigendian: 0, step: 192, data,
  });
}

// One camera info, at the base time: a 64x48 camera with a plumb_bob lens.
const cameraInfos = [{
  log: BASE,
  header: { stamp: split(BASE - 35_000_000n), frame_id: "camera" },
  height: 48, width: 64, distortion_model: "plumb_bob",
  d: [-0.11, 0.06, 0.0006, -0.0004, -0.01],
  k: [70, 0, 31.7, 0, 71, 23.9, 0, 0, 1],
  r: [1, 0, 0, 0, 1, 0, 0, 0, 1],
  p: [70, 0, 31.7, 0, 0, 71, 23.9, 0, 0, 0, 1, 0],
  binning_x: 0, binning_y: 0,
  roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false },
}];

const TOPICS = [
  { topic: "/joint_states", schema_name: "sensor_msgs/msg/JointState", def: JOINT_STATE_DEF, msgs: joints },
  { topic: "/camera/image_raw", schema_name: "sensor_msgs/msg/Image", def: IMAGE_DEF, msgs: images },
  { topic: "/camera/camera_info", schema_name: "sensor_msgs/msg/CameraInfo", def: CAMERA_INFO_DEF, msgs: cameraInfos },
];
// All messages sorted by log time (ties: topic order above), serialized once.
const records = [];
TOPICS.forEach((t, ti) => {
  const writer = new MessageWriter(parse(t.def, { ros2: true }));
  t.msgs.forEach((m, seq) => records.push({ ti, seq, log: m.log, data: writer.writeMessage(m) }));
});
records.sort((a, b) => (a.log < b.log ? -1 : a.log > b.log ? 1 : a.ti - b.ti));

// ---- compressors
await zstd.isLoaded;
await lz4Decompress.isLoaded;
const compressZstd = (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 3) });
const compressLz4 = (d) => {
  const c = lz4js.compress(d); // LZ4 frame (magic 04 22 4D 18), as the MCAP spec requires
  const back = lz4Decompress(c, d.byteLength); // liblz4's frame decoder must accept it
  if (!Buffer.from(back).equals(Buffer.from(d))) throw new Error("lz4 frame round-trip failed");
  return { compression: "lz4", compressedData: c };
};
const compressNone = (d) => ({ compression: "", compressedData: d });

const FILES = {
  // compression: null = no chunks, "" = chunks stored uncompressed
  "joint_plain.mcap": { compression: null, opts: { useChunks: false } },
  "joint_zstd.mcap": { compression: "zstd", opts: { chunkSize: CHUNK, compressChunk: compressZstd } },
  "joint_lz4.mcap": { compression: "lz4", opts: { chunkSize: CHUNK, compressChunk: compressLz4 } },
  "joint_chunked_none.mcap": { compression: "", opts: { chunkSize: CHUNK, compressChunk: compressNone } },
};

// `order`: the records to write. `rotate`: the topics registered from this one on (other channel
// and schema ids). `publishers`: per topic, the callerids of the channels that share it (a channel
// each, its metadata naming it; message k of the topic on channel k mod their number).
async function writeFile(name, opts, order = records, { rotate = 0, publishers = {} } = {}) {
  const parts = [];
  let pos = 0n;
  const writable = { position: () => pos, write: async (b) => { parts.push(Buffer.from(b)); pos += BigInt(b.byteLength); } };
  const w = new McapWriter({ writable, ...opts });
  await w.start({ profile: "ros2", library: LIBRARY_IDENTIFIER });
  const channels = [];
  for (let k = 0; k < TOPICS.length; k++) {
    const ti = (k + rotate) % TOPICS.length, t = TOPICS[ti];
    const schemaId = await w.registerSchema({ name: t.schema_name, encoding: "ros2msg", data: new TextEncoder().encode(t.def) });
    channels[ti] = [];
    for (const caller of publishers[t.topic] ?? [null]) {
      const metadata = new Map(caller ? [["callerid", caller]] : []);
      channels[ti].push(await w.registerChannel({ topic: t.topic, schemaId, messageEncoding: "cdr", metadata }));
    }
  }
  for (const r of order) {
    const ids = channels[r.ti];
    await w.addMessage({ channelId: ids[r.seq % ids.length], sequence: r.seq, logTime: r.log, publishTime: r.log, data: r.data });
  }
  await w.end();
  fs.writeFileSync(path.join(outDir, name), Buffer.concat(parts));
}

fs.mkdirSync(outDir, { recursive: true });
for (const [name, f] of Object.entries(FILES)) await writeFile(name, f.opts);
// The same messages written topic by topic (every joint state, then every image, then the camera
// info) in zstd chunks of 4 KiB: the chunks' time ranges overlap, and log-time order is the
// reader's to restore (from the summary's chunk index). Not in truth.json: its file order differs.
const byTopic = [...records].sort((a, b) => a.ti - b.ti || (a.log < b.log ? -1 : a.log > b.log ? 1 : 0));
await writeFile("joint_overlap.mcap", { chunkSize: CHUNK, compressChunk: compressZstd }, byTopic);

// The same messages with /joint_states on three channels, one per publisher (as an MCAP file
// converted from a ROS 1 bag has a channel per connection): message k on channel k mod 3. Not in
// truth.json: bag info gives one row for the topic, with its publishers.
const PUBLISHERS = ["/arm_controller", "/gripper_controller", "/joint_state_publisher"];
await writeFile("joint_publishers.mcap", { chunkSize: CHUNK, compressChunk: compressZstd }, records,
  { publishers: { "/joint_states": PUBLISHERS } });
// The same messages as a rosbag2 bag split into 11 MCAP files (split_mcap/rec_0.mcap ... rec_10.mcap,
// listed in that order in its metadata.yaml; by name rec_10 would sort before rec_2), each file
// registering the topics in another order, so that a channel's id differs from file to file.
const SPLIT = 11;
const splitNames = [];
fs.mkdirSync(path.join(outDir, "split_mcap"), { recursive: true });
for (let k = 0; k < SPLIT; k++) {
  const part = records.slice(Math.floor((k * records.length) / SPLIT), Math.floor(((k + 1) * records.length) / SPLIT));
  splitNames.push(`rec_${k}.mcap`);
  await writeFile(path.join("split_mcap", splitNames[k]), { chunkSize: CHUNK, compressChunk: compressZstd }, part, { rotate: k });
}
fs.writeFileSync(path.join(outDir, "split_mcap", "metadata.yaml"),
  "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths:\n" +
  splitNames.map((n) => `    - ${n}\n`).join("") + `  message_count: ${records.length}\n`);

// ---- truth.json
const topicInfo = TOPICS.map((t) => ({
  topic: t.topic, schema_name: t.schema_name, schema_encoding: "ros2msg", message_encoding: "cdr",
  count: t.msgs.length, first_log_time_ns: String(t.msgs[0].log), last_log_time_ns: String(t.msgs.at(-1).log),
}));
const truth = {
  profile: "ros2",
  library: LIBRARY_IDENTIFIER,
  files: Object.fromEntries(Object.keys(FILES).map((n) => [n, {
    compression: FILES[n].compression,
    topics: topicInfo,
  }])),
  joint_states: joints.map((m) => ({
    log_time_ns: String(m.log), stamp_sec: m.header.stamp.sec, stamp_nanosec: m.header.stamp.nanosec,
    frame_id: m.header.frame_id, name: m.name, position: m.position, velocity: m.velocity, effort: m.effort,
  })),
  images: images.map((m) => ({
    log_time_ns: String(m.log), stamp_sec: m.header.stamp.sec, stamp_nanosec: m.header.stamp.nanosec,
    frame_id: m.header.frame_id, height: m.height, width: m.width, encoding: m.encoding,
    is_bigendian: m.is_bigendian, step: m.step,
    data_sum: m.data.reduce((a, b) => a + b, 0), data_first8: Array.from(m.data.slice(0, 8)),
  })),
  camera_infos: cameraInfos.map((m) => ({
    log_time_ns: String(m.log), width: m.width, height: m.height, distortion_model: m.distortion_model, d: m.d, k: m.k,
  })),
};
// Objects indented, arrays of objects one element per line, everything else compact.
const fmt = (v, ind = "") => {
  const nl = `\n${ind} `;
  if (Array.isArray(v) && typeof v[0] === "object") return `[${nl}${v.map((x) => JSON.stringify(x)).join(`,${nl}`)}\n${ind}]`;
  if (v && typeof v === "object" && !Array.isArray(v))
    return `{${nl}${Object.entries(v).map(([k, x]) => `${JSON.stringify(k)}: ${fmt(x, ind + " ")}`).join(`,${nl}`)}\n${ind}}`;
  return JSON.stringify(v);
};
fs.writeFileSync(path.join(outDir, "truth.json"), fmt(truth) + "\n");
// The same serialized messages for write_db3.py (rosbag2's sqlite3 layout, written with Python's
// sqlite3): one JSON line per message in log-time order, and the definitions by type.
fs.writeFileSync(path.join(outDir, "messages.jsonl"), records.map((r) => JSON.stringify({
  topic: TOPICS[r.ti].topic, type: TOPICS[r.ti].schema_name, log_time_ns: String(r.log),
  data: Buffer.from(r.data).toString("base64"),
})).join("\n") + "\n");
fs.writeFileSync(path.join(outDir, "definitions.json"),
  JSON.stringify(Object.fromEntries(TOPICS.map((t) => [t.schema_name, t.def])), null, 1) + "\n");
console.log(`wrote ${Object.keys(FILES).join(", ")}, truth.json to ${outDir}`);
