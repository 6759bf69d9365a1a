#include "kccd/logs/db3_reader.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <sqlite3.h>

#include "kccd/input_error.hpp"
#include "kccd/logs/message_definition.hpp"

namespace kccd::logs {
namespace {

// sqlite3's own words for the last failure, quoting the file's bytes at most as printable text (a
// damaged schema's "unrecognized token" quotes whatever it holds).
std::string db3Message(sqlite3* db) { return printable(sqlite3_errmsg(db), 200); }

const std::string kDefSep = std::string(80, '=') + "\n";
const std::string kTimeDef = "int32 sec\nuint32 nanosec\n";
const std::string kHeaderDef = "builtin_interfaces/Time stamp\nstring frame_id\n";
const std::string kHeaderDeps =
    kDefSep + "MSG: std_msgs/Header\n" + kHeaderDef + kDefSep + "MSG: builtin_interfaces/Time\n" + kTimeDef;

// A text column of the current row ("" for NULL).
std::string columnText(sqlite3_stmt* st, int c) {
  const unsigned char* p = sqlite3_column_text(st, c);
  return p ? std::string(reinterpret_cast<const char*>(p), static_cast<std::size_t>(sqlite3_column_bytes(st, c)))
           : std::string();
}

}  // namespace

std::string builtinDefinition(const std::string& type) {
  const std::string t = normalTypeName(type);
  if (t == "sensor_msgs/JointState")
    return "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n" +
           kHeaderDeps;
  if (t == "sensor_msgs/Image")
    return "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 "
           "step\nuint8[] data\n" +
           kHeaderDeps;
  if (t == "sensor_msgs/CompressedImage") return "std_msgs/Header header\nstring format\nuint8[] data\n" + kHeaderDeps;
  if (t == "sensor_msgs/CameraInfo")
    return "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] "
           "k\nfloat64[9] r\n"
           "float64[12] p\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi\n" +
           kDefSep +
           "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool "
           "do_rectify\n" +
           kHeaderDeps;
  if (t == "std_msgs/Header") return kHeaderDef + kDefSep + "MSG: builtin_interfaces/Time\n" + kTimeDef;
  return {};
}

struct Db3Reader::Db {
  sqlite3* db = nullptr;
  sqlite3_stmt* rows = nullptr;
  // A file cut short: the rows it still holds, found one id at a time, in (timestamp, id) order,
  // read through `row_by_id`.
  bool salvage = false;
  std::vector<std::pair<std::int64_t, std::int64_t>> found;  // (timestamp, id)
  std::size_t next = 0;
  sqlite3_stmt* row_by_id = nullptr;
  std::string cut;  // what the header declares against what the file holds
  // The work budget (sqlite3's progress handler, in thousands of VM steps): far above what the
  // file's own rows need, so only a crafted schema can exhaust it.
  std::uint64_t ticks = 0, max_ticks = 0;
  static int onProgress(void* self) {
    auto* db = static_cast<Db*>(self);
    return ++db->ticks > db->max_ticks ? 1 : 0;
  }
  bool exhausted() const { return ticks > max_ticks; }
  ~Db() {
    if (rows) sqlite3_finalize(rows);
    if (row_by_id) sqlite3_finalize(row_by_id);
    if (db) sqlite3_close(db);
  }
};

namespace {

// The bytes a database file's 100-byte header `h` declares (page size x the in-header page count,
// when the count is valid: its version number equals the change counter), or 0 when it declares none.
std::uint64_t declaredBytes(const unsigned char (&h)[100]) {
  auto be32 = [&](int at) {
    return (std::uint32_t{h[at]} << 24) | (std::uint32_t{h[at + 1]} << 16) | (std::uint32_t{h[at + 2]} << 8) |
           h[at + 3];
  };
  const std::uint32_t page = h[16] == 0 && h[17] == 1 ? 65536u : (std::uint32_t{h[16]} << 8) | h[17];
  if (page < 512 || (page & (page - 1)) != 0 || be32(24) != be32(92)) return 0;
  return std::uint64_t{page} * be32(28);
}

// The VFS a cut file is read through: the default one, except that a read the file cannot fill is
// an error. sqlite3 otherwise fills the missing tail of the last, partial page with zeros, and a row
// on that page would read as whole with bytes it never held; through this VFS it is not found.
struct WholePagesFile {
  sqlite3_file base;
  sqlite3_file* real() { return reinterpret_cast<sqlite3_file*>(this + 1); }
};
sqlite3_vfs* g_default_vfs = nullptr;
WholePagesFile* shim(sqlite3_file* f) { return reinterpret_cast<WholePagesFile*>(f); }
sqlite3_file* realOf(sqlite3_file* f) { return shim(f)->real(); }
int wpClose(sqlite3_file* f) { return realOf(f)->pMethods->xClose(realOf(f)); }
int wpRead(sqlite3_file* f, void* buf, int amt, sqlite3_int64 off) {
  const int rc = realOf(f)->pMethods->xRead(realOf(f), buf, amt, off);
  return rc == SQLITE_IOERR_SHORT_READ ? SQLITE_IOERR_READ : rc;
}
int wpWrite(sqlite3_file*, const void*, int, sqlite3_int64) { return SQLITE_READONLY; }
int wpTruncate(sqlite3_file*, sqlite3_int64) { return SQLITE_READONLY; }
int wpSync(sqlite3_file*, int) { return SQLITE_OK; }
int wpFileSize(sqlite3_file* f, sqlite3_int64* size) { return realOf(f)->pMethods->xFileSize(realOf(f), size); }
int wpLock(sqlite3_file* f, int l) { return realOf(f)->pMethods->xLock(realOf(f), l); }
int wpUnlock(sqlite3_file* f, int l) { return realOf(f)->pMethods->xUnlock(realOf(f), l); }
int wpReserved(sqlite3_file* f, int* out) { return realOf(f)->pMethods->xCheckReservedLock(realOf(f), out); }
int wpControl(sqlite3_file* f, int op, void* arg) { return realOf(f)->pMethods->xFileControl(realOf(f), op, arg); }
int wpSector(sqlite3_file* f) { return realOf(f)->pMethods->xSectorSize(realOf(f)); }
int wpDevice(sqlite3_file* f) { return realOf(f)->pMethods->xDeviceCharacteristics(realOf(f)); }
const sqlite3_io_methods kWholePagesMethods = {
    1,         wpClose,  wpRead,   wpWrite, wpTruncate, wpSync,  wpFileSize, wpLock,  wpUnlock, wpReserved,
    wpControl, wpSector, wpDevice, nullptr, nullptr,    nullptr, nullptr,    nullptr, nullptr};
int wpOpen(sqlite3_vfs*, sqlite3_filename name, sqlite3_file* f, int flags, int* out_flags) {
  f->pMethods = nullptr;
  const int rc = g_default_vfs->xOpen(g_default_vfs, name, realOf(f), flags, out_flags);
  if (rc == SQLITE_OK && realOf(f)->pMethods) f->pMethods = &kWholePagesMethods;
  return rc;
}
// The VFS's name, registered once (not the default).
const char* wholePagesVfs() {
  static const char* const name = [] {
    static sqlite3_vfs vfs;
    g_default_vfs = sqlite3_vfs_find(nullptr);
    if (!g_default_vfs) return static_cast<const char*>(nullptr);
    vfs = *g_default_vfs;
    vfs.zName = "kccd_whole_pages";
    vfs.szOsFile = static_cast<int>(sizeof(WholePagesFile)) + g_default_vfs->szOsFile;
    vfs.xOpen = wpOpen;
    vfs.pNext = nullptr;
    return sqlite3_vfs_register(&vfs, 0) == SQLITE_OK ? vfs.zName : static_cast<const char*>(nullptr);
  }();
  return name;
}

// The message rows a cut file still holds: each id from 1 looked up alone (sqlite3 then reads only
// the pages on that row's path), until `kGap` ids in a row are missing or unreadable.
std::vector<std::pair<std::int64_t, std::int64_t>> salvageRows(sqlite3* db) {
  constexpr std::int64_t kGap = 4096;
  std::vector<std::pair<std::int64_t, std::int64_t>> found;
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(db, "SELECT timestamp FROM messages WHERE id = ?", -1, &st, nullptr) != SQLITE_OK) {
    if (st) sqlite3_finalize(st);
    return found;
  }
  for (std::int64_t id = 1, missing = 0; missing < kGap && id < (std::int64_t{1} << 47); ++id) {
    sqlite3_reset(st);
    sqlite3_bind_int64(st, 1, id);
    if (sqlite3_step(st) == SQLITE_ROW) {
      found.emplace_back(sqlite3_column_int64(st, 0), id);
      missing = 0;
    } else {
      ++missing;
    }
  }
  sqlite3_finalize(st);
  std::sort(found.begin(), found.end());
  return found;
}

}  // namespace

