#include "replay_writer.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cerrno>
#include <iterator>
#include <charconv>
#include <cstring>
#include <iostream>
#include <stdexcept>

#include <tf2_msgs/TFMessage.h>

#include "drivetrain_stiffness/core/errors.hpp"

namespace drivetrain_stiffness {

namespace {
constexpr std::size_t kCellsPerBlock = 32768;  // about 1000 rows of the widest file
}

CsvFile::CsvFile(const std::string& path, const std::string& header)
    : path_(path), worker_([this](Block& b) { format(b); }) {
  file_ = std::fopen(path.c_str(), "w");
  if (!file_) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  std::fputs(header.c_str(), file_);
  std::fputc('\n', file_);
  block_.cells.reserve(kCellsPerBlock + 64);
}

CsvFile::~CsvFile() {
  try {
    close();
  } catch (const std::exception& e) {
    std::cerr << "drivetrain_replay: " << e.what() << "\n";
  }
}

CsvFile& CsvFile::stamp(const ros::Time& t) {
  block_.cells.push_back({Cell::Kind::kStamp, t.sec, t.nsec, 0.0});
  return *this;
}

CsvFile& CsvFile::number(double v) {
  block_.cells.push_back({Cell::Kind::kNumber, 0, 0, v});
  return *this;
}

CsvFile& CsvFile::text(const std::string& s) {
  block_.cells.push_back(
      {Cell::Kind::kText, static_cast<std::uint32_t>(block_.texts.size()), 0, 0.0});
  block_.texts.push_back(s);
  return *this;
}

void CsvFile::endRow() {
  block_.cells.push_back({Cell::Kind::kEndRow, 0, 0, 0.0});
  if (block_.cells.size() >= kCellsPerBlock) handOver();
}

void CsvFile::handOver() {
  worker_.submit(std::move(block_));
  block_ = Block{};
  block_.cells.reserve(kCellsPerBlock + 64);
}

void CsvFile::format(Block& block) {
  formatted_.clear();
  char buf[32];
  bool row_start = true;
  for (const Cell& c : block.cells) {
    if (c.kind == Cell::Kind::kEndRow) {
      formatted_ += '\n';
      row_start = true;
      continue;
    }
    if (!row_start) formatted_ += ',';
    row_start = false;
    switch (c.kind) {
      case Cell::Kind::kNumber: {
        const auto r = std::to_chars(buf, buf + sizeof buf,
                                     c.number);  // shortest form that reads back exactly
        formatted_.append(buf, r.ptr);
        break;
      }
      case Cell::Kind::kStamp: {
        const int n = std::snprintf(buf, sizeof buf, "%u.%09u", c.sec, c.nsec);
        formatted_.append(buf, static_cast<std::size_t>(n));
        break;
      }
      case Cell::Kind::kText: {
        const std::string& t = block.texts[c.sec];
        if (t.find_first_of(",\"\r\n") == std::string::npos) {
          formatted_ += t;
        } else {  // RFC 4180: quoted, inner quotes doubled (what Python's csv module reads)
          formatted_ += '"';
          for (char ch : t) {
            if (ch == '"') formatted_ += '"';
            formatted_ += ch;
          }
          formatted_ += '"';
        }
        break;
      }
      case Cell::Kind::kEndRow: break;
    }
  }
  if (std::fwrite(formatted_.data(), 1, formatted_.size(), file_) != formatted_.size()) {
    throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(errno));
  }
}

void CsvFile::close() {
  if (closed_) return;
  closed_ = true;
  std::exception_ptr error = worker_.flushAndFinish([this] {
    if (!block_.cells.empty()) handOver();
  });
  if (std::fclose(file_) != 0 && !error) {
    error = std::make_exception_ptr(
        std::runtime_error("cannot write " + path_ + ": " + std::strerror(errno)));
  }
  if (error) std::rethrow_exception(error);
}

