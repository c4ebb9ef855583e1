// Progress of long work on stderr: a percentage rewritten in place when stderr is a terminal.
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
    bool m_enabled;
    std::atomic<uint64_t> m_done{0};
    std::atomic<int> m_lastPercent{-1};
};

// True when stderr is a terminal (progress lines would not clutter logs).
bool stderrIsTerminal();

}  // namespace sdft
