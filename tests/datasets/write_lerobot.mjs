// write_lerobot.mjs — LeRobot datasets written by other projects' tools, for kccd's dataset tests.
//
// Usage: node write_lerobot.mjs OUT_DIR STATES.csv FRAMES_PATTERN [options]
//        node write_lerobot.mjs OUT_DIR --from-synth REC [options]
//   STATES.csv      a state log (time, one column per state value), one row per frame
//   FRAMES_PATTERN  the frames, e.g. frames/frame_%06d.png (numbered from 0), one per row
//   REC             a `kccd synth` recording: its video's frames, and its state log (125 Hz, on a
//                   clock offset from the video's) interpolated at each frame's time
// Options:
//   --version v2.1|v3.0   the layout (default v2.1)
//   --writer pw|hy        parquet-wasm (arrow-rs) or hyparquet-writer (default pw)
//   --episodes N          rows split into N episodes of (nearly) equal length (default 2)
//   --codec C             FFmpeg encoder of the videos: libsvtav1, libx264 or mpeg4 (default libsvtav1)
//   --camera KEY          the camera feature (default observation.images.front)
//   --image-feature       frames stored in the table as PNG bytes (dtype image) instead of videos
//   --drift S             timestamps off the frame grid: + S * (i mod 7) / 6 seconds (a wall clock)
//   --info-codec C        the codec info.json names (default: the one encoded)
//   --nested-names        the state's names as a nested list ([[...]]), as some datasets write them
//   --names A,B,...       the state's names (default: the CSV's columns)
//   --extra-camera KEY    a second video feature (the same frames)
//   --row-group N         rows per Parquet row group (default 64: several groups in a small table)
//   --no-camera           no camera at all (a joint log; FRAMES_PATTERN is not read, give "-")
// Videos are encoded by Debian's FFmpeg (`ffmpeg`); tables by the npm writers. Also writes
// OUT_DIR/truth/episode_N.csv: each episode's rows as a state log (time = frame_index / fps,
// the float32 values the table holds), for comparing with kccd's video + CSV path.
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";
import * as arrow from "apache-arrow";
import * as pw from "parquet-wasm";
import { ByteWriter, parquetWrite } from "hyparquet-writer";

const args = process.argv.slice(2);
const positional = [];
const opt = { version: "v2.1", writer: "pw", episodes: 2, codec: "libsvtav1", camera: "observation.images.front", drift: 0 };
for (let i = 0; i < args.length; i++) {
  const a = args[i];
  if (!a.startsWith("--")) { positional.push(a); continue; }
  const key = a.slice(2).replace(/-([a-z])/g, (_, c) => c.toUpperCase());
  if (key === "imageFeature" || key === "nestedNames" || key === "noCamera") opt[key] = true;
  else opt[key] = args[++i];
}
if (opt.fromSynth ? positional.length !== 1 : positional.length !== 3) {
  console.error("usage: node write_lerobot.mjs OUT_DIR STATES.csv FRAMES_PATTERN [options]\n" +
    "       node write_lerobot.mjs OUT_DIR --from-synth REC [options]");
  process.exit(2);
}
const outDir = positional[0];
let [, statesCsv, framesPattern] = positional;
if (opt.fromSynth) [statesCsv, framesPattern] = fromSynth(opt.fromSynth);

// A synth recording as one state row and one PNG per frame (in OUT_DIR.frames/).
function fromSynth(rec) {
  const truth = JSON.parse(fs.readFileSync(path.join(rec, "synth.json"), "utf8"));
  const { fps, frames } = truth.video, offset = truth.state_log.time_offset;
  const lines = fs.readFileSync(path.join(rec, truth.state_log.file), "utf8").trim().split("\n");
  const head = lines[0].split(",");
  const keep = head.map((n, k) => k > 0 && !n.endsWith(".vel"));
  const log = lines.slice(1).map((l) => l.split(",").map(Number));
  const work = `${outDir}.frames`;
  fs.mkdirSync(work, { recursive: true });
  let text = ["time", ...head.filter((_, k) => keep[k])].join(",") + "\n";
  for (let i = 0, j = 0; i < frames; i++) {
    const t = i / fps + offset;  // the frame's time on the log's clock
    while (j + 2 < log.length && log[j + 1][0] <= t) j++;
    const [a, b] = [log[j], log[j + 1]];
    const w = Math.min(1, Math.max(0, (t - a[0]) / (b[0] - a[0])));
    text += [String(i / fps), ...a.map((x, k) => x + w * (b[k] - x)).filter((_, k) => keep[k])].join(",") + "\n";
  }
  fs.writeFileSync(path.join(work, "states.csv"), text);
  execFileSync("ffmpeg", ["-loglevel", "error", "-y", "-i", path.join(rec, truth.video.file), "-start_number", "0",
    path.join(work, "frame_%06d.png")]);
  return [path.join(work, "states.csv"), path.join(work, "frame_%06d.png")];
}
const v3 = opt.version.startsWith("v3");
const episodes = Number(opt.episodes);
const drift = Number(opt.drift);
const rowGroup = Number(opt.rowGroup ?? 64);

