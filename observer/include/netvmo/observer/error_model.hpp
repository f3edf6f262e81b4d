// The visual error e_ei of (eq:input_f-): how a camera turns its measurement into the error
// between its estimate g_bar_i and the (fictitious) target pose g_io_i.
//
// Every error model is one class in its own file under observer/src/error_models/ and one line
// in the registry's table (observer/src/error_models/registry.cpp). Parsing, printing, the
// command line's choices and help, the simulation and the image runner all read that table.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/observer/measurement.hpp"
#include "netvmo/observer/registry.hpp"

namespace netvmo::obs {

/// Which field of a Measurement an error model reads.
enum class MeasurementInput {
  features,  ///< Measurement::f, the image features
  pnp_pose,  ///< Measurement::g_io_pnp, the camera's own pose measurement
  true_pose  ///< Measurement::g_io_true, ground truth (simulation and rendered data only)
};

class ErrorModel {
 public:
  virtual ~ErrorModel() = default;
  /// The name used on the command line, in scenario files and in summaries.
  virtual std::string_view name() const = 0;
  /// One line for --help.
  virtual std::string_view description() const = 0;
  /// The measurement field the model reads.
  virtual MeasurementInput input() const = 0;
  /// e_ei for the estimate g_bar_i; z must be usable(). Throws std::domain_error when the error
  /// is undefined there (a feature point behind the camera for the image-feature model).
  virtual Vec6 error(const SE3& g_bar, const Measurement& z, const FeatureModel& model) const = 0;
  /// For the models whose error is E_R(g_bar^-1 g) (eq:ER) of a measured relative pose g (exact,
  /// pnp): that pose in z, null when z has none. Null for every other model (default). The
  /// in-process fast path computes those errors on compact poses, to the bits of error().
  virtual const SE3* measured_pose(const Measurement& z) const {
    (void)z;
    return nullptr;
  }

  /// delta_i(t) = 1 and the field input() names is present.
  bool usable(const Measurement& z) const;
};

/// The registry (registry.hpp): every error model, in the order help texts list them;
/// error_models().find(name) throws std::invalid_argument naming the known ones.
const Registry<ErrorModel>& error_models();

}  // namespace netvmo::obs