Db3Reader::Db3Reader(std::vector<std::string> files, std::string label)
    : files_(std::move(files)), label_(std::move(label)) {
  if (files_.empty()) throw InputError(label_ + ": no .db3 file");
  if (label_.empty()) label_ = files_.front();
  open(0);
}

Db3Reader::~Db3Reader() = default;

std::string Db3Reader::filePrefix() const {
  return files_.size() > 1 ? std::filesystem::path(files_[file_]).filename().string() + ": " : std::string();
}

std::string Db3Reader::place(std::uint64_t offset) const {
  // offset: the file's index in the high bits, the row id below.
  const std::uint64_t file = offset >> 48, row = offset & ((std::uint64_t{1} << 48) - 1);
  return (files_.size() > 1
              ? std::filesystem::path(files_[std::min<std::size_t>(file, files_.size() - 1)]).filename().string() + " "
              : std::string()) +
         "row " + std::to_string(row);
}

void Db3Reader::open(std::size_t index) {
  file_ = index;
  db_ = std::make_unique<Db>();
  const std::string& path = files_[index];
  auto fail = [&](const std::string& problem) -> void {
    throw InputError(InputLocation{path, 0, 0, "sqlite3"}, problem);
  };
  unsigned char header[100] = {};  // the magic, then what the header declares
  std::streamsize got = 0;
  {
    std::ifstream in(path, std::ios::binary);
    if (in) got = in.read(reinterpret_cast<char*>(header), sizeof header).gcount();
    if (got < 16) fail("cannot be opened");
    if (std::memcmp(header, "SQLite format 3", 16) != 0) fail("not an SQLite database (rosbag2 .db3)");
  }
  std::error_code size_error;
  const std::uint64_t size = std::filesystem::file_size(path, size_error),
                      declared = got == 100 ? declaredBytes(header) : 0;
  const bool cut = !size_error && declared > size;
  if (sqlite3_open_v2(path.c_str(), &db_->db, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX,
                      cut ? wholePagesVfs() : nullptr) != SQLITE_OK)
    fail(std::string("cannot be opened: ") + (db_->db ? db3Message(db_->db) : "out of memory"));
  // Nothing in the file's schema runs as trusted code; no value is longer than the file could
  // hold; the work of every query is bounded by the file's size.
  sqlite3_db_config(db_->db, SQLITE_DBCONFIG_TRUSTED_SCHEMA, 0, nullptr);
  const std::uint64_t bytes = size_error ? 0 : size;
  sqlite3_limit(db_->db, SQLITE_LIMIT_LENGTH,
                static_cast<int>(std::min<std::uint64_t>(bytes + (1u << 20), 1000000000u)));
  db_->max_ticks = (256 * bytes + 200'000'000) / 1000;
  sqlite3_progress_handler(db_->db, 1000, &Db::onProgress, db_.get());
  {
    // A file shorter than its header declares was cut short (a recorder killed, a copy stopped):
    // sqlite3 then refuses its schema, whose later tables' pages are gone. Reading with the schema
    // taken as it is lets the rows that remain be found one by one.
    if (cut) {
      db_->salvage = true;
      db_->cut =
          "cut short at byte " + std::to_string(size) + " of the " + std::to_string(declared) + " its header declares";
      sqlite3_exec(db_->db, "PRAGMA writable_schema=ON", nullptr, nullptr, nullptr);
    }
  }
  auto query = [&](const char* sql) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(db_->db, sql, -1, &st, nullptr) != SQLITE_OK) {
      const std::string msg = db3Message(db_->db);
      if (st) sqlite3_finalize(st);
      return std::make_pair(static_cast<sqlite3_stmt*>(nullptr), msg);
    }
    return std::make_pair(st, std::string());
  };
  // rosbag2 writes tables: a view (which can compute rows without end) in their place is refused.
  if (sqlite3_stmt* st =
          query(
              "SELECT name, type FROM sqlite_master WHERE lower(name) IN ('messages', 'topics', 'message_definitions')")
              .first) {
    while (sqlite3_step(st) == SQLITE_ROW)
      if (columnText(st, 1) != "table") {
        const std::string what = columnText(st, 0) + "' is a " + columnText(st, 1);
        sqlite3_finalize(st);
        fail("'" + printable(what, 60) + ", not a table (a rosbag2 file holds tables)");
      }
    sqlite3_finalize(st);
  }
  // The stored definitions (rosbag2 Jazzy and later: message_definitions), by type.
  std::map<std::string, std::pair<std::string, std::string>> stored;  // type -> (encoding, text)
  if (sqlite3_stmt* st =
          query("SELECT topic_type, encoding, encoded_message_definition FROM message_definitions").first) {
    while (sqlite3_step(st) == SQLITE_ROW) stored[columnText(st, 0)] = {columnText(st, 1), columnText(st, 2)};
    sqlite3_finalize(st);
  }
  const auto damaged = [&] {
    const int code = sqlite3_errcode(db_->db) & 0xff;
    return code == SQLITE_CORRUPT || code == SQLITE_NOTADB;
  };
  const std::string recover = " (sqlite3's .recover command may save the rows that are left)";
  const auto topics_query = query("SELECT id, name, type, serialization_format FROM topics");
  sqlite3_stmt* const topics = topics_query.first;
  const std::string& terr = topics_query.second;
  if (!topics)
    fail(damaged() ? "damaged: " + terr + recover : "no topics table (" + terr + "): not a rosbag2 sqlite3 file");
  topic_ids_.clear();
  int rc = 0;
  while ((rc = sqlite3_step(topics)) == SQLITE_ROW) {
    const std::int64_t id = sqlite3_column_int64(topics, 0);
    const std::string name = columnText(topics, 1), type = columnText(topics, 2), format = columnText(topics, 3);
    auto [it, fresh] = channel_of_topic_.try_emplace(name, static_cast<std::uint16_t>(channels_.size() + 1));
    if (fresh) {
      if (channels_.size() >= 65000) {
        sqlite3_finalize(topics);
        fail("more than 65000 topics");
      }
      Channel c;
      c.id = it->second;
      c.topic = name;
      c.message_encoding = format;
      // The schema: the stored definition, else the built-in one, else none (counted, not decoded).
      std::string encoding = "ros2msg", text_def;
      if (const auto s = stored.find(type); s != stored.end() && !s->second.second.empty()) {
        encoding = s->second.first == "ros2idl" ? "ros2idl" : "ros2msg";
        text_def = s->second.second;
      } else {
        text_def = builtinDefinition(type);
        if (!text_def.empty()) c.metadata.emplace_back("kccd_definition", "built in");
      }
      if (!text_def.empty()) {
        Schema s;
        s.id = c.id;
        s.name = type;
        s.encoding = encoding;
        s.data = text_def;
        schemas_[s.id] = s;
        c.schema_id = s.id;
      } else {
        c.metadata.emplace_back("kccd_no_definition", type);
      }
      channels_[c.id] = c;
    }
    topic_ids_[id] = it->second;
  }
  sqlite3_finalize(topics);
  if (rc != SQLITE_DONE)
    fail(std::string("the topics table cannot be read: ") + db3Message(db_->db) + (damaged() ? recover : ""));
  if (db_->salvage) {
    db_->found = salvageRows(db_->db);
    db_->row_by_id = query("SELECT id, topic_id, timestamp, data FROM messages WHERE id = ?").first;
    if (!db_->row_by_id || db_->found.empty()) fail(db_->cut + ", and no message row is left in what remains");
    return;
  }
  const auto rows_query = query("SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
  sqlite3_stmt* const rows = rows_query.first;
  const std::string& merr = rows_query.second;
  if (!rows)
    fail(damaged() ? "damaged: " + merr + recover : "no messages table (" + merr + "): not a rosbag2 sqlite3 file");
  db_->rows = rows;
}

