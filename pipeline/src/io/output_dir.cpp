#include "netvmo/pipeline/io/output_dir.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>
#include <utility>
#include <vector>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"

namespace netvmo::io {
namespace fs = std::filesystem;

namespace {

// Absolute, normal, symlinks resolved as far as the path exists, no trailing separator.
fs::path normalized(const fs::path& p) {
  std::error_code ec;
  fs::path n = fs::weakly_canonical(fs::absolute(p), ec);
  if (ec) n = fs::absolute(p).lexically_normal();
  if (n.filename().empty() && n.has_parent_path()) n = n.parent_path();
  return n;
}

bool inside(const fs::path& child, const fs::path& parent) {
  auto c = child.begin();
  for (auto p = parent.begin(); p != parent.end(); ++p, ++c)
    if (c == child.end() || *c != *p) return false;
  return true;
}

std::string sibling_prefix(const fs::path& dir) {
  return dir.filename().string() + ".partial-";
}

bool all_digits(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

std::string read_holder(int fd) {
  char buf[128] = {};
  const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
  std::string s(buf, n > 0 ? static_cast<size_t>(n) : 0);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

// A folder written before the marker existed: it holds the files `command` always writes.
bool legacy_output(const fs::path& dir, const std::string& command) {
  static const std::vector<std::pair<std::string, std::vector<const char*>>> kFiles = {
      {"run", {"summary.json", "estimates.csv", "energies.csv"}},
      {"demo", {"summary.json", "estimates.csv", "dataset/network.yaml"}},
      {"launch", {"summary.json", "estimates.csv", "messages.json"}},
      {"merge", {"summary.json", "estimates.csv", "messages.json"}},
      {"render", {"network.yaml", "truth.csv", "target.csv", "truth_cameras.csv"}},
      {"detect", {"detections.csv"}},
      {"sweep", {"sweep.csv", "inputs.csv"}},
      {"simulate", {"summary.json", "energies.csv", "orientation_x.csv"}},
  };
  for (const auto& [name, files] : kFiles) {
    if (name != command) continue;
    for (const char* f : files)
      if (!fs::is_regular_file(dir / f)) return false;
    return true;
  }
  return false;
}

}  // namespace

fs::path lock_path(const fs::path& dir) {
  const fs::path d = normalized(dir);
  return d.parent_path() / (d.filename().string() + ".lock");
}

OutputDir::OutputDir(fs::path dir, std::string command, bool resume)
    : dir_(normalized(dir)), command_(std::move(command)) {
  const std::string shown = dir.string();
  if (dir_.filename().empty() || dir_ == dir_.root_path())
    throw InputError(shown + ": not usable as an output folder");
  ensure_directory(dir_.parent_path());
  lock_ = lock_path(dir_);
  lock_fd_ = ::open(lock_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0)
    throw InputError(lock_.string() + ": cannot create the output lock: " + std::strerror(errno));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string holder = read_holder(lock_fd_);
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (err != EWOULDBLOCK)
      throw InputError(lock_.string() + ": cannot lock: " + std::strerror(err));
    const auto space = holder.find(' ');
    const std::string pid = holder.substr(0, space);
    const std::string cmd = space == std::string::npos ? "run" : holder.substr(space + 1);
    throw InputError("another netvmo " + cmd + " (pid " + (pid.empty() ? "?" : pid) +
                     ") is writing " + shown);
  }
  const std::string me = std::to_string(::getpid()) + " " + command_ + "\n";
  if (::ftruncate(lock_fd_, 0) != 0 || ::pwrite(lock_fd_, me.data(), me.size(), 0) < 0) {
    // The lock holds without the note; only the message of a second run would lack the pid.
  }
  try {
    // Stale temporary folders of killed runs (only the lock holder creates them). With resume,
    // the newest unfinished one (no marker: not a result killed before or after its swap) is
    // taken over below instead.
    std::error_code ec;
    const std::string prefix = sibling_prefix(dir_);
    std::vector<fs::path> stale;
    for (const auto& e : fs::directory_iterator(dir_.parent_path(), ec)) {
      const std::string name = e.path().filename().string();
      if (name.rfind(prefix, 0) == 0 && all_digits(name.substr(prefix.size())))
        stale.push_back(e.path());
    }
    fs::path taken_over;
    if (resume) {
      fs::file_time_type newest{};
      for (const auto& p : stale) {
        if (fs::exists(p / kOutputMarker, ec) || !fs::is_directory(p, ec)) continue;
        const auto t = fs::last_write_time(p, ec);
        if (!ec && (taken_over.empty() || t > newest)) taken_over = p, newest = t;
      }
    }
    for (const auto& p : stale)
      if (p != taken_over) fs::remove_all(p, ec);
    if (fs::exists(fs::symlink_status(dir_))) {
      if (!fs::is_directory(fs::symlink_status(dir_)))
        throw InputError(shown + ": exists and is not a folder; choose another output folder");
      if (!fs::is_empty(dir_) && !fs::exists(dir_ / kOutputMarker) &&
          !legacy_output(dir_, command_))
        throw InputError(shown + ": exists and was not written by netvmo (no " +
                         std::string(kOutputMarker) +
                         "); it would be replaced whole: remove it or choose another output "
                         "folder");
      if (fs::exists(dir_ / kOutputMarker)) {
        std::ifstream m(dir_ / kOutputMarker);
        std::string by;
        std::getline(m, by);
        if (by != command_)
          throw InputError(shown + ": holds the output of netvmo " + by + ", which netvmo " +
                           command_ +
                           " would replace whole: remove it or choose another output folder");
      }
    }
    staging_ = dir_.parent_path() / (prefix + std::to_string(::getpid()));
    if (taken_over == staging_) {
      // (a predecessor with this process id: already in place)
    } else if (!taken_over.empty()) {
      fs::remove_all(staging_, ec);
      fs::rename(taken_over, staging_, ec);
      if (ec)
        throw InputError(taken_over.string() +
                         ": cannot take over the unfinished folder: " + ec.message());
    } else {
      fs::remove_all(staging_, ec);
      ensure_directory(staging_);
    }
  } catch (...) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw;
  }
}

OutputDir::~OutputDir() {
  if (!committed_ && !staging_.empty()) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
  }
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

void OutputDir::commit() {
  write_file_atomic(staging_ / kOutputMarker, command_ + "\n");
  if (fs::exists(fs::symlink_status(dir_))) {
    // Swap the finished folder and the previous result in one step; the previous one is then
    // under the temporary name, removed below (or, if this process dies first, by the next run).
    if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, dir_.c_str(), RENAME_EXCHANGE) != 0)
      throw InputError(dir_.string() +
                       ": cannot swap the new result into place: " + std::strerror(errno));
  } else if (::rename(staging_.c_str(), dir_.c_str()) != 0) {
    throw InputError(dir_.string() +
                     ": cannot move the result into place: " + std::strerror(errno));
  }
  committed_ = true;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

