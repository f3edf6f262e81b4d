// Child processes for cameras as processes: start (fork/exec, output to a log file), supervise
// with a time limit, kill. Used by `netvmo launch` and by the tests; never by a signal to a
// process group or by name, only to the children started here.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace netvmo::net {

/// This program's own executable (/proc/self/exe).
std::filesystem::path self_exe();

/// Starts `argv` (argv[0] = the executable's path) with this process's environment, stdout and
/// stderr appended to `log`. The child is killed (SIGKILL) when the calling thread ends, so a
/// supervisor killed mid-run leaves no child running (Linux PR_SET_PDEATHSIG): call it from a
/// thread that outlives the child, e.g. the main thread. Throws std::runtime_error when fork fails.
pid_t spawn(const std::vector<std::string>& argv, const std::filesystem::path& log);

/// True when the child has ended (it is not reaped: supervise() still sees it).
bool has_exited(pid_t pid);

struct ChildResult {
  pid_t pid = 0;
  bool finished = false;  ///< exited on its own (exit_code valid)
  int exit_code = -1;
  int signal = 0;             ///< the signal that ended it (0 if none)
  bool killed = false;        ///< killed here (timeout, or another child failed)
  bool planned_kill = false;  ///< killed by a KillPlan (and not restarted)
  bool restarted = false;     ///< killed by a KillPlan and started again
  double seconds = 0.0;       ///< wall time until it ended
  /// A KillPlan's victim: when it was killed and restarted (wall clock, seconds since the
  /// epoch; 0 = not).
  double kill_epoch = 0.0, restart_epoch = 0.0;
};

/// A fault to inject: child `index` is killed (SIGKILL) `kill_at` seconds after supervision
/// starts and, with `restart_after`, started again (argv, log) that many seconds later.
struct KillPlan {
  size_t index = 0;
  double kill_at = 0.0;
  double restart_after = -1.0;  ///< < 0: not restarted
  std::vector<std::string> argv;
  std::filesystem::path log;
};

/// Waits for every child. After `timeout_s`, or as soon as one child fails (non-zero exit or a
/// signal) when `kill_on_failure`, the remaining ones are killed (SIGTERM, then SIGKILL after
/// 2 s). A planned kill is not a failure (its result has `planned_kill`; after a restart, the
/// result is the new process's). Returns one result per child, in order.
std::vector<ChildResult> supervise(const std::vector<pid_t>& pids, double timeout_s,
                                   bool kill_on_failure, const KillPlan* plan = nullptr);

/// One line describing a result ("exit 0", "exit 3", "killed by signal 9 (timeout)").
std::string describe(const ChildResult& r);

}  // namespace netvmo::net
