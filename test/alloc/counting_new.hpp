// A counting global operator new for the allocation tests: link counting_new.cpp into a test
// binary of its own (it replaces operator new for the whole binary) and read allocationCount()
// around the code under test.
#pragma once

namespace drivetrain_stiffness::test {

/// Heap allocations through operator new since the binary started.
long allocationCount();

}  // namespace drivetrain_stiffness::test
