// rosbag2 bags in the sqlite3 storage, ROS 2's recording format (`ros2 bag record`), read and
// written without ROS 2: a folder with metadata.yaml and the .db3 files it lists, each an SQLite
// database with the tables `topics` (id, name, type, serialization_format, offered_qos_profiles)
// and `messages` (id, topic_id, timestamp [ns], data: the CDR bytes). Read with SQLite (read
// only); MCAP storage and compressed bags are refused with one line saying how to convert.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace netvmo::ros {

struct BagTopic {
  std::string name;                  ///< e.g. /cam1/image_raw
  std::string type;                  ///< e.g. sensor_msgs/msg/Image
  std::string serialization_format;  ///< cdr
  std::uint64_t message_count = 0;   ///< metadata.yaml's, checked against the database
};

/// Where one message is: its storage file (index into RosBag::files()) and row.
struct BagMessageRef {
  std::int64_t timestamp = 0;  ///< the bag's receive time [ns since the epoch]
  std::size_t file = 0;
  std::int64_t row = 0;
};

class RosBag {
 public:
  /// A folder holding a metadata.yaml: a bag, for whatever takes a dataset folder.
  static bool is_bag(const std::filesystem::path& dir);
  /// Opens a bag: metadata.yaml (rosbag2_bagfile_information: version, storage_identifier
  /// sqlite3, no compression, relative_file_paths, topics_with_message_count), then every file
  /// it lists, whose topics and message counts must be metadata.yaml's. Throws InputError naming
  /// the file and key, or the database and what disagrees.
  explicit RosBag(const std::filesystem::path& dir);
  ~RosBag();
  RosBag(RosBag&&) noexcept;
  RosBag& operator=(RosBag&&) noexcept;

  const std::filesystem::path& dir() const { return dir_; }
  const std::vector<BagTopic>& topics() const { return topics_; }
  const std::vector<std::filesystem::path>& files() const { return files_; }
  /// The topic of that name, or nullptr.
  const BagTopic* find_topic(const std::string& name) const;
  /// Every message of a topic, in the order it was recorded (timestamp, then file and row).
  std::vector<BagMessageRef> messages(const std::string& topic) const;
  /// A message's bytes, at most the first `max_bytes`. Throws InputError naming the database
  /// when the row cannot be read.
  std::vector<std::uint8_t> read(
      const BagMessageRef& m,
      std::size_t max_bytes = std::numeric_limits<std::size_t>::max()) const;
  /// "bag/x.db3 row 12", for messages.
  std::string where(const BagMessageRef& m) const;

 private:
  struct Db;
  std::filesystem::path dir_;
  std::vector<BagTopic> topics_;
  std::vector<std::filesystem::path> files_;
  std::vector<std::unique_ptr<Db>> dbs_;
};

/// Writes a bag in the sqlite3 storage (ROS 2 Humble's layout: metadata.yaml version 5, one file
/// bag_0.db3), for datasets exported to ROS 2 and for the tests. `dir` must not exist or be an
/// empty folder. Messages are written in one transaction; close() writes metadata.yaml.
class RosBagWriter {
 public:
  explicit RosBagWriter(const std::filesystem::path& dir);
  ~RosBagWriter();
  /// Adds a topic (CDR); returns its id for write().
  int add_topic(const std::string& name, const std::string& type);
  void write(int topic, std::int64_t timestamp_ns, const std::vector<std::uint8_t>& data);
  /// Commits the database and writes metadata.yaml. Throws InputError naming the file on failure.
  void close();

 private:
  struct Db;
  std::filesystem::path dir_;
  std::unique_ptr<Db> db_;
  std::vector<BagTopic> topics_;
  std::int64_t first_ = std::numeric_limits<std::int64_t>::max(), last_ = 0;
  std::uint64_t count_ = 0;
  bool closed_ = false;
};

}  // namespace netvmo::ros
