// Cyclone DDS's C API with errors as exceptions, for the sources of src/net/.
#pragma once

#include <dds/dds.h>

#include <stdexcept>
#include <string>

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

}  // namespace netvmo::net::detail
