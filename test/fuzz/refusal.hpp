// The one place that sorts what a call did into accepted, refused the documented way, or a finding.
#pragma once

#include <exception>
#include <string>

#include "drivetrain_stiffness/core/validation.hpp"
#include "fuzz_target.hpp"

namespace drivetrain_stiffness::fuzz {

/// "std::out_of_range: <what>" with the dynamic type demangled.
std::string describeException(const std::exception& e);

/// Runs `call`. Returns true if it returned. InvalidInput and UnreachableLoad are refusals: their
/// message must pass `check` (a field_rule.hpp rule) and is recorded in `stats`. Any other
/// exception escaping is a FuzzFinding; a FuzzFinding from `call` passes through.
template <typename Call, typename Check>
bool acceptOrRefuse(CaseStats& stats, Call&& call, Check&& check) {
  try {
    call();
    return true;
  } catch (const FuzzFinding&) {
    throw;
  } catch (const InvalidInput& e) {
    check(std::string(e.what()));
    stats.refuse(e.what());
  } catch (const UnreachableLoad& e) {
    check(std::string(e.what()));
    stats.refuse(e.what());
  } catch (const std::exception& e) {
    throw FuzzFinding("escaped " + describeException(e));
  } catch (...) {
    throw FuzzFinding("escaped an exception not derived from std::exception");
  }
  return false;
}

}  // namespace drivetrain_stiffness::fuzz
