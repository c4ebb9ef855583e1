// Scene files (JSON, documented in docs/scene-format.md) to a validated Scene.
// Every error is an InputError of one line: "<file>: <JSON path>: <what was wrong>; <accepted>".
#pragma once

#include <string>

#include "sdftrace/scene/scene.h"

namespace sdft {

// The scene as described: validated, with its grid files, meshes and "bake" subtrees as asset
// requests that prepareScene (prepare_scene.h) loads. `source` names the text in messages (a file
// name, or "<demo>"); relative file paths in the scene start from `baseDir`.
Scene describeSceneFile(const std::string& path);
Scene describeSceneText(const std::string& text, const std::string& source,
                        const std::string& baseDir = "");
// Described, then prepared (assets loaded and baked, no progress shown).
Scene parseSceneFile(const std::string& path);
Scene parseSceneText(const std::string& text, const std::string& source,
                     const std::string& baseDir = "");
// The built-in demo scene (the text of examples/demo.json, embedded at build time).
Scene demoScene();
const char* demoSceneText();

// Rejects images that cannot be rendered (zero, absurd, or more than this machine's memory).
void validateImageSize(int width, int height, const std::string& what);
// A camera the renderer can use: the eye away from the target (else an error naming
// `eyeTarget`), the up vector not along the view (`up`), and the image size (`size`).
void validateCamera(const CameraDesc& camera, const std::string& eyeTarget, const std::string& up,
                    const std::string& size);

}  // namespace sdft
