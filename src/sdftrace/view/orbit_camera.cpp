#include "sdftrace/view/orbit_camera.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sdft {

namespace {

// v rotated by `angle` radians about the unit axis k (Rodrigues).
Vec3 rotate(Vec3 v, Vec3 k, float angle) {
    const float c = std::cos(angle), s = std::sin(angle);
    return v * c + cross(k, v) * s + k * (dot(k, v) * (1 - c));
}

}  // namespace

void OrbitCamera::orbit(float dx, float dy) {
    const Vec3 up = normalize(m_camera.up);
    Vec3 offset = m_camera.eye - m_camera.target;
    const float r = length(offset);
    offset = rotate(offset, up, -dx * kDegreesPerPixel * kPi / 180);
    // Pitch, clamped so that the offset stays between 1 and 179 degrees from the up axis.
    const float polar = std::acos(std::clamp(dot(offset / r, up), -1.0f, 1.0f));
    const float limit = kPi / 180;
    const float wanted = std::clamp(polar - dy * kDegreesPerPixel * kPi / 180, limit, kPi - limit);
    const Vec3 right = normalize(cross(up, offset));
    if (length(right) > 0) offset = rotate(offset, right, wanted - polar);
    m_camera.eye = m_camera.target + normalize(offset) * r;
}

void OrbitCamera::pan(float dx, float dy) {
    const Vec3 forward = normalize(m_camera.target - m_camera.eye);
    const Vec3 right = normalize(cross(forward, m_camera.up));
    const Vec3 camUp = cross(right, forward);
    const float distance = length(m_camera.target - m_camera.eye);
    const float perPixel = 2 * distance * std::tan(m_camera.fovDeg * kPi / 360) /
                           static_cast<float>(std::max(1, m_camera.height));
    const Vec3 delta = (right * -dx + camUp * dy) * perPixel;
    m_camera.eye = m_camera.eye + delta;
    m_camera.target = m_camera.target + delta;
}

void OrbitCamera::zoom(float clicks) {
    const Vec3 offset = m_camera.eye - m_camera.target;
    const float r = length(offset);
    // Between 1e-4 and 1e4 times the scene camera's distance (floats stay meaningful).
    const float home = std::max(1e-3f, length(m_home.eye - m_home.target));
    const double wanted = std::clamp(static_cast<double>(r) * std::pow(kZoomPerClick, clicks),
                                     1e-4 * home, 1e4 * home);
    m_camera.eye = m_camera.target + offset * static_cast<float>(wanted / r);
}

void OrbitCamera::fly(float forward, float right, float up) {
    const Vec3 f = normalize(m_camera.target - m_camera.eye);
    const Vec3 r = normalize(cross(f, m_camera.up));
    const Vec3 u = cross(r, f);
    const Vec3 delta = f * forward + r * right + u * up;
    m_camera.eye = m_camera.eye + delta;
    m_camera.target = m_camera.target + delta;
}

float OrbitCamera::flySpeed() const { return 0.5f * length(m_camera.target - m_camera.eye); }

void OrbitCamera::reset() {
    const int w = m_camera.width, h = m_camera.height;
    m_camera = m_home;
    m_camera.width = w;
    m_camera.height = h;
}

void OrbitCamera::setSize(int width, int height) {
    m_camera.width = width;
    m_camera.height = height;
}

std::string OrbitCamera::cliFlags() const {
    char buf[400];
    const CameraDesc& c = m_camera;
    std::snprintf(buf, sizeof buf,
                  "--eye %.9g,%.9g,%.9g --target %.9g,%.9g,%.9g --up %.9g,%.9g,%.9g --fov %.9g "
                  "--width %d --height %d",
                  c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y,
                  c.up.z, c.fovDeg, c.width, c.height);
    return buf;
}

}  // namespace sdft