// ---- the rows
const lines = fs.readFileSync(statesCsv, "utf8").trim().split("\n");
const header = lines[0].split(",");
const names = opt.names ? opt.names.split(",") : header.slice(1);
const rows = lines.slice(1).map((l) => l.split(",").slice(1).map((x) => Math.fround(Number(x))));
const times = lines.slice(1).map((l) => Number(l.split(",")[0]));
const fps = Math.round(1 / ((times[times.length - 1] - times[0]) / (times.length - 1)) * 1000) / 1000;
const frameFile = (i) => framesPattern.replace(/%0(\d)d/, (_, w) => String(i).padStart(Number(w), "0"));
const lengths = Array.from({ length: episodes }, (_, e) => Math.floor((rows.length * (e + 1)) / episodes) - Math.floor((rows.length * e) / episodes));
const starts = lengths.map((_, e) => lengths.slice(0, e).reduce((a, b) => a + b, 0));
const TASK = "check the arm's volumes";

fs.mkdirSync(path.join(outDir, "meta"), { recursive: true });
fs.mkdirSync(path.join(outDir, "truth"), { recursive: true });

function episodeRows(e) {
  const out = [];
  for (let j = 0; j < lengths[e]; j++) {
    const i = starts[e] + j;
    out.push({
      "observation.state": rows[i],
      action: rows[i].map((x) => Math.fround(x * 0.5)),
      timestamp: Math.fround(j / fps + drift * ((j % 7) / 6)),
      frame_index: j,
      episode_index: e,
      index: i,
      task_index: 0,
      image: opt.imageFeature ? { bytes: new Uint8Array(fs.readFileSync(frameFile(i))), path: `frame_${String(i).padStart(6, "0")}.png` } : null,
    });
  }
  return out;
}

// ---- tables
function writeTable(file, tableRows) {
  fs.mkdirSync(path.dirname(file), { recursive: true });
  const col = (n) => tableRows.map((r) => r[n]);
  if (opt.writer === "pw") {
    const f32 = new arrow.Float32();
    const cols = {
      "observation.state": arrow.vectorFromArray(col("observation.state"), new arrow.List(new arrow.Field("item", f32, true))),
      action: arrow.vectorFromArray(col("action"), new arrow.List(new arrow.Field("item", new arrow.Float32(), true))),
      timestamp: arrow.vectorFromArray(col("timestamp"), new arrow.Float32()),
      frame_index: arrow.vectorFromArray(col("frame_index").map(BigInt), new arrow.Int64()),
      episode_index: arrow.vectorFromArray(col("episode_index").map(BigInt), new arrow.Int64()),
      index: arrow.vectorFromArray(col("index").map(BigInt), new arrow.Int64()),
      task_index: arrow.vectorFromArray(col("task_index").map(BigInt), new arrow.Int64()),
    };
    if (opt.imageFeature)
      cols[opt.camera] = arrow.vectorFromArray(col("image"), new arrow.Struct([new arrow.Field("bytes", new arrow.Binary(), true), new arrow.Field("path", new arrow.Utf8(), true)]));
    const props = new pw.WriterPropertiesBuilder().setCompression(pw.Compression.SNAPPY).setMaxRowGroupSize(rowGroup)
      .setStatisticsEnabled(pw.EnabledStatistics.Chunk).build();
    const ipc = arrow.tableToIPC(new arrow.Table(cols), "stream");
    fs.writeFileSync(file, pw.writeParquet(pw.Table.fromIPCStream(ipc), props));
    return;
  }
  const schema = [
    { name: "root", num_children: opt.imageFeature ? 8 : 7 },
    { name: "observation.state", repetition_type: "OPTIONAL", converted_type: "LIST", num_children: 1 },
    { name: "list", repetition_type: "REPEATED", num_children: 1 },
    { name: "element", type: "FLOAT", repetition_type: "OPTIONAL" },
    { name: "action", repetition_type: "OPTIONAL", converted_type: "LIST", num_children: 1 },
    { name: "list", repetition_type: "REPEATED", num_children: 1 },
    { name: "element", type: "FLOAT", repetition_type: "OPTIONAL" },
    { name: "timestamp", type: "FLOAT", repetition_type: "OPTIONAL" },
    { name: "frame_index", type: "INT64", repetition_type: "OPTIONAL" },
    { name: "episode_index", type: "INT64", repetition_type: "OPTIONAL" },
    { name: "index", type: "INT64", repetition_type: "OPTIONAL" },
    { name: "task_index", type: "INT64", repetition_type: "OPTIONAL" },
  ];
  if (opt.imageFeature)
    schema.push({ name: opt.camera, repetition_type: "OPTIONAL", num_children: 2 },
      { name: "bytes", type: "BYTE_ARRAY", repetition_type: "OPTIONAL" },
      { name: "path", type: "BYTE_ARRAY", converted_type: "UTF8", repetition_type: "OPTIONAL" });
  const big = (n) => col(n).map(BigInt);
  const columnData = [
    { name: "observation.state", data: col("observation.state") },
    { name: "action", data: col("action") },
    { name: "timestamp", data: col("timestamp") },
    { name: "frame_index", data: big("frame_index") },
    { name: "episode_index", data: big("episode_index") },
    { name: "index", data: big("index") },
    { name: "task_index", data: big("task_index") },
  ];
  if (opt.imageFeature) columnData.push({ name: opt.camera, data: col("image") });
  const writer = new ByteWriter();
  parquetWrite({ writer, columnData, schema, rowGroupSize: rowGroup, codec: "SNAPPY" });
  fs.writeFileSync(file, new Uint8Array(writer.getBuffer()));
}

