// The long run: drivetrain_fuzz [--target NAME|all] [--cases N] [--seed S] [--timeout SECONDS]
//                               [--findings DIR] [--show-refusals]
//                drivetrain_fuzz --target NAME --replay FILE...
// Runs each target over its corpus and N seeded mutations (default 100000) with a per-case
// watchdog (exit 124 on a hang), prints the counts as one JSON line per target, and exits 1 if
// anything was found. --replay runs given case files (findings, libFuzzer crashes).
// The watchdog's default, 60 s, is a hang and not a slow case: a legitimate case may set up exact
// propagators at ~1 rpm, which the library bounds at 2e6 Magnus steps (~9 s here, more under ASan).
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "fuzz_driver.hpp"
#include "fuzz_target.hpp"

using namespace drivetrain_stiffness::fuzz;

namespace {

int usage(const std::string& why) {
  std::cerr
      << why
      << "\nusage: drivetrain_fuzz [--target NAME|all] [--cases N] [--seed S] [--timeout SECONDS]"
      << " [--findings DIR] [--show-refusals] | --target NAME --replay FILE...\ntargets:";
  for (const FuzzTarget& t : fuzzTargets()) std::cerr << " " << t.name;
  std::cerr << "\n";
  return 2;
}

int replay(const FuzzTarget& target, const std::vector<std::string>& files) {
  int found = 0;
  for (const std::string& file : files) {
    std::ifstream in(file, std::ios::binary);
    const Bytes input((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    try {
      const CaseStats c = target.fuzzOne(input.data(), input.size());
      std::cout << file << ": " << c.accepted << " accepted, " << c.refused << " refused\n";
      for (const std::string& r : c.refusals) std::cout << "  refused: " << r << "\n";
    } catch (const std::exception& e) {
      std::cout << file << ": FINDING: " << e.what() << "\n";
      ++found;
    }
  }
  return found ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string target_name = "all";
  RunOptions options;
  options.cases = 100000;
  options.case_timeout_s = 60.0;
  std::vector<std::string> replay_files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
      return argv[++i];
    };
    try {
      if (arg == "--target")
        target_name = value();
      else if (arg == "--cases")
        options.cases = std::stoull(value());
      else if (arg == "--seed")
        options.seed = std::stoull(value());
      else if (arg == "--timeout")
        options.case_timeout_s = std::stod(value());
      else if (arg == "--findings")
        options.findings_dir = value();
      else if (arg == "--show-refusals")
        options.collect_refusals = true;
      else if (arg == "--replay")
        while (i + 1 < argc) replay_files.push_back(argv[++i]);
      else
        return usage("unknown option " + arg);
    } catch (const std::exception& e) {
      return usage(arg + ": " + e.what());
    }
  }
  if (!replay_files.empty()) {
    const FuzzTarget* t = findFuzzTarget(target_name);
    return t ? replay(*t, replay_files) : usage("--replay needs one --target");
  }
  std::vector<const FuzzTarget*> targets;
  if (target_name == "all") {
    for (const FuzzTarget& t : fuzzTargets()) targets.push_back(&t);
  } else if (const FuzzTarget* t = findFuzzTarget(target_name)) {
    targets.push_back(t);
  } else {
    return usage("no target " + target_name);
  }
  std::size_t findings = 0;
  for (const FuzzTarget* t : targets) {
    const RunStats s = runTarget(*t, options);
    for (const Finding& f : s.findings) {
      std::cerr << t->name << " case " << f.case_number << ": " << f.what
                << "\n  input: " << hexDump(f.input) << "\n";
    }
    if (options.collect_refusals) {
      for (const auto& [shape, count] : s.refusal_shapes)
        std::cerr << t->name << " refusal x" << count << ": " << shape << "\n";
    }
    std::printf(
        "{\"target\": \"%s\", \"seed\": %llu, \"cases\": %llu, \"seed_files\": %llu, "
        "\"inputs_accepted\": %llu, "
        "\"inputs_refused\": %llu, \"findings\": %zu, \"slowest_case_s\": %.3f, \"slowest_case\": "
        "%llu}\n",
        t->name, static_cast<unsigned long long>(options.seed),
        static_cast<unsigned long long>(s.cases), static_cast<unsigned long long>(s.corpus_cases),
        static_cast<unsigned long long>(s.accepted), static_cast<unsigned long long>(s.refused),
        s.findings.size(), s.slowest_case_s, static_cast<unsigned long long>(s.slowest_case));
    std::fflush(stdout);
    findings += s.findings.size();
  }
  return findings ? 1 : 0;
}
