// launch's option values (net/launch.hpp): --kill ID@SECONDS and --clock-offsets ID:SECONDS,...
// read every number whole (io/number_text.hpp), so a typo is refused, not half read.
#include <gtest/gtest.h>

#include <string>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/net/launch.hpp"
#include "test_util.hpp"

namespace netvmo::net {
namespace {

io::NetworkConfig three_cameras() {
  io::NetworkConfig net;
  net.source = "ds/network.yaml";
  for (int id : {1, 2, 3}) net.cameras.push_back({id, obs::SE3::Identity(), {}, {}, {}});
  return net;
}

TEST(LaunchOptions, KillReadsACameraAndATimeWhole) {
  const auto net = three_cameras();
  const NodeKill k = parse_node_kill("3@1.5", 0.25, net);
  EXPECT_EQ(k.camera_id, 3);
  EXPECT_EQ(k.at, 1.5);
  EXPECT_EQ(k.restart_after, 0.25);
  EXPECT_EQ(parse_node_kill("2@0", 0.0, net).at, 0.0);
  for (const std::string spec :
       {"3@1s", "3x@1", "3", "@1", "3@", "4@1", "3@-1", "3@nan", "3@inf", "1.5@1", "3@1@2"})
    test::expect_input_error([&] { parse_node_kill(spec, 0.0, net); },
                             {"--kill " + spec + ": expected ID@SECONDS", net.source});
}

TEST(LaunchOptions, ClockOffsetsReadEveryCameraAndOffsetWhole) {
  const auto net = three_cameras();
  const auto o = parse_clock_offsets("2:0.5,3:-1e-3", net);
  ASSERT_EQ(o.size(), 2u);
  EXPECT_EQ(o.at(2), 0.5);
  EXPECT_EQ(o.at(3), -1e-3);
  for (const std::string spec : {"2:0.5s", "2x:1", "2:", ":1", "2:1,2:0", "9:1", "2:inf", "2"})
    test::expect_input_error([&] { parse_clock_offsets(spec, net); },
                             {"--clock-offsets " + spec + ": ", "expected ID:SECONDS"});
}

}  // namespace
}  // namespace netvmo::net