// ---- videos (FFmpeg): rows [first, first + count) of the frames
function encode(file, first, count) {
  fs.mkdirSync(path.dirname(file), { recursive: true });
  const codecArgs = opt.codec === "libsvtav1" ? ["-c:v", "libsvtav1", "-preset", "12", "-crf", "30", "-g", "2"]
    : opt.codec === "libx264" ? ["-c:v", "libx264", "-preset", "ultrafast", "-crf", "18", "-g", "2"]
    : ["-c:v", "mpeg4", "-q:v", "3", "-g", "2"];
  execFileSync("ffmpeg", ["-loglevel", "error", "-y", "-framerate", String(fps), "-start_number", String(first), "-i", framesPattern,
    "-frames:v", String(count), ...codecArgs, "-pix_fmt", "yuv420p", file], { env: { ...process.env, SVT_LOG: "1" }, stdio: ["ignore", "ignore", "inherit"] });
}
const codecName = { libsvtav1: "av1", libx264: "h264", mpeg4: "mpeg4" }[opt.codec];
const cameras = opt.imageFeature || opt.noCamera ? [] : [opt.camera, ...(opt.extraCamera ? [opt.extraCamera] : [])];

const episodeMeta = [];
if (!v3) {
  for (let e = 0; e < episodes; e++) {
    writeTable(path.join(outDir, `data/chunk-000/episode_${String(e).padStart(6, "0")}.parquet`), episodeRows(e));
    for (const key of cameras) encode(path.join(outDir, `videos/chunk-000/${key}/episode_${String(e).padStart(6, "0")}.mp4`), starts[e], lengths[e]);
  }
  fs.writeFileSync(path.join(outDir, "meta/episodes.jsonl"),
    lengths.map((n, e) => JSON.stringify({ episode_index: e, tasks: [TASK], length: n })).join("\n") + "\n");
  fs.writeFileSync(path.join(outDir, "meta/tasks.jsonl"), JSON.stringify({ task_index: 0, task: TASK }) + "\n");
} else {
  // Every episode in one data file and one video file per camera, as v3.0 packs them.
  writeTable(path.join(outDir, "data/chunk-000/file-000.parquet"), Array.from({ length: episodes }, (_, e) => episodeRows(e)).flat());
  for (const key of cameras) encode(path.join(outDir, `videos/${key}/chunk-000/file-000.mp4`), 0, rows.length);
  const col = (f) => lengths.map((_, e) => f(e));
  const cols = {
    episode_index: arrow.vectorFromArray(col((e) => BigInt(e)), new arrow.Int64()),
    tasks: arrow.vectorFromArray(col(() => [TASK]), new arrow.List(new arrow.Field("item", new arrow.Utf8(), true))),
    length: arrow.vectorFromArray(col((e) => BigInt(lengths[e])), new arrow.Int64()),
    "data/chunk_index": arrow.vectorFromArray(col(() => 0n), new arrow.Int64()),
    "data/file_index": arrow.vectorFromArray(col(() => 0n), new arrow.Int64()),
    dataset_from_index: arrow.vectorFromArray(col((e) => BigInt(starts[e])), new arrow.Int64()),
    dataset_to_index: arrow.vectorFromArray(col((e) => BigInt(starts[e] + lengths[e])), new arrow.Int64()),
  };
  for (const key of cameras) {
    cols[`videos/${key}/chunk_index`] = arrow.vectorFromArray(col(() => 0n), new arrow.Int64());
    cols[`videos/${key}/file_index`] = arrow.vectorFromArray(col(() => 0n), new arrow.Int64());
    cols[`videos/${key}/from_timestamp`] = arrow.vectorFromArray(col((e) => starts[e] / fps), new arrow.Float64());
    cols[`videos/${key}/to_timestamp`] = arrow.vectorFromArray(col((e) => (starts[e] + lengths[e]) / fps), new arrow.Float64());
  }
  fs.mkdirSync(path.join(outDir, "meta/episodes/chunk-000"), { recursive: true });
  const props = new pw.WriterPropertiesBuilder().setCompression(pw.Compression.ZSTD).build();
  fs.writeFileSync(path.join(outDir, "meta/episodes/chunk-000/file-000.parquet"),
    pw.writeParquet(pw.Table.fromIPCStream(arrow.tableToIPC(new arrow.Table(cols), "stream")), props));
}

