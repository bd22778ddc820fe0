#include "fuzz_driver.hpp"

#include <algorithm>
#include <cctype>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "field_rule.hpp"

namespace drivetrain_stiffness::fuzz {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr std::size_t kPoolSize = 256;

void writeFile(const std::string& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// Numbers masked, so that refusals of one kind count as one shape.
std::string shapeOf(const std::string& message) {
  std::string s;
  for (std::size_t i = 0; i < message.size() && s.size() < 200; ++i) {
    const char c = message[i];
    if (std::isdigit(static_cast<unsigned char>(c))) {
      if (s.empty() || s.back() != '#') s.push_back('#');
    } else {
      s.push_back(c);
    }
  }
  return s;
}

// Ends the process if one case runs longer than the timeout (the long run's hang check).
class Watchdog {
 public:
  Watchdog(double timeout_s, std::string target) : timeout_(timeout_s), target_(std::move(target)) {
    if (timeout_ > 0.0) thread_ = std::thread([this] { watch(); });
  }
  ~Watchdog() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  void start(std::uint64_t case_number) {
    case_number_ = case_number;
    started_ = Clock::now().time_since_epoch().count();
  }

 private:
  void watch() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::milliseconds(100), [this] { return done_; })) {
      const double running = std::chrono::duration<double>(Clock::now().time_since_epoch() -
                                                           Clock::duration(started_.load()))
                                 .count();
      if (running > timeout_) {
        std::fprintf(stderr, "HANG: %s case %llu ran longer than %.1f s\n", target_.c_str(),
                     static_cast<unsigned long long>(case_number_.load()), timeout_);
        std::fflush(stderr);
        std::_Exit(124);
      }
    }
  }
  double timeout_;
  std::string target_;
  std::atomic<std::uint64_t> case_number_{0};
  std::atomic<Clock::rep> started_{
      Clock::now().time_since_epoch().count()};  ///< of the running case
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace

std::vector<SeedFile> loadCorpusFiles(const FuzzTarget& target) {
  std::vector<fs::path> files;
  for (const auto& entry :
       fs::directory_iterator(fs::path(sourceDir()) / "test" / "data" / "fuzz" / target.corpus)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<SeedFile> corpus;
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    corpus.push_back({f.filename().string(),
                      Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>())});
  }
  return corpus;
}

std::vector<std::string> fuzzDictionary() {
  std::vector<std::string> words = {"bearing",
                                    "bearings",
                                    "gears",
                                    "anti_backlash",
                                    "mesh",
                                    "dynamics",
                                    "name",
                                    "shaft",
                                    "mesh_load_share",
                                    "file",
                                    "balls",
                                    "ball_diameter",
                                    "pitch_diameter",
                                    "inner_groove_conformity",
                                    "contact_angle_deg",
                                    "diametral_clearance",
                                    "teeth",
                                    "profile_shift",
                                    "module",
                                    "pressure_angle_deg",
                                    "samples",
                                    "model",
                                    "axial_preload",
                                    "radial_preload",
                                    "arrangement",
                                    "tilt",
                                    "bore_diameter",
                                    "outside_diameter",
                                    "inner_interference",
                                    "bearing_clearance",
                                    "speed_rpm",
                                    "spring_stiffness",
                                    "preload_torque",
                                    "center_distance",
                                    "face_width"};
  for (const std::string& p : nodeParameterNames()) words.push_back(p);
  return words;
}

RunStats runTarget(const FuzzTarget& target, const RunOptions& options) {
  std::vector<Bytes> corpus;
  for (SeedFile& seed : loadCorpusFiles(target)) corpus.push_back(std::move(seed.bytes));
  if (corpus.empty()) throw std::runtime_error(std::string("no seed corpus for ") + target.name);
  const std::size_t max_size = target.max_size;
  const std::string running_file =
      options.findings_dir.empty() ? "" : options.findings_dir + "/last-" + target.name + ".bin";
  Mutator mutator(options.seed, target.text ? fuzzDictionary() : std::vector<std::string>{});
  std::vector<Bytes> pool;  // accepted mutants: later cases mutate them further
  RunStats stats;
  Watchdog watchdog(options.case_timeout_s, target.name);
  const std::uint64_t total = corpus.size() + options.cases;
  for (std::uint64_t n = 0; n < total; ++n) {
    Bytes input;
    if (n < corpus.size()) {
      input = corpus[n];
      ++stats.corpus_cases;
    } else {
      const bool from_pool = !pool.empty() && mutator.below(2) == 0;
      const Bytes& parent =
          from_pool ? pool[mutator.below(pool.size())] : corpus[mutator.below(corpus.size())];
      input = mutator.mutate(parent, corpus[mutator.below(corpus.size())], target.text, max_size);
    }
    if (!running_file.empty()) writeFile(running_file, input);
    watchdog.start(n);
    const auto started = Clock::now();
    try {
      const CaseStats c = target.fuzzOne(input.data(), input.size());
      stats.accepted += c.accepted;
      stats.refused += c.refused;
      if (options.collect_refusals) {
        for (const std::string& r : c.refusals) ++stats.refusal_shapes[shapeOf(r)];
      }
      if (c.accepted > 0 && n >= corpus.size()) {
        if (pool.size() < kPoolSize)
          pool.push_back(input);
        else
          pool[mutator.below(kPoolSize)] = input;
      }
    } catch (const std::exception& e) {  // FuzzFinding, or anything fuzzOne let through
      stats.findings.push_back({n, e.what(), input});
      if (!options.findings_dir.empty()) {
        writeFile(
            options.findings_dir + "/finding-" + target.name + "-" + std::to_string(n) + ".bin",
            input);
      }
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
    if (seconds > stats.slowest_case_s) {
      stats.slowest_case_s = seconds;
      stats.slowest_case = n;
    }
    ++stats.cases;
  }
  if (!running_file.empty()) fs::remove(running_file);
  return stats;
}

std::string hexDump(const Bytes& bytes, std::size_t max_bytes) {
  std::string out;
  char buf[4];
  for (std::size_t i = 0; i < bytes.size() && i < max_bytes; ++i) {
    std::snprintf(buf, sizeof buf, "%02x ", bytes[i]);
    out += buf;
  }
  if (bytes.size() > max_bytes) out += "... (" + std::to_string(bytes.size()) + " bytes)";
  return out;
}

}  // namespace drivetrain_stiffness::fuzz
