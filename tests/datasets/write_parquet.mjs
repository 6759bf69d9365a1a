// write_parquet.mjs — independent Parquet test fixtures for kccd's own Parquet reader.
//
// Usage: node write_parquet.mjs OUT_DIR
//
// Writes the same LeRobot-like table with two other projects' writers, so kccd's reader is
// tested on files it did not write:
//   pw_COMP_vV_DICT.parquet  parquet-wasm (arrow-rs compiled to wasm) from an Arrow IPC table
//                            made with apache-arrow: COMP none/snappy/zstd/gzip, data pages v1
//                            or v2, dictionary encoding on (dict) or off (plain, PLAIN values)
//   hy_COMP_DICT.parquet     hyparquet-writer (data pages v2 only): COMP none/snappy/gzip (gzip
//                            by Node's zlib; Node 20 has no zstd), dictionary forced or off,
//                            booleans RLE-encoded in the plain files
//   hy_refused_*.parquet     hyparquet-writer with an encoding kccd refuses on one column
// plus truth.json: every file's columns, row groups and integer ranges, and each column's values
// as kccd's reader must return them (a null scalar as null, meaning NaN or "", a null or empty
// list as no values; byte values in hex).
// Columns (rows i = 0..N-1, row groups of G rows):
//   observation.state       list<float32>, 6 values; row 5 null, row 9 empty, row 13 seven
//                           values with a null third
//   action                  fixed_size_list<float32>[7] (parquet-wasm only); row 11 null
//   timestamp               float64; row 7 null
//   frame_index, episode_index, index   int64 (required)
//   task_index              int32
//   next.done               boolean; row 3 null
//   task                    string (three tasks, one non-ASCII); row 6 null
//   observation.images.top  struct {bytes: binary (a PNG), path: string}; row 10 null, row 12
//                           has no bytes
//   tag                     fixed_size_binary[4]; row 2 null
// Environment (smaller files, e.g. the fuzz target's seeds): KCCD_PARQUET_ROWS (40),
// KCCD_PARQUET_GROUP (7), KCCD_PARQUET_ONLY (a comma-separated list of file names to write),
// KCCD_PARQUET_PW_COLUMNS (the top-level columns parquet-wasm's files hold, comma-separated).
// Fully deterministic: no randomness, no wall clock.
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";
import * as arrow from "apache-arrow";
import * as pw from "parquet-wasm";
import { ByteWriter, parquetWrite } from "hyparquet-writer";
import { writeMetadata } from "hyparquet-writer/src/metadata.js";
import { parquetMetadata } from "hyparquet";

const outDir = process.argv[2];
if (!outDir) {
  console.error("usage: node write_parquet.mjs OUT_DIR");
  process.exit(2);
}
const N = Number(process.env.KCCD_PARQUET_ROWS ?? 40);
const G = Number(process.env.KCCD_PARQUET_GROUP ?? 7);
const only = process.env.KCCD_PARQUET_ONLY ? new Set(process.env.KCCD_PARQUET_ONLY.split(",")) : null;
const pwColumns = process.env.KCCD_PARQUET_PW_COLUMNS ? process.env.KCCD_PARQUET_PW_COLUMNS.split(",") : null;
fs.mkdirSync(outDir, { recursive: true });

// ---- a small valid PNG per row (8x2 grey pixels, stored deflate), so images differ row to row
const crcTable = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
const crc32 = (bytes) => {
  let c = 0xffffffff;
  for (const b of bytes) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
};
function pngChunk(type, data) {
  const out = Buffer.alloc(12 + data.length);
  out.writeUInt32BE(data.length, 0);
  out.write(type, 4, "latin1");
  Buffer.from(data).copy(out, 8);
  out.writeUInt32BE(crc32(out.subarray(4, 8 + data.length)), 8 + data.length);
  return out;
}
function png(i) {
  const w = 8, h = 2;
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0);
  ihdr.writeUInt32BE(h, 4);
  ihdr.set([8, 0, 0, 0, 0], 8);  // 8-bit greyscale
  const raw = Buffer.alloc(h * (w + 1));
  for (let y = 0; y < h; y++) for (let x = 0; x < w; x++) raw[y * (w + 1) + 1 + x] = (i * 16 + x * 8 + y) & 0xff;
  const sig = Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]);
  return new Uint8Array(Buffer.concat([sig, pngChunk("IHDR", ihdr), pngChunk("IDAT", zlib.deflateSync(raw, { level: 0 })),
    pngChunk("IEND", Buffer.alloc(0))]));
}

