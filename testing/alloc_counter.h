#pragma once

// Counts every global operator new in the test binary that links alloc_counter.cc, so a test
// can prove a hot path allocates nothing: read AllocationCount() before and after.

namespace tangent::testing {
long AllocationCount();
}  // namespace tangent::testing
