#include "netvmo/pipeline/ros/rosbag.hpp"

#include <sqlite3.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <fstream>
#include <map>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"

namespace netvmo::ros {
namespace fs = std::filesystem;

namespace {

// A whole number of a metadata.yaml key (counts and nanoseconds need 64 bits).
std::int64_t int64_of(const io::Value& v) {
  try {
    const auto x = v.node().as<long long>();
    if (x < 0) v.fail("expected a non-negative whole number");
    return x;
  } catch (const YAML::Exception&) {
    v.fail("expected a whole number");
  }
}

// One prepared statement, finalized on every path.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql, const std::string& where) : where_(where) {
    if (sqlite3_prepare_v2(db, sql, -1, &st_, nullptr) != SQLITE_OK) fail(db);
  }
  ~Statement() { sqlite3_finalize(st_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt* get() { return st_; }
  /// Next row (true), end (false), or an InputError naming the database.
  bool step() {
    const int rc = sqlite3_step(st_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail(sqlite3_db_handle(st_));
  }
  [[noreturn]] void fail(sqlite3* db) const {
    throw InputError(where_ +
                     ": cannot be read as a rosbag2 sqlite3 database: " + sqlite3_errmsg(db));
  }

 private:
  std::string where_;
  sqlite3_stmt* st_ = nullptr;
};

std::string text(sqlite3_stmt* st, int col) {
  const unsigned char* t = sqlite3_column_text(st, col);
  return t ? reinterpret_cast<const char*>(t) : "";
}

}  // namespace

struct RosBag::Db {
  sqlite3* db = nullptr;
  std::string name;  // for messages
  ~Db() { sqlite3_close(db); }
};

bool RosBag::is_bag(const fs::path& dir) {
  return fs::is_regular_file(dir / "metadata.yaml");
}

RosBag::RosBag(const fs::path& dir) : dir_(dir) {
  const fs::path meta_file = dir / "metadata.yaml";
  io::MapReader root = io::MapReader::from_file(meta_file);
  // Newer rosbag2 versions add keys: only those read here are checked.
  io::MapReader info = root.get("rosbag2_bagfile_information").map();
  const io::Value version = info.get("version");
  if (int64_of(version) < 4)
    version.fail("rosbag2 metadata version " + version.string() +
                 " is older than 4, which this reader knows");
  const io::Value storage = info.get("storage_identifier");
  if (storage.string() == "mcap")
    storage.fail(
        "mcap: MCAP bags are not read (no MCAP library in Debian 12); convert the bag to the "
        "sqlite3 storage with `ros2 bag convert -i BAG -o out.yaml`, out.yaml holding "
        "`output_bags: [{uri: BAG_SQLITE, storage_id: sqlite3, all: true}]`");
  if (storage.string() != "sqlite3")
    storage.fail("'" + storage.string() + "' storage is not read (only sqlite3)");
  if (auto c = info.find("compression_format"); c && !c->is_null() && !c->string().empty())
    c->fail("'" + c->string() +
            "': compressed bags are not read; decompress with `ros2 bag decompress` first");
  for (const io::Value& p : info.get("relative_file_paths").sequence())
    files_.push_back(dir / p.string());
  if (files_.empty()) info.fail("relative_file_paths: no storage file listed");
  if (auto twmc = info.find("topics_with_message_count"))
    for (const io::Value& t : twmc->sequence()) {
      io::MapReader tm = t.map();
      io::MapReader md = tm.get("topic_metadata").map();
      BagTopic topic;
      topic.name = md.get("name").string();
      topic.type = md.get("type").string();
      topic.serialization_format = md.get("serialization_format").string();
      topic.message_count = static_cast<std::uint64_t>(int64_of(tm.get("message_count")));
      if (topic.serialization_format != "cdr")
        md.get("serialization_format")
            .fail("'" + topic.serialization_format + "' is not read (only cdr)");
      topics_.push_back(topic);
    }

  // The databases: each topic's messages counted, summed over the files, against metadata.yaml.
  std::map<std::string, std::pair<std::string, std::uint64_t>> in_db;  // name -> (type, count)
  for (const fs::path& f : files_) {
    auto db = std::make_unique<Db>();
    db->name = f.string();
    if (!fs::is_regular_file(f))
      throw InputError(meta_file.string() + ": relative_file_paths: " + f.string() +
                       " does not exist");
    if (sqlite3_open_v2(f.c_str(), &db->db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
      throw InputError(f.string() +
                       ": cannot be opened as an SQLite database: " + sqlite3_errmsg(db->db));
    // One pass over the messages counts them per topic (the table has no index on topic_id).
    Statement topics(db->db,
                     "SELECT t.name, t.type, IFNULL(c.n, 0) FROM topics t LEFT JOIN "
                     "(SELECT topic_id, COUNT(*) AS n FROM messages GROUP BY topic_id) c "
                     "ON c.topic_id = t.id",
                     f.string());
    while (topics.step()) {
      auto& e = in_db[text(topics.get(), 0)];
      e.first = text(topics.get(), 1);
      e.second += static_cast<std::uint64_t>(sqlite3_column_int64(topics.get(), 2));
    }
    // Every message belongs to a topic of the table (a truncated file fails here too).
    Statement orphans(db->db,
                      "SELECT COUNT(*) FROM messages WHERE topic_id NOT IN (SELECT id FROM topics)",
                      f.string());
    if (orphans.step() && sqlite3_column_int64(orphans.get(), 0) > 0)
      throw InputError(f.string() + ": " + std::to_string(sqlite3_column_int64(orphans.get(), 0)) +
                       " message(s) of no topic in its topics table");
    dbs_.push_back(std::move(db));
  }
  for (const BagTopic& t : topics_) {
    const auto it = in_db.find(t.name);
    if (it == in_db.end())
      throw InputError(meta_file.string() + ": topic " + t.name +
                       " is not in the database (metadata.yaml disagrees with the .db3 files)");
    if (it->second.first != t.type || it->second.second != t.message_count)
      throw InputError(meta_file.string() + ": topic " + t.name + ": " + t.type + ", " +
                       std::to_string(t.message_count) + " message(s), but the .db3 files hold " +
                       it->second.first + ", " + std::to_string(it->second.second) +
                       " (metadata.yaml disagrees with the database)");
  }
  for (const auto& [name, e] : in_db)
    if (!find_topic(name))
      throw InputError(meta_file.string() + ": topics_with_message_count: no entry for " + name +
                       ", which the .db3 files hold (metadata.yaml disagrees with the database)");
}

RosBag::~RosBag() = default;
RosBag::RosBag(RosBag&&) noexcept = default;
RosBag& RosBag::operator=(RosBag&&) noexcept = default;

const BagTopic* RosBag::find_topic(const std::string& name) const {
  for (const auto& t : topics_)
    if (t.name == name) return &t;
  return nullptr;
}

std::vector<BagMessageRef> RosBag::messages(const std::string& topic) const {
  std::vector<BagMessageRef> out;
  for (std::size_t f = 0; f < dbs_.size(); ++f) {
    Statement st(dbs_[f]->db,
                 "SELECT m.id, m.timestamp FROM messages m JOIN topics t ON m.topic_id = t.id "
                 "WHERE t.name = ?1 ORDER BY m.timestamp, m.id",
                 dbs_[f]->name);
    sqlite3_bind_text(st.get(), 1, topic.c_str(), -1, SQLITE_TRANSIENT);
    while (st.step())
      out.push_back({sqlite3_column_int64(st.get(), 1), f, sqlite3_column_int64(st.get(), 0)});
  }
  std::stable_sort(out.begin(), out.end(), [](const BagMessageRef& a, const BagMessageRef& b) {
    return a.timestamp < b.timestamp;
  });
  return out;
}

std::vector<std::uint8_t> RosBag::read(const BagMessageRef& m, std::size_t max_bytes) const {
  const Db& db = *dbs_.at(m.file);
  Statement st(db.db, "SELECT substr(data, 1, ?1) FROM messages WHERE id = ?2", db.name);
  sqlite3_bind_int64(st.get(), 1,
                     static_cast<sqlite3_int64>(std::min<std::size_t>(max_bytes, 1u << 30)));
  sqlite3_bind_int64(st.get(), 2, m.row);
  if (!st.step()) throw InputError(where(m) + ": no such message");
  const auto* p = static_cast<const std::uint8_t*>(sqlite3_column_blob(st.get(), 0));
  const int n = sqlite3_column_bytes(st.get(), 0);
  return p ? std::vector<std::uint8_t>(p, p + n) : std::vector<std::uint8_t>{};
}

std::string RosBag::where(const BagMessageRef& m) const {
  return dbs_.at(m.file)->name + " row " + std::to_string(m.row);
}

struct RosBagWriter::Db {
  sqlite3* db = nullptr;
  sqlite3_stmt* insert = nullptr;
  ~Db() {
    sqlite3_finalize(insert);
    sqlite3_close(db);
  }
};

namespace {
void exec(sqlite3* db, const char* sql, const std::string& file) {
  char* err = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw InputError(file + ": cannot write the bag's database: " + msg);
  }
}
}  // namespace

RosBagWriter::RosBagWriter(const fs::path& dir) : dir_(dir), db_(std::make_unique<Db>()) {
  if (fs::exists(dir) && !(fs::is_directory(dir) && fs::is_empty(dir)))
    throw InputError(dir.string() +
                     ": exists and is not an empty folder; a bag is not written "
                     "over anything");
  fs::create_directories(dir);
  const fs::path file = dir / "bag_0.db3";
  if (sqlite3_open_v2(file.c_str(), &db_->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                      nullptr) != SQLITE_OK)
    throw InputError(file.string() + ": cannot be created: " + sqlite3_errmsg(db_->db));
  exec(db_->db,
       "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
       "INSERT INTO schema VALUES (3, 'humble');"
       "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
       "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
       "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
       "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
       "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
       "BEGIN;",
       file.string());
  if (sqlite3_prepare_v2(db_->db,
                         "INSERT INTO messages(topic_id, timestamp, data) VALUES (?1, ?2, ?3)", -1,
                         &db_->insert, nullptr) != SQLITE_OK)
    throw InputError(file.string() + ": " + sqlite3_errmsg(db_->db));
}

RosBagWriter::~RosBagWriter() = default;

int RosBagWriter::add_topic(const std::string& name, const std::string& type) {
  const int id = static_cast<int>(topics_.size()) + 1;
  sqlite3_stmt* st = nullptr;
  const std::string file = (dir_ / "bag_0.db3").string();
  if (sqlite3_prepare_v2(db_->db,
                         "INSERT INTO topics(id, name, type, serialization_format, "
                         "offered_qos_profiles) VALUES (?1, ?2, ?3, 'cdr', '')",
                         -1, &st, nullptr) != SQLITE_OK)
    throw InputError(file + ": " + sqlite3_errmsg(db_->db));
  sqlite3_bind_int(st, 1, id);
  sqlite3_bind_text(st, 2, name.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(st, 3, type.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  if (rc != SQLITE_DONE) throw InputError(file + ": " + sqlite3_errmsg(db_->db));
  topics_.push_back({name, type, "cdr", 0});
  return id;
}

void RosBagWriter::write(int topic, std::int64_t timestamp_ns,
                         const std::vector<std::uint8_t>& data) {
  sqlite3_stmt* st = db_->insert;
  sqlite3_reset(st);
  sqlite3_bind_int(st, 1, topic);
  sqlite3_bind_int64(st, 2, timestamp_ns);
  sqlite3_bind_blob(st, 3, data.data(), static_cast<int>(data.size()), SQLITE_TRANSIENT);
  if (sqlite3_step(st) != SQLITE_DONE)
    throw InputError((dir_ / "bag_0.db3").string() + ": " + sqlite3_errmsg(db_->db));
  ++topics_.at(static_cast<std::size_t>(topic - 1)).message_count;
  ++count_;
  first_ = std::min(first_, timestamp_ns);
  last_ = std::max(last_, timestamp_ns);
}

void RosBagWriter::close() {
  if (closed_) return;
  closed_ = true;
  exec(db_->db, "COMMIT;", (dir_ / "bag_0.db3").string());
  const std::int64_t start = count_ ? first_ : 0, duration = count_ ? last_ - first_ : 0;
  YAML::Emitter y;
  y << YAML::BeginMap << YAML::Key << "rosbag2_bagfile_information" << YAML::Value
    << YAML::BeginMap;
  y << YAML::Key << "version" << YAML::Value << 5;
  y << YAML::Key << "storage_identifier" << YAML::Value << "sqlite3";
  y << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
    << YAML::Value << duration << YAML::EndMap;
  y << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
    << "nanoseconds_since_epoch" << YAML::Value << start << YAML::EndMap;
  y << YAML::Key << "message_count" << YAML::Value << count_;
  y << YAML::Key << "topics_with_message_count" << YAML::Value << YAML::BeginSeq;
  for (const BagTopic& t : topics_) {
    y << YAML::BeginMap << YAML::Key << "topic_metadata" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "name" << YAML::Value << t.name << YAML::Key << "type" << YAML::Value
      << t.type << YAML::Key << "serialization_format" << YAML::Value << "cdr" << YAML::Key
      << "offered_qos_profiles" << YAML::Value << "";
    y << YAML::EndMap << YAML::Key << "message_count" << YAML::Value << t.message_count
      << YAML::EndMap;
  }
  y << YAML::EndSeq;
  y << YAML::Key << "compression_format" << YAML::Value << "" << YAML::Key << "compression_mode"
    << YAML::Value << "";
  y << YAML::Key << "relative_file_paths" << YAML::Value << YAML::BeginSeq << "bag_0.db3"
    << YAML::EndSeq;
  y << YAML::Key << "files" << YAML::Value << YAML::BeginSeq << YAML::BeginMap << YAML::Key
    << "path" << YAML::Value << "bag_0.db3" << YAML::Key << "starting_time" << YAML::Value
    << YAML::BeginMap << YAML::Key << "nanoseconds_since_epoch" << YAML::Value << start
    << YAML::EndMap << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key
    << "nanoseconds" << YAML::Value << duration << YAML::EndMap << YAML::Key << "message_count"
    << YAML::Value << count_ << YAML::EndMap << YAML::EndSeq;
  y << YAML::EndMap << YAML::EndMap;
  const fs::path meta = dir_ / "metadata.yaml";
  std::ofstream out(meta);
  out << y.c_str() << "\n";
  if (!out) throw InputError(meta.string() + ": cannot be written");
}

}  // namespace netvmo::ros