// ---- the rows
const TASKS = ["pick the cube", "place the cube", "wave — ünïcode"];
const rows = [];
for (let i = 0; i < N; i++) {
  let state = Array.from({ length: 6 }, (_, k) => Math.fround(Math.sin(0.1 * i + k) * 2.5 + k / 3));
  if (i === 5) state = null;
  if (i === 9) state = [];
  if (i === 13) state = [...state, Math.fround(-1 / 3)], state[2] = null;
  rows.push({
    "observation.state": state,
    action: i === 11 ? null : Array.from({ length: 7 }, (_, k) => Math.fround(Math.cos(0.05 * i * (k + 1)) / 7)),
    timestamp: i === 7 ? null : i / 30,
    frame_index: i % 20,
    episode_index: Math.floor(i / 20),
    index: i,
    task_index: i % 3,
    "next.done": i === 3 ? null : i % 20 === 19,
    task: i === 6 ? null : TASKS[i % 3],
    "observation.images.top": i === 10 ? null : { bytes: i === 12 ? null : png(i), path: `images/frame_${String(i).padStart(6, "0")}.png` },
    tag: i === 2 ? null : new Uint8Array([i & 0xff, (i * 7) & 0xff, 0, 0xff]),
  });
}
const col = (name) => rows.map((r) => r[name]);
const hex = (b) => Buffer.from(b).toString("hex");

// ---- what kccd's reader must return: per column, per row, the list of values
const truthColumns = {
  "observation.state": { bytes: false, list: true, rows: col("observation.state").map((v) => v ?? []) },
  action: { bytes: false, list: true, rows: col("action").map((v) => v ?? []) },
  timestamp: { bytes: false, list: false, rows: col("timestamp").map((v) => [v]) },
  frame_index: { bytes: false, list: false, rows: col("frame_index").map((v) => [v]) },
  episode_index: { bytes: false, list: false, rows: col("episode_index").map((v) => [v]) },
  index: { bytes: false, list: false, rows: col("index").map((v) => [v]) },
  task_index: { bytes: false, list: false, rows: col("task_index").map((v) => [v]) },
  "next.done": { bytes: false, list: false, rows: col("next.done").map((v) => [v === null ? null : Number(v)]) },
  task: { bytes: true, list: false, rows: col("task").map((v) => [v === null ? "" : hex(Buffer.from(v, "utf8"))]) },
  "observation.images.top/bytes": {
    bytes: true, list: false, rows: col("observation.images.top").map((v) => [v?.bytes ? hex(v.bytes) : ""]),
  },
  "observation.images.top/path": {
    bytes: true, list: false, rows: col("observation.images.top").map((v) => [v ? hex(Buffer.from(v.path)) : ""]),
  },
  tag: { bytes: true, list: false, rows: col("tag").map((v) => [v ? hex(v) : ""]) },
};
const groups = [];
for (let s = 0; s < N; s += G) groups.push({ first: s, rows: Math.min(G, N - s) });
// Integer statistics per row group: [min, max] of the non-null values.
function ranges(names) {
  const out = {};
  for (const name of names) {
    out[name] = groups.map(({ first, rows: n }) => {
      const v = col(name).slice(first, first + n).filter((x) => x !== null);
      return [Math.min(...v), Math.max(...v)];
    });
  }
  return out;
}
const HF = JSON.stringify({ info: { features: { "observation.state": { dtype: "float32", shape: [6] } } } });
const truth = { rows: N, groups, columns: truthColumns, files: {} };