fs::path OutputDir::keep_failed() {
  const fs::path failed = dir_.parent_path() / (dir_.filename().string() + ".failed");
  std::error_code ec;
  fs::remove_all(failed, ec);
  fs::rename(staging_, failed, ec);
  if (ec) throw InputError(failed.string() + ": cannot keep the failed run: " + ec.message());
  committed_ = true;  // nothing left to remove
  return failed;
}

void check_output_apart(const fs::path& out, const fs::path& dataset, const std::string& option,
                        const std::string& input) {
  const fs::path o = normalized(out);
  if (!dataset.empty()) {
    const fs::path d = normalized(dataset);
    if (o == d)
      throw InputError(option + " " + out.string() + " is the " + input + " " + dataset.string() +
                       ": results would be mixed into it; choose another folder");
    if (inside(o, d))
      throw InputError(option + " " + out.string() + " lies inside the " + input + " " +
                       dataset.string() + "; choose a folder outside it");
    if (inside(d, o))
      throw InputError("the " + input + " " + dataset.string() + " lies inside " + option + " " +
                       out.string() + ", which is replaced whole; choose another folder");
  }
  for (fs::path p = o; !p.empty(); p = p.parent_path()) {
    std::error_code ec;
    if (p != o && fs::exists(p / "network.yaml", ec))
      throw InputError(option + " " + out.string() + " lies inside the dataset folder " +
                       p.string() + "; choose a folder outside it");
    if (p == p.root_path()) break;
  }
}

}  // namespace netvmo::io
