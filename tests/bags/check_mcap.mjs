// check_mcap.mjs — self-check of the fixtures written by write_mcap.mjs.
//
// Usage: node check_mcap.mjs OUT_DIR
//
// Reads every .mcap named in OUT_DIR/truth.json back with Foxglove's own readers:
// McapStreamReader (every record in file order, CRCs validated, zstd/lz4 chunks decoded
// by @foxglove/wasm-zstd / @foxglove/wasm-lz4) and McapIndexedReader (summary: chunk
// index, statistics). Decodes each CDR message with @foxglove/rosmsg2-serialization and
// compares header, schemas, channels, chunk compression, per-topic counts/times and every
// message field with truth.json. Prints a line per file; exits 1 on any mismatch.
// CompressedImages (/camera/image_raw/compressed, truth.compressed_images) are compared by their
// header, format and the JPEG's first and last two bytes (SOI, EOI); with truth.dump_images (a
// folder name in OUT_DIR), each one's data is written there as 000000.jpg, 000001.jpg, ... for
// the caller to decode.
import fs from "node:fs";
import path from "node:path";
import { isDeepStrictEqual } from "node:util";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4Decompress from "@foxglove/wasm-lz4";

const dir = process.argv[2];
if (!dir) {
  console.error("usage: node check_mcap.mjs OUT_DIR");
  process.exit(2);
}
await zstd.isLoaded;
await lz4Decompress.isLoaded;
const truth = JSON.parse(fs.readFileSync(path.join(dir, "truth.json"), "utf8"));
const decompressHandlers = {
  zstd: (buf, size) => zstd.decompress(buf, Number(size)),
  lz4: (buf, size) => lz4Decompress(buf, Number(size)),
};
let failures = 0;
const expect = (file, what, got, want) => {
  if (!isDeepStrictEqual(got, want)) {
    failures++;
    console.log(`  MISMATCH ${file}: ${what}: got ${JSON.stringify(got)} want ${JSON.stringify(want)}`);
  }
};
// Decoded message -> the shape truth.json uses.
const plain = {
  "/joint_states": (m, log) => ({
    log_time_ns: String(log), stamp_sec: m.header.stamp.sec, stamp_nanosec: m.header.stamp.nanosec,
    frame_id: m.header.frame_id, name: m.name, position: Array.from(m.position),
    velocity: Array.from(m.velocity), effort: Array.from(m.effort),
  }),
  "/camera/image_raw": (m, log) => ({
    log_time_ns: String(log), stamp_sec: m.header.stamp.sec, stamp_nanosec: m.header.stamp.nanosec,
    frame_id: m.header.frame_id, height: m.height, width: m.width, encoding: m.encoding,
    is_bigendian: m.is_bigendian, step: m.step,
    data_sum: m.data.reduce((a, b) => a + b, 0), data_first8: Array.from(m.data.slice(0, 8)),
  }),
  "/camera/image_raw/compressed": (m, log) => ({
    log_time_ns: String(log), stamp_sec: m.header.stamp.sec, stamp_nanosec: m.header.stamp.nanosec,
    frame_id: m.header.frame_id, format: m.format,
    data_ends: [m.data[0], m.data[1], m.data[m.data.length - 2], m.data[m.data.length - 1]],
  }),
  "/camera/camera_info": (m, log) => ({
    log_time_ns: String(log), width: m.width, height: m.height, distortion_model: m.distortion_model,
    d: Array.from(m.d), k: Array.from(m.k),
  }),
};
const wantMsgs = { "/joint_states": truth.joint_states, "/camera/image_raw": truth.images,
                   "/camera/image_raw/compressed": truth.compressed_images, "/camera/camera_info": truth.camera_infos };
const dumpDir = truth.dump_images ? path.join(dir, truth.dump_images) : null;
if (dumpDir) fs.mkdirSync(dumpDir, { recursive: true });
let dumped = 0;

for (const [file, want] of Object.entries(truth.files)) {
  const buf = fs.readFileSync(path.join(dir, file));
  const stream = new McapStreamReader({ includeChunks: true, decompressHandlers, validateCrcs: true });
  stream.append(buf);
  const schemas = new Map(), topics = new Map(), chunkComps = new Set(); // topics: channel id -> {info, reader, msgs}
  let lastLog = -1n, chunks = 0;
  for (let rec; (rec = stream.nextRecord()); ) {
    if (rec.type === "Header") expect(file, "header", { profile: rec.profile, library: rec.library }, { profile: truth.profile, library: truth.library });
    else if (rec.type === "Schema") schemas.set(rec.id, rec);
    else if (rec.type === "Chunk") { chunks++; chunkComps.add(rec.compression); }
    else if (rec.type === "Channel" && !topics.has(rec.id)) {
      const schema = schemas.get(rec.schemaId);
      topics.set(rec.id, {
        info: { topic: rec.topic, schema_name: schema.name, schema_encoding: schema.encoding, message_encoding: rec.messageEncoding },
        reader: new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true })),
        msgs: [],
      });
    } else if (rec.type === "Message") {
      if (rec.logTime < lastLog) expect(file, "log-time order", String(rec.logTime), `>= ${lastLog}`);
      lastLog = rec.logTime;
      expect(file, "publish_time", rec.publishTime, rec.logTime);
      const t = topics.get(rec.channelId);
      const m = t.reader.readMessage(rec.data);
      t.msgs.push(plain[t.info.topic](m, rec.logTime));
      if (dumpDir && t.info.topic === "/camera/image_raw/compressed")
        fs.writeFileSync(path.join(dumpDir, `${String(dumped++).padStart(6, "0")}.jpg`), m.data);
    }
  }
  expect(file, "stream complete", stream.done(), true);
  const comps = [...chunkComps];
  expect(file, "chunk compression", comps, want.compression === null ? [] : [want.compression]);

  // Summary section as McapIndexedReader sees it.
  const readable = { size: async () => BigInt(buf.length), read: async (o, n) => buf.subarray(Number(o), Number(o + n)) };
  const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  expect(file, "chunk index count", indexed.chunkIndexes.length, chunks);
  expect(file, "statistics message count", indexed.statistics?.messageCount, BigInt([...topics.values()].reduce((a, t) => a + t.msgs.length, 0)));

  const byTopic = new Map([...topics.values()].map((t) => [t.info.topic, t]));
  const counts = [];
  for (const w of want.topics) {
    const t = byTopic.get(w.topic);
    if (!t) { expect(file, "topic present", null, w.topic); continue; }
    const first = t.msgs[0]?.log_time_ns, last = t.msgs.at(-1)?.log_time_ns;
    expect(file, `topic ${w.topic}`, { ...t.info, count: t.msgs.length, first_log_time_ns: first, last_log_time_ns: last }, w);
    t.msgs.forEach((m, i) => expect(file, `${w.topic}[${i}]`, m, wantMsgs[w.topic][i]));
    counts.push(`${w.topic}=${t.msgs.length}`);
  }
  expect(file, "topic count", byTopic.size, want.topics.length);
  console.log(`${file}: ${buf.length} bytes, ${chunks} chunks, compression ${JSON.stringify(comps)}, ${counts.join(" ")}`);
}
console.log(failures ? `FAIL: ${failures} mismatches` : "OK: all files match truth.json");
process.exit(failures ? 1 : 0);
