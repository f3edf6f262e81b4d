#include "netvmo/pipeline/io/yaml_reader.hpp"

#include <cstdio>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::io {

std::string format_number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

YAML::Node load_file(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) throw InputError(file.string() + ": file not found");
  try {
    return YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    throw InputError(file.string() + ": invalid YAML at line " + std::to_string(e.mark.line + 1) +
                     ": " + e.msg);
  }
}

void Value::fail(const std::string& what) const {
  throw InputError(file_ + ": " + (path_.empty() ? std::string("(root)") : path_) + ": " + what);
}

double Value::number() const {
  if (!node_ || !node_.IsScalar()) fail("expected a number");
  try {
    return node_.as<double>();
  } catch (const YAML::Exception&) {
    fail("expected a number, got '" + node_.Scalar() + "'");
  }
}

int Value::integer() const {
  if (!node_ || !node_.IsScalar()) fail("expected an integer");
  try {
    return node_.as<int>();
  } catch (const YAML::Exception&) {
    fail("expected an integer, got '" + node_.Scalar() + "'");
  }
}

bool Value::boolean() const {
  if (!node_ || !node_.IsScalar()) fail("expected true or false");
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    fail("expected true or false, got '" + node_.Scalar() + "'");
  }
}

std::string Value::string() const {
  if (!node_ || !node_.IsScalar()) fail("expected a string");
  return node_.Scalar();
}

std::vector<double> Value::numbers() const {
  if (!node_ || !node_.IsSequence()) fail("expected a list of numbers");
  std::vector<double> out;
  for (size_t i = 0; i < node_.size(); ++i)
    out.push_back(Value(node_[i], file_, path_ + "[" + std::to_string(i) + "]").number());
  return out;
}

MapReader Value::map() const {
  if (!node_ || !node_.IsMap()) fail("expected a mapping (key: value)");
  return MapReader(node_, file_, path_);
}

std::vector<Value> Value::sequence() const {
  if (!node_ || !node_.IsSequence()) fail("expected a list");
  std::vector<Value> out;
  for (size_t i = 0; i < node_.size(); ++i)
    out.emplace_back(node_[i], file_, path_ + "[" + std::to_string(i) + "]");
  return out;
}

MapReader::MapReader(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
  if (!node_.IsMap()) fail("expected a mapping (key: value)");
}

MapReader MapReader::from_file(const std::filesystem::path& file) {
  const YAML::Node root = load_file(file);
  if (!root.IsMap()) throw InputError(file.string() + ": expected a mapping at the top level");
  return MapReader(root, file.string(), "");
}

std::string MapReader::child(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void MapReader::fail(const std::string& what) const {
  throw InputError(file_ + ": " + (path_.empty() ? std::string("(root)") : path_) + ": " + what);
}

bool MapReader::has(const std::string& key) const {
  return static_cast<bool>(node_[key]);
}

Value MapReader::get(const std::string& key) {
  used_.insert(key);
  const YAML::Node n = node_[key];
  if (!n || n.IsNull()) throw InputError(file_ + ": " + child(key) + ": missing value");
  return Value(n, file_, child(key));
}

std::optional<Value> MapReader::find(const std::string& key) {
  used_.insert(key);
  const YAML::Node n = node_[key];
  if (!n) return std::nullopt;
  if (n.IsNull()) throw InputError(file_ + ": " + child(key) + ": missing value");
  return Value(n, file_, child(key));
}

double MapReader::get_or(const std::string& key, double fallback) {
  const auto v = find(key);
  return v ? v->number() : fallback;
}
int MapReader::get_or(const std::string& key, int fallback) {
  const auto v = find(key);
  return v ? v->integer() : fallback;
}
std::string MapReader::get_or(const std::string& key, const std::string& fallback) {
  const auto v = find(key);
  return v ? v->string() : fallback;
}
bool MapReader::get_or(const std::string& key, bool fallback) {
  const auto v = find(key);
  return v ? v->boolean() : fallback;
}

void MapReader::finish() const {
  for (const auto& kv : node_) {
    const std::string key = kv.first.Scalar();
    if (!used_.count(key)) throw InputError(file_ + ": " + child(key) + ": unknown key");
  }
}

}  // namespace netvmo::io
