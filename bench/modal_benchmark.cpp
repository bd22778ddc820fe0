// Cost of one output-only modal identification (docs/vibration.md, "Cost"): 2 channels at
// 51.2 kHz, a 1 s record of the rig's two modes, model orders 2..40, with and without the
// variance propagation (50 blocks); the pole selection; the mesh-order removal of orders 1-3.
//   devel/lib/drivetrain_stiffness/modal_benchmark
#include <cmath>

#include <benchmark/benchmark.h>

#include "drivetrain_stiffness/modal/order_removal.hpp"
#include "drivetrain_stiffness/modal/pole_selection.hpp"
#include "drivetrain_stiffness/modal/ssi_cov.hpp"
#include "synthetic_modes.hpp"  // NOLINT(build/include_subdir)

namespace {
using namespace drivetrain_stiffness::modal;

constexpr double kFs = 51200.0;

const Eigen::MatrixXd& record() {
  static const Eigen::MatrixXd y = test::rigModes(kFs).record(51200, 7);
  return y;
}

void BM_SsiCovIdentify(benchmark::State& state) {
  SsiOptions o;
  o.max_order = static_cast<int>(state.range(0));
  o.variance_blocks = static_cast<int>(state.range(1));
  const SsiCov ssi(o);
  size_t poles = 0;
  for (auto _ : state) {
    const SsiResult r = ssi.identify(record(), kFs);
    poles = r.poles.size();
    benchmark::DoNotOptimize(poles);
  }
  state.counters["poles"] = static_cast<double>(poles);
}
BENCHMARK(BM_SsiCovIdentify)
    ->Args({40, 50})
    ->Args({40, 0})
    ->Args({20, 50})
    ->Unit(benchmark::kMillisecond);

void BM_SelectModes(benchmark::State& state) {
  SsiOptions o;
  o.max_order = 40;
  const SsiResult r = SsiCov(o).identify(record(), kFs);
  for (auto _ : state) benchmark::DoNotOptimize(selectModes(r).modes.size());
}
BENCHMARK(BM_SelectModes)->Unit(benchmark::kMillisecond);

void BM_OrderRemoval(benchmark::State& state) {
  OrderRemovalOptions o;
  o.orders = {1.0, 2.0, 3.0};
  const OrderRemoval removal(o);
  Eigen::VectorXd angle(record().cols());
  for (long t = 0; t < angle.size(); ++t) angle[t] = 2.0 * M_PI * 8600.0 * t / kFs;
  Eigen::MatrixXd y = record();
  for (auto _ : state) {
    y = record();
    removal.remove(y, angle, kFs);
    benchmark::DoNotOptimize(y.data());
  }
}
BENCHMARK(BM_OrderRemoval)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
