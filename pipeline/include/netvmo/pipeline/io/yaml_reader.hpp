// Strict, self-describing YAML reading on top of yaml-cpp. Every error names the file and the
// key path (e.g. "datasets/paper5.yaml: cameras[2].p_wi: expected 3 numbers") and is thrown as
// InputError. A map reader remembers which keys were read; finish() rejects the others, so a
// misspelt key is an error instead of a silently ignored setting.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace netvmo::io {

/// Shortest text for a number in a message: 9, 0.5, 1e-07.
std::string format_number(double v);

/// Parses a YAML file; throws InputError "<file>: ..." if missing or malformed.
YAML::Node load_file(const std::filesystem::path& file);

class MapReader;

/// A value at a key path inside a file.
class Value {
 public:
  Value(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

  double number() const;
  int integer() const;
  bool boolean() const;
  std::string string() const;
  std::vector<double> numbers() const;
  /// Exactly N numbers.
  template <int N>
  Eigen::Matrix<double, N, 1> vec() const {
    const auto v = numbers();
    if (static_cast<int>(v.size()) != N) fail("expected " + std::to_string(N) + " numbers");
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out[i] = v[static_cast<size_t>(i)];
    return out;
  }
  MapReader map() const;
  std::vector<Value> sequence() const;
  bool is_null() const { return !node_ || node_.IsNull(); }
  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  [[noreturn]] void fail(const std::string& what) const;

 private:
  YAML::Node node_;
  std::string file_, path_;
};

/// A YAML mapping whose keys are checked: get() for required keys, get_or()/find() for optional
/// ones, then finish() to reject keys that were never asked for.
class MapReader {
 public:
  MapReader(YAML::Node node, std::string file, std::string path);
  /// Reads the root mapping of a file.
  static MapReader from_file(const std::filesystem::path& file);

  bool has(const std::string& key) const;
  /// Required key; error "missing key" if absent or empty.
  Value get(const std::string& key);
  /// Optional key.
  std::optional<Value> find(const std::string& key);
  double get_or(const std::string& key, double fallback);
  int get_or(const std::string& key, int fallback);
  std::string get_or(const std::string& key, const std::string& fallback);
  bool get_or(const std::string& key, bool fallback);
  /// Throws naming the first key that was not read.
  void finish() const;
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  [[noreturn]] void fail(const std::string& what) const;

 private:
  std::string child(const std::string& key) const;
  YAML::Node node_;
  std::string file_, path_;
  std::set<std::string> used_;
};

}  // namespace netvmo::io
