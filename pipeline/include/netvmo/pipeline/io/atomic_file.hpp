// Small output helpers: files are written to a temporary sibling and renamed into place on
// commit, so a failure part-way never leaves a truncated or corrupted result behind.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace netvmo::io {

/// An output file that appears at `path` only when commit() succeeds.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();  // discards the temporary file if commit() was not called
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ofstream& stream() { return out_; }
  template <class T>
  AtomicFile& operator<<(const T& v) {
    out_ << v;
    return *this;
  }
  /// Flushes, closes and renames into place; throws InputError naming the file on failure.
  void commit();

 private:
  std::filesystem::path path_, tmp_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes a whole file atomically.
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

/// Creates a directory (and parents); throws InputError naming it if that fails.
void ensure_directory(const std::filesystem::path& dir);

/// `v` as text that reads back as the same double (printf's %.17g): the numbers of CSV rows,
/// calibration files and command lines that another process reads.
std::string exact_text(double v);

}  // namespace netvmo::io