// ---- parquet-wasm (arrow-rs) from an Arrow table
function arrowTable() {
  const f32 = () => new arrow.Float32();
  const image = new arrow.Struct([new arrow.Field("bytes", new arrow.Binary(), true), new arrow.Field("path", new arrow.Utf8(), true)]);
  const v = (name, type) => arrow.vectorFromArray(col(name), type);
  const table = new arrow.Table({
    "observation.state": v("observation.state", new arrow.List(new arrow.Field("item", f32(), true))),
    action: v("action", new arrow.FixedSizeList(7, new arrow.Field("item", f32(), true))),
    timestamp: v("timestamp", new arrow.Float64()),
    frame_index: arrow.vectorFromArray(col("frame_index").map(BigInt), new arrow.Int64()),
    episode_index: arrow.vectorFromArray(col("episode_index").map(BigInt), new arrow.Int64()),
    index: arrow.vectorFromArray(col("index").map(BigInt), new arrow.Int64()),
    task_index: v("task_index", new arrow.Int32()),
    "next.done": v("next.done", new arrow.Bool()),
    task: v("task", new arrow.Utf8()),
    "observation.images.top": v("observation.images.top", image),
    tag: v("tag", new arrow.FixedSizeBinary(4)),
  });
  // LeRobot's indices are never null: required columns, as datasets write them.
  const required = new Set(["frame_index", "episode_index", "index"]);
  const fields = table.schema.fields.map((f) => (required.has(f.name) ? f.clone({ nullable: false }) : f));
  const schema = new arrow.Schema(fields);
  return new arrow.Table(schema, table.batches.map((b) => new arrow.RecordBatch(schema, b.data)));
}
const PW_COMPRESSION = { none: pw.Compression.UNCOMPRESSED, snappy: pw.Compression.SNAPPY, zstd: pw.Compression.ZSTD, gzip: pw.Compression.GZIP };
function writePw(name, compression, version, dictionary) {
  const props = new pw.WriterPropertiesBuilder()
    .setCompression(PW_COMPRESSION[compression])
    .setWriterVersion(version === 1 ? pw.WriterVersion.V1 : pw.WriterVersion.V2)
    .setDictionaryEnabled(dictionary)
    // Without a dictionary, arrow-rs's v2 pages default to DELTA_BINARY_PACKED integers and
    // DELTA_BYTE_ARRAY strings, which kccd refuses (pyarrow, which datasets use, writes PLAIN).
    .setEncoding(pw.Encoding.PLAIN)
    .setMaxRowGroupSize(G)
    .setStatisticsEnabled(pw.EnabledStatistics.Chunk)
    .setCreatedBy("parquet-wasm 0.8.0 (kccd fixtures)")
    .setKeyValueMetadata(new Map([["huggingface", HF]]))
    .build();
  const table = pwColumns ? arrowTable().select(pwColumns) : arrowTable();
  const ipc = arrow.tableToIPC(table, "stream");
  const bytes = pw.writeParquet(pw.Table.fromIPCStream(ipc), props);
  fs.writeFileSync(path.join(outDir, name), bytes);
  const columns = Object.keys(truthColumns).filter((c) => !pwColumns || pwColumns.includes(c.split("/")[0]));
  truth.files[name] = {
    writer: "parquet-wasm", compression, pageVersion: version, dictionary, columns,
    integerRanges: ranges(["frame_index", "episode_index", "index", "task_index"]),
    metadata: { huggingface: HF },
  };
}

