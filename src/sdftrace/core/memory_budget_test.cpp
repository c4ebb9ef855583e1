#include "sdftrace/core/memory_budget.h"

#include <gtest/gtest.h>

#include <new>
#include <string>

#include "sdftrace/core/error.h"

namespace sdft {
namespace {

// A reader's allocation failure ends as one InputError naming the file (never std::bad_alloc);
// its value and its own InputErrors pass through unchanged.
TEST(MemoryBudget, ReadersEndAllocationFailuresInOneLine) {
    EXPECT_EQ(readWithinBudget("a.vdb", [] { return 7; }), 7);
    try {
        readWithinBudget("scan.ply", []() -> int { throw std::bad_alloc(); });
        FAIL() << "no error";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("scan.ply: reading it needs more memory than the budget of ", 0), 0u)
            << what;
        EXPECT_EQ(what.find('\n'), std::string::npos);
    }
    EXPECT_THROW(readWithinBudget("x.sdfg", []() -> int { throw InputError("x.sdfg: bad"); }),
                 InputError);
}

// Checked before an allocation: over the budget is an InputError that names what asked.
TEST(MemoryBudget, ChecksNameWhatAsked) {
    const double before = memoryBudgetIsSet() ? memoryBudgetBytes() : 0;  // 0: the default
    setMemoryBudgetBytes(1 << 20);
    EXPECT_NO_THROW(checkMemoryBudget(1000, "--res", "the grid", "lower --res"));
    try {
        checkMemoryBudget(4e6, "--res", "the grid", "lower --res");
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("--res: needs ", 0), 0u) << e.what();
    }
    setMemoryBudgetBytes(before);
}

}  // namespace
}  // namespace sdft
