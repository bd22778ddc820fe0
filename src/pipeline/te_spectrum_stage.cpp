#include "drivetrain_stiffness/pipeline/te_spectrum_stage.hpp"

#include <algorithm>
#include <vector>

namespace drivetrain_stiffness {

TeSpectrumStage::TeSpectrumStage(int window, int hop, double interval)
    : spectrum_(window, hop, interval, SpectrumPeaks::kMaxPeaks) {}

void TeSpectrumStage::sample(Stamp stamp, const DynamicsSample& s, double /*mesh_frequency*/,
                             PipelineSink& sink) {
  if (!spectrum_.push(s.dynamic_te)) return;
  const std::vector<SpectralPeak>& peaks = spectrum_.peaks();
  SpectrumPeaks& out = peaks_;
  out.count = std::min(peaks.size(), SpectrumPeaks::kMaxPeaks);
  std::copy_n(peaks.begin(), out.count, out.peaks.begin());
  out.resolution = spectrum_.resolution();
  out.window_seconds = spectrum_.windowSeconds();
  sink.spectrum(stamp, out);
  ++counters_.spectra_out;
}

}  // namespace drivetrain_stiffness