OutputTopics OutputTopics::parse(const std::string& option, const std::string& list) {
  if (list == "all") return all();
  unsigned bits = 0;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = std::min(list.find(',', begin), list.size());
    const std::string name = list.substr(begin, end - begin);
    const auto* found = std::find_if(std::begin(kNames), std::end(kNames),
                                     [&](const char* n) { return name == n; });
    if (found == std::end(kNames)) {
      std::string known;
      for (const char* n : kNames) known += std::string(known.empty() ? "" : ", ") + n;
      throw InvalidInput(option + " = '" + list + "': unknown topic '" + name +
                         "' (all, or a comma-separated list of: " + known + ")");
    }
    bits |= 1u << static_cast<unsigned>(found - std::begin(kNames));
    if (end == list.size()) break;
    begin = end + 1;
  }
  return OutputTopics(bits);
}

std::string OutputTopics::describe() const {
  if (bits_ == all().bits_) return "all";
  std::string out;
  for (unsigned t = 0; t < kCount; ++t) {
    if (has(static_cast<Topic>(t))) out += std::string(out.empty() ? "" : ",") + kNames[t];
  }
  return out;
}

namespace {

/// calibration.csv's header: the Calibration message's fields in message order.
std::string calibrationCsvHeader() {
  std::string parameters, identified;
  for (int i = 0; i < kCalibrationSize; ++i) {
    parameters += std::string(",") + calibrationName(i) + "," + calibrationName(i) + "_std";
    identified += std::string(",") + calibrationName(i) + "_identified";
  }
  std::string bands;
  for (const char* f : {"mesh_stiffness", "pinion_bearing_stiffness", "gear_bearing_stiffness",
                        "natural_frequency_1", "natural_frequency_2", "natural_frequency_3"}) {
    bands += std::string(",") + f + "," + f + "_low," + f + "_high";
  }
  return "stamp" + parameters + identified +
         ",nis,excited,baseline,outcome,windows,baseline_windows,"
         "updates,gated,not_excited,window_torque,window_speed,"
         "series_compliance,series_compliance_std" +
         bands +
         ",knee_torque,measured_mean_te,predicted_mean_te,"
         "measured_mesh_harmonic_1,predicted_mesh_harmonic_1,"
         "measured_mesh_harmonic_2,predicted_mesh_harmonic_2,modal_updates,modal_gated,modal_nis";
}

}  // namespace

