// Where drivetrain_replay puts the pipeline's outputs: a bag with the node's topics (record time =
// header stamp) and flat CSV files, one per topic, numbers in shortest round-trip form
// (std::to_chars), so identical inputs give identical bytes.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>


#include "bag_writer.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/ros/message_sink.hpp"

namespace drivetrain_stiffness {

/// One CSV file whose rows are formatted and written on a background thread (OrderedWorker), in
/// row order: the analysis thread only records the cells. Numbers in shortest round-trip form.
class CsvFile {
 public:
  CsvFile(const std::string& path, const std::string& header);
  ~CsvFile();  ///< close() if it was not called; an error there is printed, not thrown
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  CsvFile& stamp(const ros::Time& t);  ///< sec.nsec, exact
  CsvFile& number(double v);
  CsvFile& text(const std::string& s);  ///< quoted (RFC 4180) if it holds a comma, a quote or a line break
  void endRow();
  void close();  ///< writes the rest; throws naming the path on an I/O error

 private:
  struct Cell {
    enum class Kind : std::uint8_t { kNumber, kStamp, kText, kEndRow } kind;
    std::uint32_t sec, nsec;  ///< stamp; for text, sec is the index into Block::texts
    double number;
  };
  struct Block {
    std::vector<Cell> cells;
    std::vector<std::string> texts;
  };
  void handOver();
  void format(Block& block);  ///< worker thread

  std::string path_;
  std::FILE* file_ = nullptr;
  Block block_;
  std::string formatted_;  ///< worker's buffer
  bool closed_ = false;
  OrderedWorker<Block> worker_;  ///< last: its thread uses the members above
};

class ReplayWriter : public MessageSink {
 public:
  /// out_bag and csv_dir may be empty (not written).
  ReplayWriter(const RigPipeline& pipeline, const OutputSettings& settings, const std::string& out_bag,
               BagCompression compression, const std::string& csv_dir);
  void close();

 protected:
  void emitStiffness(const drivetrain_stiffness::Stiffness& m) override;
  void emitTransmissionError(const drivetrain_stiffness::TransmissionError& m) override;
  void emitSpectrum(const drivetrain_stiffness::SpectralPeaks& m) override;
  void emitResonance(const drivetrain_stiffness::Resonance& m) override;
  void emitMeasuredTe(const drivetrain_stiffness::MeasuredTe& m) override;
  void emitCalibration(const drivetrain_stiffness::Calibration& m) override;
  void emitMeshPeriodStats(const drivetrain_stiffness::MeshPeriodStats& m) override;
  void emitTransforms(const std::vector<geometry_msgs::TransformStamped>& t) override;
  void emitMarkers(const visualization_msgs::MarkerArray& m) override;

 private:
  std::unique_ptr<BagWriter> bag_;
  std::unique_ptr<CsvFile> stiffness_csv_, te_csv_, spectrum_csv_, resonance_csv_, measured_te_csv_, calibration_csv_,
      mesh_period_csv_;
  std::vector<std::string> bearing_names_;
};

}  // namespace drivetrain_stiffness
