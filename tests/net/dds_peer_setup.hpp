// The two-camera network of the DDS tests, shared by the peer processes and the in-process
// reference.
#pragma once

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/lie.hpp"

namespace netvmo::net_test {

constexpr double kH = 1.0 / 330.0;  // one sub-step of a 30 frames/s frame with 11 rounds
/// The position coordinate `dds_peer writer` sends: eight bytes a packet capture looks for.
constexpr double kMarker = 4242.4242424242;

inline obs::ObserverSettings peer_settings() {
  obs::ObserverSettings s;
  s.error_model = "pnp";
  s.k_e = 1.0;
  s.k_s = 50.0;
  return s;
}

/// Camera i: believed pose, initial estimate and a fixed PnP measurement, all different.
inline void setup_peer(obs::CameraObserver& c) {
  const int i = c.index();
  obs::Vec6 a, b, m;
  a << 0.3 * i, -0.2, 0.1 * i, 0.05, 0.1 * i, -0.2;
  b << 0.1, 0.2 * i, 1.5, 0.2 * i, -0.1, 0.3;
  m << -0.05 * i, 0.1, 1.2, 0.1, 0.05 * i, 0.02;
  c.set_camera_pose(obs::exp_se3(a));
  c.reset(obs::exp_se3(b));
  obs::Measurement z;
  z.delta = true;
  z.g_io_pnp = obs::exp_se3(m);
  c.set_measurement(z);
}

}  // namespace netvmo::net_test