ReplayWriter::ReplayWriter(const RigPipeline& pipeline, const OutputSettings& settings,
                           const std::string& out_bag, BagCompression compression,
                           const std::string& csv_dir, OutputTopics bag_topics,
                           OutputTopics csv_topics)
    : MessageSink(pipeline, settings),
      bag_topics_(bag_topics),
      csv_topics_(csv_topics),
      mesh_period_totals_(pipeline.rig().gears.teeth[0]) {
  // BagWriter, not rosbag::Bag: rosbag's per-message syscalls cap the replay near 300x
  // (bag_writer.hpp).
  if (!out_bag.empty()) bag_ = std::make_unique<BagWriter>(out_bag, compression);
  if (csv_dir.empty()) return;
  std::string bearings;
  for (const SupportEstimate& s : pipeline.estimator().current().supports) {
    bearing_names_.push_back(s.name);
    for (const char* f : {"radial_stiffness", "axial_stiffness", "tilt_stiffness", "radial_load",
                          "axial_load", "max_contact_pressure", "balls_in_contact"}) {
      bearings += "," + s.name + "." + f;
    }
  }
  if (csv_topics_.has(OutputTopics::kStiffness))
    stiffness_csv_ =
        std::make_unique<CsvFile>(csv_dir + "/stiffness.csv",
                                  "stamp,torque,mesh_force,mesh_phase,mesh_stiffness,mesh_"
                                  "stiffness_mean,mesh_stiffness_drive,mesh_stiffness_back,"
                                  "drive_flank_loaded,back_flank_loaded" +
                                      bearings +
                                      ",calibrated,mesh_stiffness_mean_calibrated,mesh_stiffness_"
                                      "mean_low,mesh_stiffness_mean_high,"
                                      "pinion_bearing_stiffness_calibrated,pinion_bearing_"
                                      "stiffness_low,pinion_bearing_stiffness_high,"
                                      "gear_bearing_stiffness_calibrated,gear_bearing_stiffness_"
                                      "low,gear_bearing_stiffness_high");
  if (csv_topics_.has(OutputTopics::kTransmissionError))
    te_csv_ = std::make_unique<CsvFile>(csv_dir + "/transmission_error.csv",
                                        "stamp,dynamic_te,static_te,x_p,x_g,x,mesh_force,mesh_"
                                        "phase,torque,drive_flank_loaded,back_flank_loaded");
  if (csv_topics_.has(OutputTopics::kTeSpectrum))
    spectrum_csv_ = std::make_unique<CsvFile>(
        csv_dir + "/te_spectrum.csv",
        "stamp,peak_frequency_hz,peak_amplitude,f2_hz,a2,f3_hz,a3,window_s,resolution_hz");
  if (csv_topics_.has(OutputTopics::kResonance))
    resonance_csv_ =
        std::make_unique<CsvFile>(csv_dir + "/resonance.csv",
                                  "stamp,f1_hz,f2_hz,f3_hz,zeta1,zeta2,zeta3,dominant1,dominant2,"
                                  "dominant3,floquet_valid,floquet_margin,"
                                  "calibrated,f1_hz_calibrated,f1_hz_low,f1_hz_high,f2_hz_"
                                  "calibrated,f2_hz_low,f2_hz_high,f3_hz_calibrated,f3_hz_low,"
                                  "f3_hz_high");
  // The calibration's files, named after the message fields in message order (the ctest
  // replay_writes_the_calibration checks the columns against msg/); header only without a
  // calibration.
  if (csv_topics_.has(OutputTopics::kMeasuredTe))
    measured_te_csv_ = std::make_unique<CsvFile>(csv_dir + "/measured_te.csv",
                                                 "stamp,te,predicted,residual,torque,mesh_phase");
  // Per block of whole mesh periods, named after the MeshPeriodStats fields in message order.
  if (csv_topics_.has(OutputTopics::kMeshPeriodStats))
    mesh_period_csv_ =
        std::make_unique<CsvFile>(csv_dir + "/mesh_period_stats.csv",
                                  "stamp,te_mean,te_rms,te_peak_to_peak,mesh_force_mean,mesh_force_"
                                  "rms,mesh_force_peak_to_peak,mesh_frequency,torque,"
                                  "periods,samples,duration");
  if (csv_topics_.has(OutputTopics::kCalibration))
    calibration_csv_ =
        std::make_unique<CsvFile>(csv_dir + "/calibration.csv", calibrationCsvHeader());
  // The modal identification: one row per identified mode and per model mode left without one,
  // and every pole of every order (the stabilisation diagram). Empty cells where a value does not
  // apply.
  if (csv_topics_.has(OutputTopics::kModalIdentification)) {
    modal_csv_ = std::make_unique<CsvFile>(
        csv_dir + "/modal_identification.csv",
        "stamp,record_start,record_duration,sample_rate,torque,pinion_speed,status,mode,model_mode,"
        "dominant,predicted_frequency,predicted_low,predicted_high,frequency,frequency_std,"
        "damping,damping_std,mac,orders,unresolved");
    modal_poles_csv_ = std::make_unique<CsvFile>(
        csv_dir + "/modal_poles.csv",
        "stamp,order,frequency,damping,frequency_std,damping_std,stable,mode,order_band,status");
  }
}

