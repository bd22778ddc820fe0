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

#include "bag/bag_writer.hpp"      // NOLINT(build/include_subdir)
#include "mesh_period_totals.hpp"  // NOLINT(build/include_subdir)
#include "modal_totals.hpp"        // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/ros/message_sink.hpp"

namespace drivetrain_stiffness {

/// Which output topics drivetrain_replay writes (--topics to the bag and the CSV files,
/// --csv-topics to the CSV files alone). The messages are built either way (the pipeline and the
/// sink run identically); only their writing is skipped. A campaign keeps a bag's report small with
/// it (measured_te at the encoders' 5 kHz is the largest file: docs/campaign.md).
class OutputTopics {
 public:
  /// In the order of kNames; a bit per topic.
  enum Topic : unsigned {
    kStiffness,
    kTransmissionError,
    kTeSpectrum,
    kResonance,
    kMeasuredTe,
    kCalibration,
    kMeshPeriodStats,
    kTf,
    kRigMarkers,
    kModalIdentification,
    kCount
  };
  /// The topic names as written to the bag (without the leading '/'), as --topics takes them.
  static constexpr const char* kNames[kCount] = {
      "stiffness",   "transmission_error", "te_spectrum", "resonance",   "measured_te",
      "calibration", "mesh_period_stats",  "tf",          "rig_markers", "modal_identification"};
  static OutputTopics all() { return OutputTopics((1u << kCount) - 1u); }
  /// "all", or names from kNames separated by commas; throws InvalidInput naming `option` and the
  /// unknown or empty name.
  static OutputTopics parse(const std::string& option, const std::string& list);
  bool has(Topic t) const { return (bits_ >> t) & 1u; }
  bool includes(const OutputTopics& other) const { return (other.bits_ & ~bits_) == 0u; }
  std::string describe() const;  ///< "all" or the names, comma-separated, in kNames order

 private:
  explicit OutputTopics(unsigned bits) : bits_(bits) {}
  unsigned bits_;
};

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
  CsvFile& text(
      const std::string& s);  ///< quoted (RFC 4180) if it holds a comma, a quote or a line break
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
  /// out_bag and csv_dir may be empty (not written); only `bag_topics` go to the bag and only
  /// `csv_topics` to the CSV files.
  ReplayWriter(const RigPipeline& pipeline, const OutputSettings& settings,
               const std::string& out_bag, BagCompression compression, const std::string& csv_dir,
               OutputTopics bag_topics = OutputTopics::all(),
               OutputTopics csv_topics = OutputTopics::all());
  void close();
  /// Every mesh_period_stats block so far, summed (whether or not --topics writes the topic).
  const MeshPeriodTotals& meshPeriodTotals() const { return mesh_period_totals_; }
  /// Every modal identification so far, summed (whether or not --topics writes the topic).
  const ModalTotals& modalTotals() const { return modal_totals_; }
  const OutputTopics& topics() const { return bag_topics_; }     ///< what the bag holds
  const OutputTopics& csvTopics() const { return csv_topics_; }  ///< what the CSV files hold

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
  void emitModalIdentification(const drivetrain_stiffness::ModalIdentification& m) override;

 private:
  /// The bag, if --out was given and the topic is selected.
  BagWriter* bagFor(OutputTopics::Topic t) const {
    return bag_topics_.has(t) ? bag_.get() : nullptr;
  }

  OutputTopics bag_topics_, csv_topics_;
  MeshPeriodTotals mesh_period_totals_;
  ModalTotals modal_totals_;
  std::unique_ptr<BagWriter> bag_;
  std::unique_ptr<CsvFile> stiffness_csv_, te_csv_, spectrum_csv_, resonance_csv_, measured_te_csv_,
      calibration_csv_, mesh_period_csv_, modal_csv_, modal_poles_csv_;
  std::vector<std::string> bearing_names_;
};

}  // namespace drivetrain_stiffness
