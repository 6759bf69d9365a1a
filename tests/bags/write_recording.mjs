// write_recording.mjs — a recording (images, a state log, frame times) written as a ROS 2 MCAP bag
// by other projects' writers (@mcap/core, @foxglove/rosmsg2-serialization), for the tests that
// compare a command on the bag with the same command on the files.
//
// Usage: node write_recording.mjs OUT.mcap --images PATTERN --frame-times T.csv --states S.csv
//          [--state-offset S] [--compression zstd|lz4|none] [--chunk BYTES] [--topic-order]
//   --images        frame files, a printf pattern with one %d (e.g. f_%06d.png or .jpg), from 0;
//                   each is a sensor_msgs/msg/CompressedImage (format png or jpeg) of its bytes
//   --frame-times   CSV "frame,time": image i is stamped BASE + time(i); logged 20 ms later
//   --states        CSV "time,NAME,..." (the suite's state log): each row a JointState stamped
//                   BASE + time - state-offset (the log's clock runs that far ahead), logged 1 ms
//                   later, with the joint names rotated by one place per message
//   --topic-order   write all joint states, then all images (chunks then overlap in time)
// BASE is 1700000000 s. Deterministic: no randomness, no wall clock.
import fs from "node:fs";
import { McapWriter, LIBRARY_IDENTIFIER } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4js from "lz4js";

const args = process.argv.slice(2);
const out = args[0];
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i < 0 ? dflt : args[i + 1];
};
const images = opt("--images"), frameTimes = opt("--frame-times"), states = opt("--states");
if (!out || !images || !frameTimes || !states) {
  console.error("usage: node write_recording.mjs OUT.mcap --images PATTERN --frame-times T.csv --states S.csv [options]");
  process.exit(2);
}
const offset = Number(opt("--state-offset", "0"));
const compression = opt("--compression", "zstd");
const chunk = Number(opt("--chunk", String(1 << 20)));
const topicOrder = args.includes("--topic-order");

const SEP = "=".repeat(80);
const deps = `${SEP}\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n${SEP}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n`;
const JOINT_STATE_DEF = "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n" + deps;
const COMPRESSED_DEF = "std_msgs/Header header\nstring format\nuint8[] data\n" + deps;
const BASE = 1700000000_000000000n;
const ns = (seconds) => BASE + BigInt(Math.round(seconds * 1e9));
const split = (t) => ({ sec: Number(t / 1_000_000_000n), nanosec: Number(t % 1_000_000_000n) });
const csv = (file) => fs.readFileSync(file, "utf8").trim().split(/\r?\n/).map((l) => l.split(","));

const records = [];
const jointWriter = new MessageWriter(parse(JOINT_STATE_DEF, { ros2: true }));
const [head, ...rows] = csv(states);
// Columns NAME are positions, NAME.vel velocities (given when every joint has one).
const cols = head.map((c, i) => [c, i]).slice(1).filter(([c]) => !c.endsWith(".vel"));
const names = cols.map(([c]) => c);
const velCol = names.map((n) => head.indexOf(`${n}.vel`));
const withVel = velCol.every((c) => c > 0);
rows.forEach((r, i) => {
  const stamp = ns(Number(r[0]) - offset);
  const order = names.map((_, k) => (k + i) % names.length);
  const msg = { header: { stamp: split(stamp), frame_id: "" }, name: order.map((k) => names[k]),
                position: order.map((k) => Number(r[cols[k][1]])),
                velocity: withVel ? order.map((k) => Number(r[velCol[k]])) : [], effort: [] };
  records.push({ ti: 0, log: stamp + 1_000_000n, data: jointWriter.writeMessage(msg) });
});
const imageWriter = new MessageWriter(parse(COMPRESSED_DEF, { ros2: true }));
const [, ...times] = csv(frameTimes);
times.forEach(([frame, time]) => {
  const file = images.replace(/%0?(\d*)d/, (_, w) => String(frame).padStart(Number(w || 0), "0"));
  const stamp = ns(Number(time));
  const format = /\.jpe?g$/i.test(file) ? "jpeg" : "png";
  const msg = { header: { stamp: split(stamp), frame_id: "camera" }, format, data: new Uint8Array(fs.readFileSync(file)) };
  records.push({ ti: 1, log: stamp + 20_000_000n, data: imageWriter.writeMessage(msg) });
});
if (!topicOrder) records.sort((a, b) => (a.log < b.log ? -1 : a.log > b.log ? 1 : a.ti - b.ti));

await zstd.isLoaded;
const compress = compression === "zstd" ? (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 3) })
               : compression === "lz4" ? (d) => ({ compression: "lz4", compressedData: lz4js.compress(d) })
               : (d) => ({ compression: "", compressedData: d });
const parts = [];
let pos = 0n;
const writable = { position: () => pos, write: async (b) => { parts.push(Buffer.from(b)); pos += BigInt(b.byteLength); } };
const w = new McapWriter({ writable, chunkSize: chunk, compressChunk: compress });
await w.start({ profile: "ros2", library: LIBRARY_IDENTIFIER });
const channels = [];
for (const [topic, type, def] of [["/joint_states", "sensor_msgs/msg/JointState", JOINT_STATE_DEF],
                                  ["/camera/image_raw/compressed", "sensor_msgs/msg/CompressedImage", COMPRESSED_DEF]]) {
  const schemaId = await w.registerSchema({ name: type, encoding: "ros2msg", data: new TextEncoder().encode(def) });
  channels.push(await w.registerChannel({ topic, schemaId, messageEncoding: "cdr", metadata: new Map() }));
}
const seq = [0, 0];
for (const r of records) await w.addMessage({ channelId: channels[r.ti], sequence: seq[r.ti]++, logTime: r.log, publishTime: r.log, data: r.data });
await w.end();
fs.writeFileSync(out, Buffer.concat(parts));
console.log(`wrote ${out}: ${rows.length} joint states, ${times.length} images`);
