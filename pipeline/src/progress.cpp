#include "netvmo/pipeline/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace netvmo {

Progress::Progress(std::string label, long total, bool enabled)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled),
      tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

void Progress::update(long done) {
  if (!enabled_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_).count();
  if (done < total_ && since_last < (tty_ ? 0.1 : 5.0)) return;
  last_ = now;
  const double el = std::chrono::duration<double>(now - start_).count();
  const double rate = el > 0 ? done / el : 0.0;
  const double left = rate > 0 ? (total_ - done) / rate : 0.0;
  const int width = 30;
  const int fill = total_ > 0 ? static_cast<int>(width * done / total_) : width;
  std::string bar(static_cast<size_t>(fill), '#');
  bar.resize(width, '.');
  std::fprintf(stderr, "%s%s [%s] %ld/%ld  %.1f/s  %.0fs left%s", tty_ ? "\r" : "", label_.c_str(),
               bar.c_str(), done, total_, rate, left, tty_ ? "" : "\n");
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  const double el =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s: %ld done in %.1fs%s\n", tty_ ? "\r" : "", label_.c_str(), total_, el,
               tty_ ? "                              " : "");
}

}  // namespace netvmo