bool Db3Reader::next(LogMessage& out) {
  for (;;) {
    if (!db_) return false;
    sqlite3_stmt* const st = db_->salvage ? db_->row_by_id : db_->rows;
    int rc = SQLITE_DONE;
    if (!db_->salvage) {
      rc = sqlite3_step(st);
    } else {
      // The next row found that still reads whole; one that does not is skipped and counted.
      while (db_->next < db_->found.size()) {
        sqlite3_reset(st);
        sqlite3_bind_int64(st, 1, db_->found[db_->next++].second);
        if ((rc = sqlite3_step(st)) == SQLITE_ROW) break;
        rc = SQLITE_DONE;
      }
    }
    if (rc == SQLITE_ROW) {
      const std::int64_t row = sqlite3_column_int64(st, 0);
      const std::int64_t topic = sqlite3_column_int64(st, 1);
      const std::int64_t stamp = sqlite3_column_int64(st, 2);
      const auto t = topic_ids_.find(topic);
      if (t == topic_ids_.end())
        throw InputError(InputLocation{files_[file_], 0, 0, "row " + std::to_string(row)},
                         "a message of topic id " + std::to_string(topic) + ", which the topics table does not list");
      const void* blob = sqlite3_column_blob(st, 3);
      const int bytes = sqlite3_column_bytes(st, 3);
      data_.assign(static_cast<const std::uint8_t*>(blob), static_cast<const std::uint8_t*>(blob) + (blob ? bytes : 0));
      const Channel& c = channels_.at(t->second);
      out.channel = &c;
      out.schema = c.schema_id ? &schemas_.at(c.schema_id) : nullptr;
      out.sequence = static_cast<std::uint32_t>(row);
      out.log_time = out.publish_time = static_cast<std::uint64_t>(std::max<std::int64_t>(stamp, 0));
      out.data = data_;
      out.offset = (static_cast<std::uint64_t>(file_) << 48) |
                   (static_cast<std::uint64_t>(row) & ((std::uint64_t{1} << 48) - 1));
      ++row_;
      return true;
    }
    if (rc != SQLITE_DONE) {
      // A file cut short or damaged: what was read stands, with the damage named.
      damage_ = filePrefix() +
                (db_->exhausted() ? std::string("reading stopped: far more work than a file of this size needs")
                                  : db3Message(db_->db)) +
                " (after " + std::to_string(row_) + " messages)";
      db_.reset();
      return false;
    }
    if (db_->salvage && damage_.empty())
      damage_ = filePrefix() + db_->cut + " (the message rows it still holds are read)";
    if (file_ + 1 >= files_.size()) {
      db_.reset();
      return false;
    }
    open(file_ + 1);
  }
}

}  // namespace kccd::logs
