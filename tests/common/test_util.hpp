// Helpers shared by the test suites: scratch folders, reading files, running the netvmo binary,
// and checking user-facing errors.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::test {

/// The scratch folders a test program made: removed when it ends with every test passed, kept
/// for a look (and named on stderr) when one failed. One instance per program, appended to
/// GoogleTest's listeners, which own it, on first use.
class ScratchFolders : public ::testing::EmptyTestEventListener {
 public:
  static ScratchFolders& instance() {
    static ScratchFolders* const self = [] {
      auto* l = new ScratchFolders;
      ::testing::UnitTest::GetInstance()->listeners().Append(l);
      return l;
    }();
    return *self;
  }
  void add(const std::filesystem::path& d) {
    if (std::find(dirs_.begin(), dirs_.end(), d) == dirs_.end()) dirs_.push_back(d);
  }
  void OnTestProgramEnd(const ::testing::UnitTest& unit_test) override {
    for (const auto& d : dirs_) {
      if (!unit_test.Passed()) {
        std::error_code ec;
        if (std::filesystem::exists(d, ec))  // (a test may have removed its own)
          std::fprintf(stderr, "scratch folder kept: %s\n", d.c_str());
        continue;
      }
      std::error_code ec;
      std::filesystem::remove_all(d, ec);
      if (ec)
        std::fprintf(stderr, "scratch folder %s not removed: %s\n", d.c_str(),
                     ec.message().c_str());
    }
  }

 private:
  ScratchFolders() = default;
  std::vector<std::filesystem::path> dirs_;
};

/// An empty folder under the system's temporary directory, unique per process (so concurrent
/// test runs never collide); its caller removes it. For programs without GoogleTest.
inline std::filesystem::path make_scratch_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() /
                 ("netvmo_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

/// make_scratch_dir() in a test program: removed when the program passes (ScratchFolders).
inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto d = make_scratch_dir(name);
  ScratchFolders::instance().add(d);
  return d;
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// Writes `text` to `file` (replacing it) and returns the path.
inline std::filesystem::path write_text(const std::filesystem::path& file,
                                        const std::string& text) {
  std::ofstream(file) << text;
  return file;
}

/// `text` with the first occurrence of `from` replaced by `to` (a test's variant of a valid
/// file); fails the test when `from` does not occur.
inline std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "'" << from << "' not in the text";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

struct CliResult {
  int code = -1;
  std::string out, err;
};

/// Runs `netvmo ARGS` from the build folder, capturing stdout and stderr in files under `scratch`.
/// The process is killed after `seconds` (SIGTERM, then SIGKILL 5 s later): no test waits for
/// ever on a child.
inline CliResult run_netvmo(const std::string& args, const std::filesystem::path& scratch,
                            int seconds = 600) {
  const auto out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string cmd = "timeout -k 5 " + std::to_string(seconds) + " " +
                          std::string(NETVMO_BINARY_DIR) + "/netvmo " + args + " > " +
                          out.string() + " 2> " + err.string();
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

/// Runs f and expects an InputError: one line containing every needle.
template <class F>
void expect_input_error(F f, std::initializer_list<std::string> needles) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const auto& n : needles)
      EXPECT_NE(msg.find(n), std::string::npos) << msg << " lacks " << n;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
  }
}

/// A command's standard error is one line holding every needle.
inline void expect_one_line(const std::string& err, std::initializer_list<std::string> needles) {
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one line: " << err;
  for (const auto& n : needles) EXPECT_NE(err.find(n), std::string::npos) << err << " lacks " << n;
}

}  // namespace netvmo::test