void ReplayWriter::close() {
  // Each close throws on an I/O error, naming its file.
  if (bag_) bag_->close();
  for (auto* csv : {&stiffness_csv_, &te_csv_, &spectrum_csv_, &resonance_csv_, &measured_te_csv_,
                    &calibration_csv_, &mesh_period_csv_, &modal_csv_, &modal_poles_csv_}) {
    if (*csv) (*csv)->close();
  }
}

void ReplayWriter::emitStiffness(const drivetrain_stiffness::Stiffness& m) {
  if (auto* bag = bagFor(OutputTopics::kStiffness)) bag->write("/stiffness", m.header.stamp, m);
  if (!stiffness_csv_) return;
  CsvFile& c = *stiffness_csv_;
  c.stamp(m.header.stamp)
      .number(m.torque)
      .number(m.mesh_force)
      .number(m.mesh_phase)
      .number(m.mesh_stiffness);
  c.number(m.mesh_stiffness_mean).number(m.mesh_stiffness_drive).number(m.mesh_stiffness_back);
  c.number(m.drive_flank_loaded).number(m.back_flank_loaded);
  for (const auto& b : m.bearings) {
    c.number(b.radial_stiffness)
        .number(b.axial_stiffness)
        .number(b.tilt_stiffness)
        .number(b.radial_load);
    c.number(b.axial_load).number(b.max_contact_pressure).number(b.balls_in_contact);
  }
  c.number(m.calibrated)
      .number(m.mesh_stiffness_mean_calibrated)
      .number(m.mesh_stiffness_mean_low)
      .number(m.mesh_stiffness_mean_high);
  c.number(m.pinion_bearing_stiffness_calibrated)
      .number(m.pinion_bearing_stiffness_low)
      .number(m.pinion_bearing_stiffness_high);
  c.number(m.gear_bearing_stiffness_calibrated)
      .number(m.gear_bearing_stiffness_low)
      .number(m.gear_bearing_stiffness_high);
  c.endRow();
}

void ReplayWriter::emitTransmissionError(const drivetrain_stiffness::TransmissionError& m) {
  if (auto* bag = bagFor(OutputTopics::kTransmissionError))
    bag->write("/transmission_error", m.header.stamp, m);
  if (!te_csv_) return;
  te_csv_->stamp(m.header.stamp)
      .number(m.dynamic_te)
      .number(m.static_te)
      .number(m.x_p)
      .number(m.x_g)
      .number(m.x);
  te_csv_->number(m.mesh_force)
      .number(m.mesh_phase)
      .number(m.torque)
      .number(m.drive_flank_loaded)
      .number(m.back_flank_loaded);
  te_csv_->endRow();
}

void ReplayWriter::emitSpectrum(const drivetrain_stiffness::SpectralPeaks& m) {
  if (auto* bag = bagFor(OutputTopics::kTeSpectrum)) bag->write("/te_spectrum", m.header.stamp, m);
  if (!spectrum_csv_) return;
  spectrum_csv_->stamp(m.header.stamp);
  for (std::size_t i = 0; i < 3; ++i) {
    spectrum_csv_->number(i < m.frequencies_hz.size() ? m.frequencies_hz[i] : 0.0);
    spectrum_csv_->number(i < m.amplitudes.size() ? m.amplitudes[i] : 0.0);
  }
  spectrum_csv_->number(m.window_s).number(m.resolution_hz).endRow();
}

void ReplayWriter::emitResonance(const drivetrain_stiffness::Resonance& m) {
  if (auto* bag = bagFor(OutputTopics::kResonance)) bag->write("/resonance", m.header.stamp, m);
  if (!resonance_csv_) return;
  resonance_csv_->stamp(m.header.stamp);
  for (double f : m.frequencies_hz) resonance_csv_->number(f);
  for (double z : m.damping_ratios) resonance_csv_->number(z);
  for (const std::string& d : m.dominant_coordinate) resonance_csv_->text(d);
  resonance_csv_->number(m.floquet_valid).number(m.floquet_margin).number(m.calibrated);
  resonance_csv_->number(m.f1_hz_calibrated).number(m.f1_hz_low).number(m.f1_hz_high);
  resonance_csv_->number(m.f2_hz_calibrated).number(m.f2_hz_low).number(m.f2_hz_high);
  resonance_csv_->number(m.f3_hz_calibrated).number(m.f3_hz_low).number(m.f3_hz_high).endRow();
}

