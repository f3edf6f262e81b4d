// netvmo security init: a test PKI for DDS Security (net::write_test_pki).
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/net/security.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

void add_security(CLI::App& app, int& exit_code) {
  auto* security = app.add_subcommand("security", "DDS Security for the camera processes");
  security->require_subcommand(1);
  struct Options {
    std::string dir, dataset;
    int days = 365;
  };
  auto o = std::make_shared<Options>();
  auto* init = add_command(
      *security, "init", "Write a test PKI for a dataset's cameras",
      "Writes into DIR, with OpenSSL: an identity CA and a permissions CA (EC prime256v1), the\n"
      "signed governance (no unauthenticated participant; discovery, liveliness and data\n"
      "encrypted; every topic access-controlled), and per camera of DATASET's network.yaml a\n"
      "key, a certificate and signed permissions (publish its own estimate topic and ROS 2\n"
      "outputs, read only its neighbours' estimate topics and its camera topics), plus the\n"
      "identities `viewer` (reads every camera's ROS 2 outputs) and `player` (netvmo play).\n"
      "For tests and trials: the CAs' keys are not kept, so DIR cannot grow; a deployment makes\n"
      "its own (docs/processes.md, \"Security\"). launch, node and play take DIR with --security.");
  init->add_option("DIR", o->dir, "Output folder")->required();
  init->add_option("DATASET", o->dataset, "Dataset folder (its network.yaml)")->required();
  init->add_option("--days", o->days, "Validity of the certificates and permissions")
      ->capture_default_str()
      ->check(CLI::Range(1, 36500));
  init->callback([o, &exit_code] {
    exit_code = guarded("security init", [&] {
      const auto net = io::load_network_config(fs::path(o->dataset) / "network.yaml");
      net::write_test_pki(o->dir, net, o->days);
      std::printf("security folder %s: %zu camera identities, viewer and player, valid %d days\n",
                  o->dir.c_str(), net.cameras.size(), o->days);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
