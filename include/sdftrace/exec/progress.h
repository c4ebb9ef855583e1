// Progress of long work on stderr: a percentage rewritten in place when stderr is a terminal, one
// line per 10 % when it is not (a log: under mpirun rank 0's stderr is a pipe to mpirun). Callers
// enable it only where stderr is a terminal, except for a distributed job's rank 0.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

namespace sdft {

class Progress {
  public:
    Progress(std::string label, uint64_t total, bool enabled);
    ~Progress();
    void advance(uint64_t n = 1);

  private:
    std::string m_label;
    uint64_t m_total;
    bool m_enabled, m_lines;
    std::atomic<uint64_t> m_done{0};
    std::atomic<int> m_lastPercent{-1};
};

// True when stderr is a terminal (progress lines would not clutter logs).
bool stderrIsTerminal();

}  // namespace sdft
