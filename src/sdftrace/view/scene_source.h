// The viewer's input, watched: a scene file (or a mesh or grid file, or the demo) loaded as
// `render` loads it, and loaded again when the file changes on disk. A load that fails keeps the
// last good scene and says why, so that editing the JSON in another window never loses the view.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

#include "sdftrace/scene/scene.h"

namespace sdft {

class SceneSource {
  public:
    enum class Poll { Unchanged, Reloaded, Failed };

    // Loads the input ("" is the demo); throws InputError when the first load fails.
    explicit SceneSource(std::string input);

    // Whether the file changed (time or size) since it was last read; if so, reads it again.
    Poll poll();
    // Reads the file again now.
    Poll reload();

    const Scene& scene() const { return m_scene; }
    const std::string& input() const { return m_input; }
    // Why the last reload failed (one line, as the CLI prints it); empty after a good load.
    const std::string& error() const { return m_error; }
    // A note on what was done to a mesh or grid input ("" for scene files).
    const std::string& note() const { return m_note; }
    // Good loads so far (the first included).
    int loads() const { return m_loads; }

  private:
    struct Stamp {
        std::filesystem::file_time_type time{};
        uintmax_t size = 0;
        bool exists = false;
        bool operator==(const Stamp&) const = default;
    };
    Stamp stamp() const;
    void load();  // throws InputError; the scene is replaced only when it succeeds

    std::string m_input;
    Scene m_scene;
    std::string m_error, m_note;
    Stamp m_stamp;
    int m_loads = 0;
};

}  // namespace sdft
