// How estimates travel between cameras. A transport carries each camera's EstimateMessage to
// the cameras whose neighbour it is. The in-process one below delivers every message of a round
// at once; others may lose, delay or repeat messages (the receiver keeps the latest estimate it
// accepted from each neighbour), or cross process boundaries (a middleware).
//
// Adding a transport: a class implementing Transport in its own file, and one line in the
// pipeline's transport registry (pipeline/include/netvmo/pipeline/run/transports.hpp) so that
// runs and the command line can choose it by name.
#pragma once

#include <vector>

#include "netvmo/observer/estimate_message.hpp"
#include "netvmo/observer/graph.hpp"

namespace netvmo::obs {

class Transport {
 public:
  virtual ~Transport() = default;
  /// Sends camera m.sender's message of this round to its neighbours.
  virtual void send(const EstimateMessage& m) = 0;
  /// Replaces `out` with the messages that reached camera `receiver` since its last call. Called
  /// once per camera and round, after every camera of the round has sent. A lock-step transport
  /// may block here until the round's messages from all neighbours have arrived.
  virtual void receive(int receiver, std::vector<EstimateMessage>& out) = 0;
};

/// Direct delivery within one process: every neighbour's message of the round, in neighbour
/// order (the default of NetworkedObserver).
class InProcessTransport final : public Transport {
 public:
  explicit InProcessTransport(Graph graph);
  const Graph& graph() const { return graph_; }
  void send(const EstimateMessage& m) override;
  void receive(int receiver, std::vector<EstimateMessage>& out) override;

 private:
  Graph graph_;
  std::vector<EstimateMessage> sent_;  ///< the latest message of each camera
  std::vector<bool> has_sent_;
};

}  // namespace netvmo::obs
