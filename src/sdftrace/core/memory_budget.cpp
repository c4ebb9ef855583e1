#include "sdftrace/core/memory_budget.h"

#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "sdftrace/core/error.h"

namespace sdft {

namespace {
std::atomic<double> g_budget{0.0};  // 0: the default
std::atomic<int> g_sharers{1};

// Where the default comes from, for error messages.
std::string defaultSource() {
    std::string s = "half of this machine's " + formatBytes(physicalMemoryBytes());
    if (g_sharers.load() > 1) s += " shared by " + std::to_string(g_sharers.load()) + " ranks";
    return s;
}
}  // namespace

double peakResidentMiB() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss / 1024.0;  // KiB on Linux
}

double physicalMemoryBytes() {
    // Once: sysconf(_SC_PHYS_PAGES) is a sysinfo() system call, and the allocation guard asks for
    // the budget on every operator new (it made a million-triangle mesh load 6x slower).
    static const double bytes =
        static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
    return bytes;
}

double memoryBudgetBytes() {
    const double set = g_budget.load();
    return set > 0 ? set : 0.5 * physicalMemoryBytes() / g_sharers.load();
}

void setMemorySharers(int processes) { g_sharers.store(processes > 1 ? processes : 1); }

void setMemoryBudgetBytes(double bytes) { g_budget.store(bytes > 0 ? bytes : 0.0); }

bool memoryBudgetIsSet() { return g_budget.load() > 0; }

std::string formatBytes(double bytes) {
    char buf[64];
    if (bytes >= 1024.0 * 1024 * 1024)
        std::snprintf(buf, sizeof buf, "%.1f GiB", bytes / (1024.0 * 1024 * 1024));
    else if (bytes >= 1024.0 * 1024)
        std::snprintf(buf, sizeof buf, "%.0f MiB", bytes / (1024.0 * 1024));
    else if (bytes >= 1024.0)
        std::snprintf(buf, sizeof buf, "%.0f KiB", bytes / 1024.0);
    else
        std::snprintf(buf, sizeof buf, "%.0f bytes", bytes);
    return buf;
}

void throwOverBudget(const std::string& what) {
    throw InputError(what + ": reading it needs more memory than the budget of " +
                     formatBytes(memoryBudgetBytes()) + " (" +
                     (memoryBudgetIsSet() ? "--max-memory" : defaultSource()) +
                     "), or the file is damaged; raise --max-memory if it is not");
}

void checkMemoryBudget(double bytes, const std::string& what, const std::string& forWhat,
                       const std::string& advice) {
    const double budget = memoryBudgetBytes();
    if (!(bytes > budget)) return;
    const std::string source =
        memoryBudgetIsSet() ? "--max-memory" : defaultSource() + "; raise it with --max-memory";
    throw InputError(what + ": needs " + formatBytes(bytes) + " (" + forWhat +
                     "), more than the memory budget of " + formatBytes(budget) + " (" + source +
                     "); " + advice);
}

bool parseByteSize(const std::string& text, double& bytes) {
    const char* s = text.c_str();
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (end == s || !std::isfinite(v) || v <= 0) return false;
    std::string unit(end);
    for (char& c : unit) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    double scale = 0;
    if (unit.empty() || unit == "b")
        scale = 1;
    else if (unit == "k" || unit == "kb" || unit == "kib")
        scale = 1024.0;
    else if (unit == "m" || unit == "mb" || unit == "mib")
        scale = 1024.0 * 1024;
    else if (unit == "g" || unit == "gb" || unit == "gib")
        scale = 1024.0 * 1024 * 1024;
    else if (unit == "t" || unit == "tb" || unit == "tib")
        scale = 1024.0 * 1024 * 1024 * 1024;
    if (scale == 0) return false;
    bytes = v * scale;
    return bytes >= 1;
}

}  // namespace sdft
