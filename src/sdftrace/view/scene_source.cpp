#include "sdftrace/view/scene_source.h"

#include <system_error>

#include "sdftrace/core/error.h"
#include "sdftrace/scene/load_input.h"

namespace sdft {

SceneSource::SceneSource(std::string input) : m_input(std::move(input)) { load(); }

void SceneSource::load() {
    m_stamp = stamp();
    LoadedInput loaded = loadSceneInput(m_input, false);
    m_scene = std::move(loaded.scene);
    m_note = std::move(loaded.note);
    m_error.clear();
    ++m_loads;
}

SceneSource::Stamp SceneSource::stamp() const {
    Stamp s;
    if (m_input.empty()) return s;
    std::error_code ec;
    s.time = std::filesystem::last_write_time(m_input, ec);
    if (ec) return s;
    s.size = std::filesystem::file_size(m_input, ec);
    s.exists = !ec;
    return s;
}

SceneSource::Poll SceneSource::poll() {
    if (m_input.empty() || stamp() == m_stamp) return Poll::Unchanged;
    return reload();
}

SceneSource::Poll SceneSource::reload() {
    if (m_input.empty()) return Poll::Unchanged;
    try {
        load();
        return Poll::Reloaded;
    } catch (const InputError& e) {
        m_error = e.what();
        return Poll::Failed;
    }
}

}  // namespace sdft