void ReplayWriter::emitMeasuredTe(const drivetrain_stiffness::MeasuredTe& m) {
  if (auto* bag = bagFor(OutputTopics::kMeasuredTe)) bag->write("/measured_te", m.header.stamp, m);
  if (!measured_te_csv_) return;
  measured_te_csv_->stamp(m.header.stamp)
      .number(m.te)
      .number(m.predicted)
      .number(m.residual)
      .number(m.torque);
  measured_te_csv_->number(m.mesh_phase).endRow();
}

void ReplayWriter::emitCalibration(const drivetrain_stiffness::Calibration& m) {
  if (auto* bag = bagFor(OutputTopics::kCalibration)) bag->write("/calibration", m.header.stamp, m);
  if (!calibration_csv_) return;
  CsvFile& c = *calibration_csv_;
  c.stamp(m.header.stamp);
  c.number(m.mesh_stiffness_scale).number(m.mesh_stiffness_scale_std);
  c.number(m.pinion_bearing_scale).number(m.pinion_bearing_scale_std);
  c.number(m.gear_bearing_scale).number(m.gear_bearing_scale_std);
  c.number(m.preload_torque).number(m.preload_torque_std);
  c.number(m.te_offset).number(m.te_offset_std);
  c.number(m.mesh_stiffness_scale_identified).number(m.pinion_bearing_scale_identified);
  c.number(m.gear_bearing_scale_identified)
      .number(m.preload_torque_identified)
      .number(m.te_offset_identified);
  c.number(m.nis).number(m.excited).number(m.baseline).text(m.outcome);
  c.number(static_cast<double>(m.windows)).number(static_cast<double>(m.baseline_windows));
  c.number(static_cast<double>(m.updates))
      .number(static_cast<double>(m.gated))
      .number(static_cast<double>(m.not_excited));
  c.number(m.window_torque)
      .number(m.window_speed)
      .number(m.series_compliance)
      .number(m.series_compliance_std);
  c.number(m.mesh_stiffness).number(m.mesh_stiffness_low).number(m.mesh_stiffness_high);
  c.number(m.pinion_bearing_stiffness)
      .number(m.pinion_bearing_stiffness_low)
      .number(m.pinion_bearing_stiffness_high);
  c.number(m.gear_bearing_stiffness)
      .number(m.gear_bearing_stiffness_low)
      .number(m.gear_bearing_stiffness_high);
  c.number(m.natural_frequency_1)
      .number(m.natural_frequency_1_low)
      .number(m.natural_frequency_1_high);
  c.number(m.natural_frequency_2)
      .number(m.natural_frequency_2_low)
      .number(m.natural_frequency_2_high);
  c.number(m.natural_frequency_3)
      .number(m.natural_frequency_3_low)
      .number(m.natural_frequency_3_high);
  c.number(m.knee_torque).number(m.measured_mean_te).number(m.predicted_mean_te);
  c.number(m.measured_mesh_harmonic_1).number(m.predicted_mesh_harmonic_1);
  c.number(m.measured_mesh_harmonic_2).number(m.predicted_mesh_harmonic_2);
  c.number(static_cast<double>(m.modal_updates)).number(static_cast<double>(m.modal_gated));
  c.number(m.modal_nis).endRow();
}

