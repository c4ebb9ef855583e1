#include "sdftrace/scene/grid_scene.h"

#include <cmath>

namespace sdft {

CameraDesc frameBounds(const Bounds3& b, float fovDeg, int width, int height) {
    CameraDesc c;
    c.fovDeg = fovDeg;
    c.width = width;
    c.height = height;
    Vec3 center = b.center();
    float radius = 0.5f * length(b.extent());
    float halfFov = radians(0.5f * fovDeg);
    // Fit the sphere in the narrower of the two fields of view.
    float aspect = static_cast<float>(width) / height;
    float halfNarrow = aspect < 1 ? std::atan(std::tan(halfFov) * aspect) : halfFov;
    float distance = radius / std::sin(halfNarrow) * 1.05f;
    c.target = center;
    c.eye = center + normalize(Vec3(0.55f, 0.45f, 1.0f)) * distance;
    c.up = {0, 1, 0};
    return c;
}

Scene sceneForObject(NodePtr object, const Bounds3& bounds) {
    Scene s;
    s.materials.push_back(Material{"default", {0.78f, 0.76f, 0.72f}, 1.0f, 0.25f, 40.0f});
    s.root = std::move(object);
    s.camera = frameBounds(bounds, 35.0f, 640, 480);
    Light key;
    key.direction = normalize(Vec3(-0.4f, -1.0f, -0.5f));
    key.intensity = 0.9f;
    Light fill;
    fill.direction = normalize(Vec3(0.7f, -0.3f, 0.2f));
    fill.intensity = 0.3f;
    fill.castShadows = false;
    s.lighting.lights = {key, fill};
    s.lighting.ambient = {0.08f, 0.08f, 0.1f};
    s.lighting.background = {0.18f, 0.19f, 0.22f};
    return s;
}

}  // namespace sdft
