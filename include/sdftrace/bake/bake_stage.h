// The stages of a bake and their times, for the summary `sdftrace bake` prints.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace sdft {

struct BakeStage {
    std::string name;
    double seconds = 0;
};

// Records the time since the previous mark (or construction) under a stage name.
class StageClock {
  public:
    explicit StageClock(std::vector<BakeStage>& stages) : m_stages(stages) {}
    void mark(const std::string& name) {
        auto now = std::chrono::steady_clock::now();
        m_stages.push_back({name, std::chrono::duration<double>(now - m_last).count()});
        m_last = now;
    }
    void restart() { m_last = std::chrono::steady_clock::now(); }

  private:
    std::vector<BakeStage>& m_stages;
    std::chrono::steady_clock::time_point m_last = std::chrono::steady_clock::now();
};

}  // namespace sdft