// ---- hyparquet-writer from columns, with an explicit schema (lists and structs are nested)
function hySchema() {
  const opt = "OPTIONAL";
  return [
    { name: "root", num_children: 10 },
    { name: "observation.state", repetition_type: opt, converted_type: "LIST", num_children: 1 },
    { name: "list", repetition_type: "REPEATED", num_children: 1 },
    { name: "element", type: "FLOAT", repetition_type: opt },
    { name: "timestamp", type: "DOUBLE", repetition_type: opt },
    { name: "frame_index", type: "INT64", repetition_type: "REQUIRED" },
    { name: "episode_index", type: "INT64", repetition_type: "REQUIRED" },
    { name: "index", type: "INT64", repetition_type: "REQUIRED" },
    { name: "task_index", type: "INT32", repetition_type: opt },
    { name: "next.done", type: "BOOLEAN", repetition_type: opt },
    { name: "task", type: "BYTE_ARRAY", converted_type: "UTF8", repetition_type: opt },
    { name: "observation.images.top", repetition_type: opt, num_children: 2 },
    { name: "bytes", type: "BYTE_ARRAY", repetition_type: opt },
    { name: "path", type: "BYTE_ARRAY", converted_type: "UTF8", repetition_type: opt },
    { name: "tag", type: "FIXED_LEN_BYTE_ARRAY", type_length: 4, repetition_type: opt },
  ];
}
const gzip = (b) => new Uint8Array(zlib.gzipSync(b));
function writeHy(name, compression, dictionary, refuse) {
  const names = ["observation.state", "timestamp", "frame_index", "episode_index", "index", "task_index", "next.done", "task",
    "observation.images.top", "tag"];
  const columnData = names.map((n) => {
    const c = { name: n, data: col(n).map((v) => (typeof v === "number" && n.endsWith("index") && hySchema().find((e) => e.name === n).type === "INT64" ? BigInt(v) : v)) };
    if (n === "next.done") c.encoding = dictionary ? "PLAIN" : "RLE";
    else c.encoding = dictionary ? "RLE_DICTIONARY" : "PLAIN";
    if (refuse && refuse.column === n) c.encoding = refuse.encoding;
    return c;
  });
  const writer = new ByteWriter();
  parquetWrite({
    writer, columnData, schema: hySchema(), rowGroupSize: G, codec: compression === "none" ? "UNCOMPRESSED" : compression.toUpperCase(),
    compressors: { GZIP: gzip }, kvMetadata: [{ key: "huggingface", value: HF }], createdBy: "hyparquet-writer 0.17.0 (kccd fixtures)",
  });
  fs.writeFileSync(path.join(outDir, name), new Uint8Array(writer.getBuffer()));
  const columns = Object.keys(truthColumns).filter((c) => c !== "action");
  truth.files[name] = {
    writer: "hyparquet-writer", compression, pageVersion: 2, dictionary, columns,
    integerRanges: ranges(["frame_index", "episode_index", "index", "task_index"]),
    metadata: { huggingface: HF },
  };
  if (refuse) truth.files[name].refused = refuse;
}

const wanted = (name) => !only || only.has(name);
for (const compression of ["none", "snappy", "zstd", "gzip"])
  for (const version of [1, 2])
    for (const dictionary of [true, false]) {
      const name = `pw_${compression}_v${version}_${dictionary ? "dict" : "plain"}.parquet`;
      if (wanted(name)) writePw(name, compression, version, dictionary);
    }
for (const compression of ["none", "snappy", "gzip"])
  for (const dictionary of [true, false]) {
    const name = `hy_${compression}_${dictionary ? "dict" : "plain"}.parquet`;
    if (wanted(name)) writeHy(name, compression, dictionary);
  }
const REFUSED = [
  { column: "index", encoding: "DELTA_BINARY_PACKED" },
  { column: "timestamp", encoding: "BYTE_STREAM_SPLIT" },
  { column: "task", encoding: "DELTA_BYTE_ARRAY" },
];
for (const refuse of REFUSED) {
  const name = `hy_refused_${refuse.encoding.toLowerCase()}.parquet`;
  if (wanted(name)) writeHy(name, "snappy", false, refuse);
}

