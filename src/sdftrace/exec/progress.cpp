#include "sdftrace/exec/progress.h"

#include <unistd.h>

#include <cstdio>

namespace sdft {

bool stderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

Progress::Progress(std::string label, uint64_t total, bool enabled)
    : m_label(std::move(label)),
      m_total(total == 0 ? 1 : total),
      m_enabled(enabled),
      m_lines(enabled && !stderrIsTerminal()) {}

Progress::~Progress() {
    if (m_enabled && !m_lines && m_lastPercent.load() >= 0) std::fprintf(stderr, "\r\033[K");
}

void Progress::advance(uint64_t n) {
    uint64_t done = m_done.fetch_add(n) + n;
    if (!m_enabled) return;
    int percent = static_cast<int>(100 * done / m_total);
    if (m_lines) percent -= percent % 10;  // a log: one line per 10 %
    int last = m_lastPercent.load();
    if (percent > last && m_lastPercent.compare_exchange_strong(last, percent)) {
        if (m_lines)
            std::fprintf(stderr, "%s: %d%%\n", m_label.c_str(), percent);
        else
            std::fprintf(stderr, "\r%s %3d%%", m_label.c_str(), percent);
        std::fflush(stderr);
    }
}

}  // namespace sdft
