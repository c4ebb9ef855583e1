// A ready-to-render scene around one field object (a grid file rendered directly): a camera that
// frames its bounds, a key and a fill light, a neutral material.
#pragma once

#include "sdftrace/scene/scene.h"

namespace sdft {

// Looks at the bounds' centre from above and to the front-right, far enough for the bounding sphere
// to fit the vertical field of view (docs/design.md camera conventions).
CameraDesc frameBounds(const Bounds3& bounds, float fovDeg, int width, int height);

Scene sceneForObject(NodePtr object, const Bounds3& bounds);

}  // namespace sdft
