// Matching identified modes to predicted ones, and the predicted modes that cannot be observed.
#include <cmath>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/modal/mode_matching.hpp"
#include "synthetic_modes.hpp"

namespace drivetrain_stiffness::modal {
namespace {

Eigen::VectorXcd shape2(double a, double b) {
  Eigen::VectorXcd v(2);
  v << a, b;
  return v;
}

PredictedMode predicted(const std::string& name, double f, const Eigen::VectorXcd& shape) {
  PredictedMode p;
  p.name = name;
  p.frequency = f;
  p.shape = shape;
  return p;
}

TEST(ModeMatching, MatchesTheRigsModesAndStatesTheUnobservable) {
  const test::SyntheticModes sys = test::rigModes();
  SsiOptions o;
  o.max_order = 40;
  const SelectionResult sel = selectModes(SsiCov(o).identify(sys.record(51200, 41), 51200.0));
  ASSERT_EQ(sel.modes.size(), 2u);
  // The model off by 3 % and its shapes off by 0.1 at one channel.
  const std::vector<PredictedMode> model = {
      predicted("gear shaft", 7900.0 * 1.03, shape2(0.9, 0.5)),
      predicted("pinion shaft", 9400.0 * 0.97, shape2(0.3, -0.9)),
      predicted("torsional", 30000.0, shape2(1.0, 1.0)),  // above 25.6 kHz
      predicted("axial", 12000.0, shape2(0.01, -0.04)),   // no channel sees it
  };
  const MatchResult m = matchModes(sel.modes, model, 51200.0);
  EXPECT_EQ(m.predicted_of[0], 0);
  EXPECT_EQ(m.predicted_of[1], 1);
  EXPECT_GT(m.mac_of[0], 0.95);
  EXPECT_EQ(m.identified_of[0], 0);
  EXPECT_EQ(m.identified_of[1], 1);
  EXPECT_EQ(m.observability[0], Observability::kObservable);
  EXPECT_EQ(m.observability[2], Observability::kAboveNyquist);
  EXPECT_EQ(m.observability[3], Observability::kNoChannel);
  EXPECT_EQ(m.identified_of[2], -1);
  EXPECT_EQ(m.identified_of[3], -1);
  EXPECT_STREQ(observabilityName(m.observability[2]), "above Nyquist");
  EXPECT_STREQ(observabilityName(m.observability[3]), "no channel sees it");
}

TEST(ModeMatching, TheShapeDecidesBetweenCandidatesInTheWindow) {
  IdentifiedMode id;
  id.frequency = 7900.0;
  id.shape = shape2(1.0, 0.4);
  // Both within 15 %; the nearer one in frequency has the orthogonal shape.
  const std::vector<PredictedMode> model = {predicted("near", 8000.0, shape2(-0.4, 1.0)),
                                            predicted("far", 8800.0, shape2(1.0, 0.4))};
  const MatchResult m = matchModes({id}, model, 51200.0);
  EXPECT_EQ(m.predicted_of[0], 1);
  EXPECT_NEAR(m.mac_of[0], 1.0, 1e-12);
  EXPECT_EQ(m.identified_of[0], -1);  // observable, not identified in this record
  // Outside the window: no match, whatever the shape.
  const MatchResult none = matchModes({id}, {predicted("far", 9500.0, id.shape)}, 51200.0);
  EXPECT_EQ(none.predicted_of[0], -1);
  EXPECT_TRUE(std::isnan(none.mac_of[0]));
}

TEST(ModeMatching, RejectsBadArgumentsNamingTheField) {
  IdentifiedMode id;
  id.frequency = 7900.0;
  id.shape = shape2(1.0, 0.4);
  auto expectInvalid = [](const std::function<void()>& f, const std::string& text) {
    try {
      f();
      ADD_FAILURE() << "no InvalidInput for " << text;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  Eigen::VectorXcd three = Eigen::VectorXcd::Ones(3);
  expectInvalid([&] { matchModes({id}, {predicted("a", 8000.0, three)}, 51200.0); },
                "predicted[0].shape.size = 3");
  expectInvalid([&] { matchModes({id}, {predicted("a", -1.0, id.shape)}, 51200.0); },
                "predicted[0].frequency = -1");
  expectInvalid([&] { matchModes({id}, {}, 0.0); }, "sample_rate = 0");
  MatchOptions o;
  o.frequency_window = 0.0;
  expectInvalid([&] { matchModes({id}, {}, 51200.0, o); }, "matching.frequency_window = 0");
}

}  // namespace
}  // namespace drivetrain_stiffness::modal
