// Every registry has the one form of observer/registry.hpp: entries with unique, non-empty
// names and descriptions, found by name, and an unknown name refused with the known ones.
#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

#include "netvmo/observer/error_model.hpp"
#include "netvmo/observer/estimator.hpp"
#include "netvmo/pipeline/run/transports.hpp"
#include "netvmo/pipeline/sources/camera_stream.hpp"

namespace {

template <class Entry>
void expect_well_formed(const netvmo::obs::Registry<Entry>& r) {
  SCOPED_TRACE(r.what());
  EXPECT_GE(r.size(), 2u);
  std::set<std::string> seen;
  for (const Entry* e : r) {
    EXPECT_FALSE(e->name().empty());
    EXPECT_FALSE(e->description().empty()) << e->name();
    EXPECT_TRUE(seen.insert(std::string(e->name())).second) << "twice: " << e->name();
    EXPECT_EQ(&r.find(e->name()), e);
  }
  EXPECT_EQ(r.lookup("no-such-entry"), nullptr);
  try {
    r.find("no-such-entry");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "unknown " + r.what() + " 'no-such-entry' (" + r.names() + ")");
  }
}

}  // namespace

TEST(Registries, EveryRegistryHasTheOneForm) {
  expect_well_formed(netvmo::obs::error_models());
  expect_well_formed(netvmo::obs::estimators());
  expect_well_formed(netvmo::run::transport_kinds());
  expect_well_formed(netvmo::sources::stream_kinds());
  EXPECT_EQ(netvmo::obs::estimators().names(), "vmo, zero-offset");
  EXPECT_EQ(netvmo::run::transport_kinds().names(" | "), "in-process | lossy");
  EXPECT_EQ(netvmo::sources::stream_kinds().names(), "image-folder, video");
}
