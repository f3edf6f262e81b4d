#include "netvmo/pipeline/net/cyclone_config.hpp"

#include <cstdlib>
#include <fstream>
#include <system_error>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;

std::string loopback_config_xml() {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- netvmo: loopback only. No multicast, unicast discovery of 127.0.0.1 alone: nothing leaves
     this machine. The domain id is given by the program (netvmo launch prints it). -->
<CycloneDDS xmlns="https://cdds.io/config">
  <Domain Id="any">
    <General>
      <Interfaces>
        <NetworkInterface name="lo" />
      </Interfaces>
      <AllowMulticast>false</AllowMulticast>
      <DontRoute>true</DontRoute>
    </General>
    <Discovery>
      <ParticipantIndex>auto</ParticipantIndex>
      <MaxAutoParticipantIndex>)" +
         std::to_string(kMaxParticipants) + R"(</MaxAutoParticipantIndex>
      <Peers>
        <Peer Address="127.0.0.1" />
      </Peers>
    </Discovery>
    <Internal>
      <!-- Images come in bursts larger than the 1 MiB Cyclone asks for by default (a 640x480
           mono8 image is 300 KiB); a full buffer drops datagrams, and a best-effort image with
           them. Ask for 16 MiB and take what the kernel gives (net.core.rmem_max caps it). -->
      <SocketReceiveBufferSize max="16MiB" />
    </Internal>
  </Domain>
</CycloneDDS>
)";
}

void write_loopback_config(const fs::path& file) {
  const fs::path tmp = file.string() + ".tmp";
  {
    std::ofstream f(tmp);
    f << loopback_config_xml();
    if (!f) throw InputError(tmp.string() + ": cannot write the Cyclone DDS configuration");
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) throw InputError(file.string() + ": cannot write the Cyclone DDS configuration");
}

int domain_from_pid(long pid) {
  return 1 + static_cast<int>(pid % 200);
}

void use_config(const fs::path& file) {
  ::setenv("CYCLONEDDS_URI", ("file://" + fs::absolute(file).string()).c_str(), 1);
}

}  // namespace netvmo::net
