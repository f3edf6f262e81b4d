// Fuzz target: a node's journal, node_<id>.csv, as `netvmo merge` reads the files gathered from
// several machines (net::read_node_journal), then every row read written again
// (net::node_journal_row).
#include "netvmo/pipeline/net/node_journal.hpp"
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_input(data, size, "node_1.csv");
  try {
    for (const auto& row : net::read_node_journal(path, false)) (void)net::node_journal_row(row);
  } catch (const InputError&) {
  }
  return 0;
}
