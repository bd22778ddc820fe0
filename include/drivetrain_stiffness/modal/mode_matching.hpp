// Matching of identified modes to the model's predicted modes (frequency window, then the highest
// MAC on the shape over the channels), and which predicted modes these channels and this sample
// rate cannot observe. docs/vibration.md, "Matching".
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/modal/pole_selection.hpp"

namespace drivetrain_stiffness::modal {

/// A mode of the model, seen at the channels.
struct PredictedMode {
  std::string name;
  double frequency = 0.0;  ///< undamped natural frequency [Hz]
  /// At each channel, in the channel's direction, scaled so that the mode's largest displacement
  /// over all model coordinates is 1 [-].
  Eigen::VectorXcd shape;
};

struct MatchOptions {
  double frequency_window = 0.15;  ///< |f_id - f_pred| <= this x f_pred to be a candidate [-]
  double min_mac = 0.5;            ///< a candidate's MAC at least this to match [-]
  double visibility = 0.05;        ///< a channel sees a mode when |shape entry| >= this [-]
};

enum class Observability {
  kObservable,
  kAboveNyquist,  ///< frequency >= sample_rate / 2
  kNoChannel,     ///< |shape entry| < visibility on every channel
};

/// "observable", "above Nyquist" or "no channel sees it".
const char* observabilityName(Observability o);

struct MatchResult {
  /// Per identified mode: the matched predicted mode's index, or -1; its MAC (NaN if none).
  std::vector<int> predicted_of;
  std::vector<double> mac_of;
  /// Per predicted mode: whether it is observable, and the identified mode matched to it, or -1
  /// (observable but not identified in this record).
  std::vector<Observability> observability;
  std::vector<int> identified_of;
};

/// Matches identified and observable predicted modes one to one within the frequency window, the
/// pairs of highest MAC first. Throws InvalidInput naming a non-positive rate, a predicted
/// frequency that is not positive and finite, a shape of another size than the identified shapes,
/// or an option out of range.
MatchResult matchModes(const std::vector<IdentifiedMode>& identified,
                       const std::vector<PredictedMode>& predicted, double sample_rate,
                       const MatchOptions& options = {});

}  // namespace drivetrain_stiffness::modal
