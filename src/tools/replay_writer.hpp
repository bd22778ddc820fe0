// Where drivetrain_replay puts the pipeline's outputs: a bag with the node's topics (record time =
// header stamp) and flat CSV files, one per topic, numbers in shortest round-trip form
// (std::to_chars), so identical inputs give identical bytes.
#pragma once

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include <rosbag/bag.h>

#include "drivetrain_stiffness/ros/message_sink.hpp"

namespace drivetrain_stiffness {

class CsvFile {
 public:
  CsvFile(const std::string& path, const std::string& header);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  CsvFile& stamp(const ros::Time& t);  ///< sec.nsec, exact
  CsvFile& number(double v);
  CsvFile& text(const std::string& s);
  void endRow();

 private:
  void separator();
  std::FILE* file_ = nullptr;
  std::string row_;
};

class ReplayWriter : public MessageSink {
 public:
  /// out_bag and csv_dir may be empty (not written).
  ReplayWriter(const RigPipeline& pipeline, const OutputSettings& settings, const std::string& out_bag,
               const std::string& csv_dir);
  void close();

 protected:
  void emitStiffness(const drivetrain_stiffness::Stiffness& m) override;
  void emitTransmissionError(const drivetrain_stiffness::TransmissionError& m) override;
  void emitSpectrum(const drivetrain_stiffness::SpectralPeaks& m) override;
  void emitResonance(const drivetrain_stiffness::Resonance& m) override;
  void emitTransforms(const std::vector<geometry_msgs::TransformStamped>& t) override;
  void emitMarkers(const visualization_msgs::MarkerArray& m) override;

 private:
  std::unique_ptr<rosbag::Bag> bag_;
  std::unique_ptr<CsvFile> stiffness_csv_, te_csv_, spectrum_csv_, resonance_csv_;
  std::vector<std::string> bearing_names_;
};

}  // namespace drivetrain_stiffness
