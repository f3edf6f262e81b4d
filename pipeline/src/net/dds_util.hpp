// Cyclone DDS's C API with errors as exceptions, for the sources of src/net/.
#pragma once

#include <dds/dds.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace netvmo::net::detail {

/// `rc` when it is not an error (an entity, a count); otherwise throws std::runtime_error
/// "Cyclone DDS: <what>: <Cyclone's reason>".
inline dds_return_t check(dds_return_t rc, const char* what) {
  if (rc < 0)
    throw std::runtime_error(std::string("Cyclone DDS: ") + what + ": " + dds_strretcode(rc));
  return rc;
}

/// A read condition on `reader` and a waitset attached to it, for blocking reads.
inline void make_waitset(dds_entity_t participant, dds_entity_t reader, dds_entity_t& readcond,
                         dds_entity_t& waitset) {
  readcond = check(dds_create_readcondition(reader, DDS_ANY_STATE), "create read condition");
  waitset = check(dds_create_waitset(participant), "create waitset");
  check(dds_waitset_attach(waitset, readcond, 0), "attach read condition");
}

/// How many readers match writer `w` now.
inline int matched_readers(dds_entity_t w) {
  dds_publication_matched_status_t st;
  check(dds_get_publication_matched_status(w, &st), "matched status");
  return static_cast<int>(st.current_count);
}

/// Waits until every writer of `writers` matches at least `n` readers, at most `timeout_s`
/// (polled every 10 ms); false when they did not come.
inline bool wait_for_readers(const std::vector<dds_entity_t>& writers, int n, double timeout_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    if (std::all_of(writers.begin(), writers.end(),
                    [n](dds_entity_t w) { return matched_readers(w) >= n; }))
      return true;
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

/// Whether a best-effort reader matches writer `w` now (it acknowledges nothing, so
/// dds_wait_for_acks does not wait for it). More matched readers than 256: assumed so.
inline bool has_best_effort_reader(dds_entity_t w) {
  std::vector<dds_instance_handle_t> handles(256);
  const dds_return_t n = check(dds_get_matched_subscriptions(w, handles.data(), handles.size()),
                               "matched subscriptions");
  if (static_cast<size_t>(n) > handles.size()) return true;
  for (dds_return_t i = 0; i < n; ++i) {
    dds_builtintopic_endpoint_t* e = dds_get_matched_subscription_data(w, handles[i]);
    if (!e) continue;  // unmatched meanwhile
    dds_reliability_kind_t kind = DDS_RELIABILITY_RELIABLE;
    dds_duration_t blocking = 0;
    const bool best_effort = e->qos && dds_qget_reliability(e->qos, &kind, &blocking) &&
                             kind == DDS_RELIABILITY_BEST_EFFORT;
    dds_builtintopic_free_endpoint(e);
    if (best_effort) return true;
  }
  return false;
}

}  // namespace netvmo::net::detail
