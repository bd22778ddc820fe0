// The YAML file loaders on hostile files: each case is the bytes of one file.
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "case_files.hpp"
#include "field_rule.hpp"
#include "finite_checks.hpp"
#include "fuzz_target.hpp"
#include "refusal.hpp"

namespace drivetrain_stiffness::fuzz {
namespace {

// Mesh tables cost time linear in mesh.samples (up to the 100000 the loader allows): past this,
// an accepted rig is not handed on to the estimator, to keep every case cheap. The estimator's
// own tests cover large tables.
constexpr int kMaxSamplesForEstimator = 1024;

template <typename Load>
CaseStats loadCase(const char* subdir, const std::uint8_t* data, std::size_t size, Load load) {
  CaseStats stats;
  const std::string path = CaseFiles::instance().write(subdir, data, size);
  if (acceptOrRefuse(
          stats, [&] { load(path); },
          [&](const std::string& m) { requireNamesYamlField(m, path); })) {
    ++stats.accepted;
  }
  return stats;
}

}  // namespace

CaseStats fuzzBearingFile(const std::uint8_t* data, std::size_t size) {
  return loadCase("bearings", data, size, [](const std::string& path) { loadBearingFile(path); });
}

CaseStats fuzzGearFile(const std::uint8_t* data, std::size_t size) {
  return loadCase("gearboxes", data, size, [](const std::string& path) { loadGearFile(path); });
}

CaseStats fuzzRigFile(const std::uint8_t* data, std::size_t size) {
  RigConfig rig;
  bool loaded = false;
  CaseStats stats = loadCase("gearboxes", data, size, [&](const std::string& path) {
    rig = loadRigFile(path);
    loaded = true;
  });
  // A rig the loader accepted goes on to the estimator (what the node does next, with its limits):
  // it may still be refused (a preload no bearing equilibrium carries), naming the field, but never
  // with a crash, another exception type or a non-finite initial estimate.
  if (loaded && rig.mesh_samples <= kMaxSamplesForEstimator) {
    acceptOrRefuse(
        stats,
        [&] {
          requireAllFinite(StiffnessEstimator(rig, PipelineOptions::onlineLimits()).current());
        },
        &requireNamesSchemaKey);
  }
  return stats;
}

}  // namespace drivetrain_stiffness::fuzz
