// The memory budget: every allocation whose size a user controls (films, grids, bake arrays,
// seeds, BVHs, shadow maps, histories) is checked against it before it is made, so that a request
// too large fails with one line instead of an out-of-memory kill halfway through. The CLI's
// --max-memory sets it; the default is half of this machine's physical memory, divided among the
// ranks of an MPI job that share the machine.
#pragma once

#include <new>
#include <string>

namespace sdft {

double physicalMemoryBytes();
// This process's peak resident memory so far, in MiB (getrusage).
double peakResidentMiB();
double memoryBudgetBytes();
// bytes <= 0 restores the default.
void setMemoryBudgetBytes(double bytes);
// True when the budget was set (--max-memory), not the default.
bool memoryBudgetIsSet();
// The processes of one job on this machine (Communicator::init, under mpirun): each one's default
// budget is its share of half the machine's memory.
void setMemorySharers(int processes);

// Throws InputError "<what>: needs <bytes> (<for>), more than the memory budget of <budget>
// (<where it comes from>); <advice>" when `bytes` exceeds the budget. `what` names the flag, file
// or JSON path that asked for it.
void checkMemoryBudget(double bytes, const std::string& what, const std::string& forWhat,
                       const std::string& advice);

// Throws InputError "<what>: reading it needs more memory than the budget of <budget> (...)".
[[noreturn]] void throwOverBudget(const std::string& what);
// read(), an allocation failure in it (the allocation guard's std::bad_alloc for one allocation
// over the budget, a third-party reader's, or the machine's memory exhausted) thrown as
// throwOverBudget(what)'s InputError: file readers end in one line, never std::bad_alloc.
template <class Read>
auto readWithinBudget(const std::string& what, Read&& read) -> decltype(read()) {
    try {
        return read();
    } catch (const std::bad_alloc&) {
        throwOverBudget(what);
    }
}
// "1.5 GiB", "820 MiB", "12 KiB", "100 bytes".
std::string formatBytes(double bytes);
// "8G", "8GiB", "512M", "1.5g", "123456" (bytes); false on anything else or on a size <= 0.
bool parseByteSize(const std::string& text, double& bytes);

}  // namespace sdft
