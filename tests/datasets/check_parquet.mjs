// check_parquet.mjs — self-check of the fixtures written by write_parquet.mjs.
//
// Usage: node check_parquet.mjs OUT_DIR
//
// Reads every file named in OUT_DIR/truth.json back with the writers' projects' own readers:
// hyparquet (gzip by Node's zlib) for every file Node can decompress, and parquet-wasm's
// readParquet (arrow-rs) for every file, and compares the row count, row groups, key-value
// metadata and every value of every column with truth.json: what kccd's reader is tested
// against is what the files hold. The refused-encoding files are read too (these readers know
// those encodings); the files refused whole are checked to hold what is refused. Prints a line per file; exits 1 on any mismatch.
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";
import { isDeepStrictEqual } from "node:util";
import * as arrow from "apache-arrow";
import * as pw from "parquet-wasm";
import { parquetMetadata, parquetReadObjects } from "hyparquet";

const dir = process.argv[2];
if (!dir) {
  console.error("usage: node check_parquet.mjs OUT_DIR");
  process.exit(2);
}
const truth = JSON.parse(fs.readFileSync(path.join(dir, "truth.json"), "utf8"));
const hex = (b) => Buffer.from(b).toString("hex");

// One row's value of `column` ("a/b" is field b of struct a) in truth.json's form.
function cell(row, column, spec) {
  let v = row;
  for (const part of column.split("/")) v = v === null || v === undefined ? null : v[part];
  const one = (x) => {
    if (x === null || x === undefined) return spec.bytes ? "" : null;
    if (spec.bytes) return hex(typeof x === "string" ? Buffer.from(x, "utf8") : x);
    if (typeof x === "bigint" || typeof x === "boolean") return Number(x);
    return Number.isNaN(x) ? null : x;
  };
  if (spec.list) return v === null || v === undefined ? [] : Array.from(v, one);
  return [one(v)];
}

let failed = 0;
function compare(name, reader, rows) {
  const file = truth.files[name];
  const problems = [];
  if (rows.length !== truth.rows) problems.push(`${rows.length} rows, not ${truth.rows}`);
  for (const column of file.columns) {
    const spec = truth.columns[column];
    for (let r = 0; r < Math.min(rows.length, truth.rows) && problems.length < 5; r++) {
      const got = cell(rows[r], column, spec);
      if (!isDeepStrictEqual(got, spec.rows[r]))
        problems.push(`${column} row ${r}: ${JSON.stringify(got).slice(0, 120)}, not ${JSON.stringify(spec.rows[r]).slice(0, 120)}`);
    }
  }
  if (problems.length) {
    failed++;
    console.log(`check_parquet: ${name} (${reader}) MISMATCH: ${problems.join("; ")}`);
  }
  return problems.length === 0;
}

for (const name of Object.keys(truth.files)) {
  const file = truth.files[name];
  const bytes = fs.readFileSync(path.join(dir, name));
  const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  const meta = parquetMetadata(buffer);
  const groups = meta.row_groups.map((g) => Number(g.num_rows));
  if (!isDeepStrictEqual(groups, truth.groups.map((g) => g.rows))) {
    failed++;
    console.log(`check_parquet: ${name}: row groups ${JSON.stringify(groups)}`);
  }
  for (const [key, value] of Object.entries(file.metadata)) {
    if (meta.key_value_metadata?.find((kv) => kv.key === key)?.value !== value) {
      failed++;
      console.log(`check_parquet: ${name}: metadata ${key} differs`);
    }
  }
  if (file.refusedLayout) {
    // Files kccd must refuse whole: their footers parse, and hold what kccd refuses.
    const repeated = meta.schema.filter((e) => e.repetition_type === "REPEATED").length;
    const holds = file.refusedLayout === "INT96" ? meta.schema.some((e) => e.type === "INT96") : repeated >= 2;
    if (!holds) failed++;
    console.log(`check_parquet: ${name}: ${holds ? "holds" : "MISMATCH: does not hold"} ${file.refusedLayout}`);
    continue;
  }
  const readers = [];
  if (file.compression !== "zstd") {
    const rows = await parquetReadObjects({
      file: buffer, compressors: { GZIP: (input) => new Uint8Array(zlib.gunzipSync(input)) }, utf8: false,
    });
    // hyparquet reads a 4-byte fixed-length column and binary as bytes, strings as strings.
    readers.push(compare(name, "hyparquet", rows) && "hyparquet");
  }
  const table = arrow.tableFromIPC(pw.readParquet(bytes).intoIPCStream());
  const rows = table.toArray().map((r) => r.toJSON());
  for (const r of rows) {
    for (const [k, v] of Object.entries(r)) {
      if (v instanceof arrow.Vector) r[k] = v.toArray();
      if (v && typeof v === "object" && typeof v.toJSON === "function" && !(v instanceof Uint8Array)) r[k] = v.toJSON();
    }
  }
  readers.push(compare(name, "parquet-wasm", rows) && "parquet-wasm");
  if (readers.every(Boolean)) console.log(`check_parquet: ${name}: ${truth.rows} rows as written (${readers.join(", ")})`);
}
if (failed) process.exit(1);
