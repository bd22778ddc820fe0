#include "refusal.hpp"

#include <cxxabi.h>

#include <cstdlib>
#include <memory>
#include <typeinfo>

namespace drivetrain_stiffness::fuzz {

std::string describeException(const std::exception& e) {
  const char* mangled = typeid(e).name();
  int status = 0;
  std::unique_ptr<char, void (*)(void*)> demangled(
      abi::__cxa_demangle(mangled, nullptr, nullptr, &status), std::free);
  return std::string(status == 0 && demangled ? demangled.get() : mangled) + ": " + e.what();
}

}  // namespace drivetrain_stiffness::fuzz
