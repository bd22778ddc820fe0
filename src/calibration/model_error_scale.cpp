#include "drivetrain_stiffness/calibration/model_error_scale.hpp"

#include <cmath>

namespace drivetrain_stiffness {

double ModelErrorScale::gridValue(int k) { return std::pow(10.0, -4.0 + 6.0 * k / (kGrid - 1)); }

void ModelErrorScale::reset(const CalibrationMatrix& prior) {
  for (auto& s : score_) s.fill(0.0);
  noise_part_ = prior;
  for (auto& p : model_part_) p.setZero();
  scored_.fill(0);
  windows_ = 0;
}

FeatureVector ModelErrorScale::innovationVariance(const FeatureRows& H,
                                                  const FeatureVector& noise) const {
  const CalibrationMatrix P = covariance();
  FeatureVector v;
  for (int j = 0; j < kFeatureSize; ++j) v[j] = H.row(j).dot(P * H.row(j).transpose()) + noise[j];
  return v;
}

void ModelErrorScale::update(const FeatureVector& nu, const FeatureVector& variance,
                             const FeatureVector& noise, const FeatureVector& model, const Gain& K,
                             const FeatureRows& H) {
  for (int j = 0; j < kFeatureSize; ++j) {
    const double a = variance[j], m = model[j], nu2 = nu[j] * nu[j];
    if (!(m > 0.0) || !(a >= 0.0) || !std::isfinite(nu2))
      continue;  // no allowance there: nothing to learn
    for (int k = 0; k < kGrid; ++k) {
      const double v =
          a + gridValue(k) * m;  // the innovation's variance if the model error were c M
      score_[j][k] += m * (nu2 - v) / (v * v);
    }
    ++scored_[j];
  }
  // Joseph form with each part of the true noise: P_N takes K N K', P_Mj takes K_j M_j K_j'.
  const CalibrationMatrix IKH = CalibrationMatrix::Identity() - K * H;
  noise_part_ =
      (IKH * noise_part_ * IKH.transpose()).eval() + K * noise.asDiagonal() * K.transpose();
  for (int j = 0; j < kFeatureSize; ++j) {
    model_part_[j] = (IKH * model_part_[j] * IKH.transpose()).eval() +
                     model[j] * (K.col(j) * K.col(j).transpose());
  }
  ++windows_;
}

void ModelErrorScale::absorb(const CalibrationMatrix& ikh, const CalibrationMatrix& krk) {
  // Joseph form (Gelb 1974, sec. 7.2): the other measurement's whole noise is known, so it joins
  // P_N; the features' model-error parts are only carried through the gain.
  noise_part_ = (ikh * noise_part_ * ikh.transpose()).eval() + krk;
  for (CalibrationMatrix& p : model_part_) p = (ikh * p * ikh.transpose()).eval();
}

FeatureVector ModelErrorScale::scale() const {
  FeatureVector c = FeatureVector::Ones();
  if (windows_ < kMinWindows) return c;
  for (int j = 0; j < kFeatureSize; ++j) {
    if (scored_[j] == 0) continue;  // never an allowance: nothing to scale
    const auto& s = score_[j];
    // The score falls as c grows (more variance explains the innovations); its root is the ML c.
    if (!(s[0] > 0.0)) {
      c[j] = gridValue(0);
      continue;
    }
    c[j] = gridValue(kGrid - 1);
    for (int k = 0; k + 1 < kGrid; ++k) {
      if (!(s[k + 1] > 0.0)) {
        const double f = s[k] / (s[k] - s[k + 1]);  // linear in log c between the two grid points
        c[j] = gridValue(k) * std::pow(gridValue(k + 1) / gridValue(k), f);
        break;
      }
    }
  }
  return c;
}

CalibrationMatrix ModelErrorScale::covariance(double min_scale) const {
  const FeatureVector c = scale().cwiseMax(min_scale);
  CalibrationMatrix p = noise_part_;
  for (int j = 0; j < kFeatureSize; ++j) p += c[j] * model_part_[j];
  return 0.5 * (p + p.transpose());
}

}  // namespace drivetrain_stiffness