void ReplayWriter::emitMeshPeriodStats(const drivetrain_stiffness::MeshPeriodStats& m) {
  mesh_period_totals_.add(m);
  if (auto* bag = bagFor(OutputTopics::kMeshPeriodStats))
    bag->write("/mesh_period_stats", m.header.stamp, m);
  if (!mesh_period_csv_) return;
  CsvFile& c = *mesh_period_csv_;
  c.stamp(m.header.stamp).number(m.te_mean).number(m.te_rms).number(m.te_peak_to_peak);
  c.number(m.mesh_force_mean).number(m.mesh_force_rms).number(m.mesh_force_peak_to_peak);
  c.number(m.mesh_frequency).number(m.torque).number(static_cast<double>(m.periods));
  c.number(static_cast<double>(m.samples)).number(m.duration).endRow();
}

void ReplayWriter::emitModalIdentification(const drivetrain_stiffness::ModalIdentification& m) {
  modal_totals_.add(m);
  if (auto* bag = bagFor(OutputTopics::kModalIdentification))
    bag->write("/modal_identification", m.header.stamp, m);
  if (!modal_csv_) return;
  const ros::Duration duration(m.record_duration);
  const ros::Time start = m.header.stamp - duration;
  auto head = [&](CsvFile& c, const char* status) -> CsvFile& {
    c.stamp(m.header.stamp).stamp(start).number(m.record_duration).number(m.sample_rate);
    return c.number(m.torque).number(m.pinion_speed).text(status);
  };
  auto predicted = [&](CsvFile& c, int k) {
    if (k < 0) {
      c.text("").text("").text("").text("").text("");
      return;
    }
    const drivetrain_stiffness::PredictedMode& p = m.predicted[static_cast<std::size_t>(k)];
    c.number(k).text(p.dominant).number(p.frequency).number(p.frequency_low);
    c.number(p.frequency_high);
  };
  CsvFile& c = *modal_csv_;
  for (std::size_t i = 0; i < m.modes.size(); ++i) {
    const drivetrain_stiffness::IdentifiedMode& x = m.modes[i];
    head(c, x.model_mode >= 0 ? "identified" : "unmatched").number(static_cast<double>(i));
    predicted(c, x.model_mode);
    c.number(x.frequency).number(x.frequency_std).number(x.damping).number(x.damping_std);
    (x.model_mode >= 0 ? c.number(x.mac) : c.text(""));
    c.number(x.orders).number(x.unresolved).endRow();
  }
  for (std::size_t k = 0; k < m.predicted.size(); ++k) {
    const drivetrain_stiffness::PredictedMode& p = m.predicted[k];
    if (p.identified >= 0) continue;
    const bool observable = p.observability == "observable";
    head(c, observable ? "not identified" : p.observability.c_str()).text("");
    predicted(c, static_cast<int>(k));
    for (int i = 0; i < 7; ++i) c.text("");
    c.endRow();
  }
  CsvFile& poles = *modal_poles_csv_;
  for (std::size_t i = 0; i < m.pole_order.size(); ++i) {
    const std::string& status = m.pole_status[i];
    poles.stamp(m.header.stamp).number(m.pole_order[i]).number(m.pole_frequency[i]);
    poles.number(m.pole_damping[i]).number(m.pole_frequency_std[i]).number(m.pole_damping_std[i]);
    poles.number(status == "stable" || status == "selected");
    poles.number(m.pole_mode[i]).number(status == "order band").text(status).endRow();
  }
}

void ReplayWriter::emitTransforms(const std::vector<geometry_msgs::TransformStamped>& t) {
  BagWriter* bag = bagFor(OutputTopics::kTf);
  if (!bag || t.empty()) return;
  tf2_msgs::TFMessage msg;
  msg.transforms = t;
  bag->write("/tf", t.front().header.stamp, msg);
}

void ReplayWriter::emitMarkers(const visualization_msgs::MarkerArray& m) {
  if (BagWriter* bag = bagFor(OutputTopics::kRigMarkers); bag && !m.markers.empty()) {
    bag->write("/rig_markers", m.markers.front().header.stamp, m);
  }
}

}  // namespace drivetrain_stiffness