// ---- layouts the writers do not make themselves: hyparquet-writer's file with its footer written
// anew (hyparquet's parquetMetadata, then hyparquet-writer's own writeMetadata) in another schema
// that has the same levels, so the pages stay right for it.
function rewriteFooter(name, bytes, change) {
  const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  const meta = parquetMetadata(buffer);
  const footerLength = new DataView(buffer).getUint32(bytes.byteLength - 8, true);
  change(meta);
  const writer = new ByteWriter();
  writer.appendBytes(bytes.subarray(0, bytes.byteLength - 8 - footerLength));
  writeMetadata(writer, meta);
  writer.appendUint32(0x31524150);  // PAR1
  fs.writeFileSync(path.join(outDir, name), new Uint8Array(writer.getBuffer()));
}
function writeHyColumns(columnData, schema) {
  const writer = new ByteWriter();
  parquetWrite({ writer, columnData, schema, rowGroupSize: G, codec: "SNAPPY", createdBy: "hyparquet-writer 0.17.0 (kccd fixtures)" });
  return new Uint8Array(writer.getBuffer());
}
const legacyRows = col("observation.state").map((v) => (v ?? []).filter((x) => x !== null));
truthColumns.legacy = { bytes: false, list: true, rows: col("observation.state").map((v, i) => (v === null ? [] : legacyRows[i])) };
truthColumns.legacy_bare = { bytes: false, list: true, rows: legacyRows };
if (wanted("hy_legacy_lists.parquet")) {
  // Written as three-level lists of required floats (an optional list, then a required one);
  // stored as the two-level `optional group legacy (LIST) { repeated float element; }` and the bare
  // `repeated float legacy_bare`: the same definition and repetition levels.
  const bytes = writeHyColumns(
    [
      { name: "index", data: col("index").map(BigInt) },
      { name: "legacy", data: col("observation.state").map((v) => (v === null ? null : v.filter((x) => x !== null))) },
      { name: "legacy_bare", data: legacyRows },
    ],
    [
      { name: "root", num_children: 3 },
      { name: "index", type: "INT64", repetition_type: "REQUIRED" },
      { name: "legacy", repetition_type: "OPTIONAL", converted_type: "LIST", num_children: 1 },
      { name: "list", repetition_type: "REPEATED", num_children: 1 },
      { name: "element", type: "FLOAT", repetition_type: "REQUIRED" },
      { name: "legacy_bare", repetition_type: "REQUIRED", converted_type: "LIST", num_children: 1 },
      { name: "list", repetition_type: "REPEATED", num_children: 1 },
      { name: "element", type: "FLOAT", repetition_type: "REQUIRED" },
    ]);
  rewriteFooter("hy_legacy_lists.parquet", bytes, (meta) => {
    meta.schema.splice(5, 3, { name: "legacy_bare", type: "FLOAT", repetition_type: "REPEATED" });
    meta.schema.splice(3, 2, { name: "element", type: "FLOAT", repetition_type: "REPEATED" });
    for (const g of meta.row_groups) {
      g.columns[1].meta_data.path_in_schema = ["legacy", "element"];
      g.columns[2].meta_data.path_in_schema = ["legacy_bare"];
    }
  });
  truth.files["hy_legacy_lists.parquet"] = {
    writer: "hyparquet-writer", compression: "snappy", pageVersion: 2, dictionary: true, columns: ["index", "legacy", "legacy_bare"],
    integerRanges: ranges(["index"]), metadata: {},
  };
}
if (wanted("hy_refused_int96.parquet")) {
  // INT96 (a legacy timestamp): the index column's type changed in the footer, its pages left.
  // A second column stays readable: the refusal is the INT96 column's alone.
  const bytes = writeHyColumns([{ name: "index", data: col("index").map(BigInt) }, { name: "frame_index", data: col("frame_index").map(BigInt) }],
    [{ name: "root", num_children: 2 }, { name: "index", type: "INT64", repetition_type: "REQUIRED" },
      { name: "frame_index", type: "INT64", repetition_type: "REQUIRED" }]);
  rewriteFooter("hy_refused_int96.parquet", bytes, (meta) => {
    meta.schema[1].type = "INT96";
    for (const g of meta.row_groups) {
      g.columns[0].meta_data.type = "INT96";
      delete g.columns[0].meta_data.statistics;
    }
  });
  truth.files["hy_refused_int96.parquet"] = { writer: "hyparquet-writer", refusedLayout: "INT96", columns: [], metadata: {} };
}
if (wanted("hy_refused_list_of_lists.parquet")) {
  const bytes = writeHyColumns([{ name: "nested", data: rows.map((_, i) => [[i, i + 1], [], [i * 2]]) },
    { name: "frame_index", data: col("frame_index").map(BigInt) }], [
    { name: "root", num_children: 2 },
    { name: "nested", repetition_type: "OPTIONAL", converted_type: "LIST", num_children: 1 },
    { name: "list", repetition_type: "REPEATED", num_children: 1 },
    { name: "element", repetition_type: "OPTIONAL", converted_type: "LIST", num_children: 1 },
    { name: "list", repetition_type: "REPEATED", num_children: 1 },
    { name: "element", type: "INT32", repetition_type: "OPTIONAL" },
    { name: "frame_index", type: "INT64", repetition_type: "REQUIRED" },
  ]);
  fs.writeFileSync(path.join(outDir, "hy_refused_list_of_lists.parquet"), bytes);
  truth.files["hy_refused_list_of_lists.parquet"] = { writer: "hyparquet-writer", refusedLayout: "list of lists", columns: [], metadata: {} };
}
fs.writeFileSync(path.join(outDir, "truth.json"), JSON.stringify(truth, null, 1));
console.log(`write_parquet: ${Object.keys(truth.files).length} files in ${outDir}`);