// ---- info.json
const png = opt.noCamera ? null : fs.readFileSync(frameFile(0));  // the frames' size from the first PNG's IHDR
const w = png ? png.readUInt32BE(16) : 0, h = png ? png.readUInt32BE(20) : 0;
const stateNames = opt.nestedNames ? [names] : names;
const features = {
  "observation.state": { dtype: "float32", shape: [names.length], names: stateNames },
  action: { dtype: "float32", shape: [names.length], names: names.map((n) => `${n}_target`) },
};
for (const key of cameras)
  features[key] = {
    dtype: "video", shape: [h, w, 3], names: ["height", "width", "channels"],
    info: { "video.height": h, "video.width": w, "video.codec": opt.infoCodec ?? codecName, "video.pix_fmt": "yuv420p", "video.is_depth_map": false, "video.fps": fps, "video.channels": 3, has_audio: false },
  };
if (opt.imageFeature) features[opt.camera] = { dtype: "image", shape: [h, w, 3], names: ["height", "width", "channel"] };
Object.assign(features, {
  timestamp: { dtype: "float32", shape: [1], names: null },
  frame_index: { dtype: "int64", shape: [1], names: null },
  episode_index: { dtype: "int64", shape: [1], names: null },
  index: { dtype: "int64", shape: [1], names: null },
  task_index: { dtype: "int64", shape: [1], names: null },
});
const info = {
  codebase_version: opt.version, robot_type: "kccd_test_arm", total_episodes: episodes, total_frames: rows.length, total_tasks: 1,
  chunks_size: 1000, fps, splits: { train: `0:${episodes}` },
  data_path: v3 ? "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet" : "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet",
  video_path: cameras.length === 0 ? null : v3 ? "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
    : "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4",
  features,
};
fs.writeFileSync(path.join(outDir, "meta/info.json"), JSON.stringify(info, null, 4));

// ---- the truth: each episode as a state log at its frames' times
const exact = (x) => String(x);  // JavaScript's shortest round-trip form of the float32's double
for (let e = 0; e < episodes; e++) {
  let text = ["time", ...header.slice(1)].join(",") + "\n";
  for (let j = 0; j < lengths[e]; j++) text += [exact(j / fps), ...rows[starts[e] + j].map(exact)].join(",") + "\n";
  fs.writeFileSync(path.join(outDir, `truth/episode_${e}.csv`), text);
}
console.log(`write_lerobot: ${opt.version} (${opt.writer}), ${episodes} episodes, ${rows.length} rows, ${cameras.length ? opt.codec : opt.imageFeature ? "images in the table" : "no camera"} in ${outDir}`);
