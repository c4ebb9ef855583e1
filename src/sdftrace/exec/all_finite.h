// Whether every value of a float array is finite: loaders check their samples before a grid is
// built from them (a NaN or infinity would reach every ray that reads it).
#pragma once

#include <cstddef>

namespace sdft {

// In parallel for large arrays; x * 0 is NaN exactly where x is not finite, so the test is one
// multiply-add per value without a branch.
bool allFinite(const float* values, size_t count);

}  // namespace sdft
