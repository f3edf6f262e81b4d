#include "netvmo/pipeline/net/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;

fs::path self_exe() {
  return fs::read_symlink("/proc/self/exe");
}

pid_t spawn(const std::vector<std::string>& argv, const fs::path& log) {
  if (argv.empty()) throw std::invalid_argument("spawn: empty command");
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const std::string log_path = log.string();
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    // The child dies with its parent (SIGKILL from the kernel when the parent ends, however it
    // ends): a supervisor killed mid-run leaves no node behind. getppid() catches a parent that
    // died before prctl.
    if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) ::_exit(127);
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    ::execv(args[0], args.data());
    std::fprintf(stderr, "cannot start %s: %s\n", args[0], std::strerror(errno));
    ::_exit(127);
  }
  return pid;
}

bool has_exited(pid_t pid) {
  siginfo_t info{};
  return ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 &&
         info.si_pid == pid;
}

std::vector<ChildResult> supervise(const std::vector<pid_t>& pids_in, double timeout_s,
                                   bool kill_on_failure, const KillPlan* plan) {
  std::vector<pid_t> pids = pids_in;
  enum class Plan { waiting, killed, restarted } plan_state = Plan::waiting;
  bool awaiting = false;  // the planned victim is dead (reaped) and waits for its restart
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  std::vector<ChildResult> res(pids.size());
  std::vector<bool> done(pids.size(), false);
  size_t left = pids.size();
  bool killing = false;
  double kill_time = 0.0;
  double kill_epoch = 0.0;  // when the planned victim was killed
  for (size_t i = 0; i < pids.size(); ++i) res[i].pid = pids[i];
  // Stops every child still running (SIGTERM now, SIGKILL two seconds later, below).
  const auto stop_all = [&] {
    killing = true;
    kill_time = elapsed();
    if (awaiting) {  // the planned victim was never restarted: nothing to kill there
      done[plan->index] = true;
      --left;
      awaiting = false;
    }
    for (size_t k = 0; k < pids.size(); ++k)
      if (!done[k]) {
        res[k].killed = true;
        ::kill(pids[k], SIGTERM);
      }
  };
  while (left > 0) {
    for (size_t i = 0; i < pids.size(); ++i) {
      if (done[i] || (awaiting && i == plan->index)) continue;
      int status = 0;
      const pid_t r = ::waitpid(pids[i], &status, WNOHANG);
      if (r != pids[i]) continue;
      done[i] = true;
      --left;
      res[i].seconds = elapsed();
      if (WIFEXITED(status)) {
        res[i].finished = true;
        res[i].exit_code = WEXITSTATUS(status);
      } else if (WIFSIGNALED(status)) {
        res[i].signal = WTERMSIG(status);
      }
      if (plan && i == plan->index && plan_state == Plan::killed && !res[i].finished) {
        res[i].planned_kill = true;  // our own SIGKILL: not a failure
        if (plan->restart_after >= 0) {
          done[i] = false;  // it comes back
          ++left;
          awaiting = true;
        }
        continue;
      }
      const bool failed = !res[i].finished || res[i].exit_code != 0;
      if (failed && kill_on_failure && !killing) stop_all();
    }
    if (left == 0) break;
    if (plan && !killing && plan->index < pids.size()) {
      const size_t i = plan->index;
      if (plan_state == Plan::waiting && elapsed() >= plan->kill_at && !done[i]) {
        ::kill(pids[i], SIGKILL);
        kill_epoch = epoch_seconds();
        res[i].kill_epoch = kill_epoch;
        plan_state = Plan::killed;
      } else if (plan_state == Plan::killed && plan->restart_after >= 0 && res[i].planned_kill &&
                 elapsed() >= plan->kill_at + plan->restart_after) {
        pids[i] = spawn(plan->argv, plan->log);
        res[i] = ChildResult{};
        res[i].pid = pids[i];
        res[i].restarted = true;
        res[i].kill_epoch = kill_epoch;
        res[i].restart_epoch = epoch_seconds();
        plan_state = Plan::restarted;
        awaiting = false;
      }
    }
    if (!killing && elapsed() > timeout_s) stop_all();
    if (killing && elapsed() > kill_time + 2.0)
      for (size_t k = 0; k < pids.size(); ++k)
        if (!done[k]) ::kill(pids[k], SIGKILL);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return res;
}

std::string describe(const ChildResult& r) {
  std::string s = r.finished ? "exit " + std::to_string(r.exit_code)
                             : "killed by signal " + std::to_string(r.signal);
  if (r.planned_kill) s += " (planned)";
  if (r.restarted) s += " (restarted)";
  if (r.killed) s += " (stopped by the supervisor)";
  return s;
}

}  // namespace netvmo::net
