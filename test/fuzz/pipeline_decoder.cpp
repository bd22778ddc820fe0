#include "pipeline_decoder.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

namespace drivetrain_stiffness::fuzz {
namespace {

template <typename T, std::size_t N>
T pick(const T (&values)[N], unsigned index) {
  return values[index % N];
}

constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;  // 2026-01-01, a wall-clock epoch

}  // namespace

Fidelity decodeFidelity(std::uint8_t byte) {
  static const Fidelity kFidelities[] = {Fidelity::kFull, Fidelity::kQuasiStatic,
                                         Fidelity::kLinearModal, Fidelity::kFull};
  return pick(kFidelities, byte);
}

PipelineSetup decodeSetup(ByteReader& in) {
  const std::uint8_t h0 = in.u8(), h1 = in.u8(), h2 = in.u8();
  PipelineSetup s;
  PipelineOptions& o = s.options;
  o.dynamics = (h0 & 1) == 0;
  s.settings.fidelity = decodeFidelity(static_cast<std::uint8_t>(h0 >> 1));
  s.rig = (h0 >> 3) & 1;
  o.limits.load_tolerance = (h0 & 0x10) ? 0.0 : PipelineOptions::onlineLimits().load_tolerance;
  static const double kStiffnessRates[] = {0.0, 0.0, 10.0, 1000.0, 1e5, 0.5, 1e-3, 100.0};
  s.settings.stiffness_rate = pick(kStiffnessRates, h0 >> 5);
  static const double kOutputRates[] = {1000.0, 100.0, 5000.0, 20000.0};
  static const double kMaxGaps[] = {1.0, 0.05, 0.01, 1e-3};
  static const double kStampJumps[] = {1.0, 0.0, 1e-3, 10.0};
  static const double kClockJumps[] = {0.0, 0.5, 1e-9, 10.0};
  o.output_rate = pick(kOutputRates, h1);
  // 20 kHz only with short gaps: max_gap x rate stays <= 1000 (the default's product). The ordinary
  // gear integrates with dopri5 whenever its flanks separate (0.3 s per simulated second; 7 times
  // that under ASan): short gaps too, so that a case stays a fraction of a second.
  const bool short_gaps = o.output_rate > 5000.0 || s.rig == 1;
  o.max_gap = short_gaps ? pick(kMaxGaps, 1 + (h1 >> 2) % 3) : pick(kMaxGaps, h1 >> 2);
  o.stamp_jump_back = pick(kStampJumps, h1 >> 4);
  o.clock_jump_back = pick(kClockJumps, h1 >> 6);
  static const int kWindows[][2] = {{1024, 256}, {8, 1}, {64, 64}, {16, 3}};
  o.torque_frame = (h2 & 0x80) ? "pinion" : "";  // half the cases enforce the frame rule
  o.spectrum_window = kWindows[h2 % 4][0];
  o.spectrum_hop = kWindows[h2 % 4][1];
  static const double kThresholds[] = {0.01, 1e-6, 0.5, 0.999};
  // Not below 300 rpm: the exact propagators' set-up, which every preload change of more than 1 %
  // repeats, grows as 1 / speed (1000 rpm: 8 ms; 100 rpm: 90 ms; 7 times that under ASan), which
  // would make cases slow, not different. node_params reaches the slow speeds.
  static const double kSpeeds[] = {1000.0, 300.0, 6000.0, 30000.0};
  o.resonance_threshold = pick(kThresholds, h2 >> 2);
  o.pinion_speed_rpm = pick(kSpeeds, h2 >> 4);
  return s;
}

Stamp decodeStamp(ByteReader& in, Stamp last) {
  const Stamp base = last.isZero() ? Stamp{kEpoch} : last;
  switch (in.u8() % 8) {
    case 0:
    case 1:
      return Stamp{base.ns +
                   static_cast<std::int64_t>(in.u16()) * 16};  // forward, up to 1 ms: kHz inputs
    case 2:
      return Stamp{base.ns +
                   static_cast<std::int64_t>(in.u16()) * 10000};  // forward, up to 0.65 s: gaps
    case 3: return Stamp{base.ns + in.u8()};                      // a burst: 0 to 255 ns on
    case 4: {  // back, up to 0.65 s, but not before 0: ROS stamps are unsigned
      const std::int64_t back = static_cast<std::int64_t>(in.u16()) * 10000;
      return Stamp{base.ns > back ? base.ns - back : 0};
    }
    case 5: return base;
    case 6: return Stamp{0};
    default: {
      // Anything a ROS header carries: two uint32, nsec not necessarily normalised.
      const std::uint32_t sec = in.u32(), nsec = in.u32();
      return Stamp::fromSecNsec(sec, nsec);
    }
  }
}

double decodeValue(ByteReader& in, double typical) {
  static const double kInteresting[] = {
      0.0, -0.0, 1.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
      -std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
      -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::denorm_min(),
      -std::numeric_limits<double>::denorm_min(), DBL_MIN, DBL_MAX, -DBL_MAX, 1e-300, 1e300,
      // the default limits (max_abs_torque, max_preload, max_interference) and just past them
      100.0, std::nextafter(100.0, 1e9), -std::nextafter(100.0, 1e9), 1e5, std::nextafter(1e5, 1e9),
      1e-3, std::nextafter(1e-3, 1.0),
      // damping ratio bounds
      1.0 - 1e-16, std::nextafter(1.0, 2.0)};
  switch (in.u8() % 4) {
    case 0: return pick(kInteresting, in.u8());
    case 1: return in.rawDouble();
    default: return typical * static_cast<std::int16_t>(in.u16()) / 32768.0;
  }
}

MotionCase decodeMotion(ByteReader& in) {
  const std::uint8_t flags = in.u8();
  MotionCase m;
  m.missing_pinion = (flags & 0x07) == 0x07;
  m.numbering = flags & 0xF8;
  m.reading.pinion_angle = decodeValue(in, 10.0);  // [rad]: several turns, wrapped or not
  if (flags & 1)
    m.reading.pinion_velocity = decodeValue(in, 700.0);  // [rad/s]: 6700 rpm at full scale
  if (flags & 2) m.reading.gear_angle = decodeValue(in, 10.0);
  return m;
}

VibrationCase decodeVibration(ByteReader& in) {
  // Channel names: both supports, one, an unknown extra, none, an empty name, none known, a
  // repeated name, one from the bytes beside a support.
  static const std::vector<std::string> kLayouts[] = {{"pinion_bearing", "gear_bearing"},
                                                      {"gear_bearing"},
                                                      {"pinion_bearing", "gear_bearing", "tacho"},
                                                      {},
                                                      {"", "gear_bearing"},
                                                      {"nacelle"},
                                                      {"pinion_bearing", "pinion_bearing"},
                                                      {}};
  const std::uint8_t layout = in.u8(), rate = in.u8();
  VibrationCase v;
  v.channels = kLayouts[layout % 8];
  if (layout % 8 == 7) v.channels = {in.string(16), "gear_bearing"};
  v.numbering = (layout >> 3) & 3;
  static const double kRates[] = {
      51200.0, 51200.0 * (1.0 + 1e-7), 51200.0 * (1.0 + 1e-5), 25600.0, 64.0, 0.0, -51200.0};
  v.sample_rate = rate % 8 < 7 ? kRates[rate % 8] : std::min(decodeValue(in, 51200.0), 51200.0);
  const std::size_t frames = in.u8() % 33;
  const double amplitude = decodeValue(in, 10.0);  // [m/s^2]
  const std::size_t width = v.channels.size();
  v.data.resize(frames * width);
  for (std::size_t i = 0; i < v.data.size(); ++i) {
    v.data[i] = static_cast<float>(
        amplitude * std::sin(0.7 * static_cast<double>(i / std::max<std::size_t>(width, 1)) +
                             0.3 * static_cast<double>(i % std::max<std::size_t>(width, 1))));
  }
  switch ((layout >> 5) & 3) {
    case 2:  // one sample short of whole frames
      if (!v.data.empty()) v.data.pop_back();
      break;
    case 3: v.data.clear(); break;
    default: break;
  }
  if ((layout & 0x80) && !v.data.empty()) {
    const std::size_t at = in.u8() % v.data.size();
    v.data[at] = static_cast<float>(decodeValue(in, 1e6));  // NaN, +-Inf, past the range
  }
  return v;
}

std::vector<PreloadSetting> decodePreloads(ByteReader& in) {
  static const char* const kNames[] = {"pinion_bearing", "gear_bearing", "", "pinion_bearing\n"};
  std::vector<PreloadSetting> settings(in.u8() % 4);
  for (PreloadSetting& p : settings) {
    const std::uint8_t n = in.u8();
    p.name = n % 8 == 7 ? in.string(16) : pick(kNames, n % 8 < 6 ? n % 2 : n % 4);
    p.axial_preload = std::abs(decodeValue(in, 3000.0));  // mostly admissible: preloads are >= 0
    p.radial_preload = std::abs(decodeValue(in, 3000.0));
    p.inner_interference = std::abs(decodeValue(in, 2e-5));
    p.outer_interference = std::abs(decodeValue(in, 2e-5));
    if (n & 0x80) p.axial_preload = -p.axial_preload;  // and sometimes not
  }
  return settings;
}

}  // namespace drivetrain_stiffness::fuzz
