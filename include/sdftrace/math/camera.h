// Pinhole camera (docs/design.md conventions): eye, target, up, vertical fov in degrees. Pixel (x,
// y) has its centre at (x + 0.5, y + 0.5); row 0 is the top of the image; primary directions are
// unit.
#pragma once

#include <cmath>

#include "sdftrace/math/ray.h"

namespace sdft {

struct CameraDesc {
    Vec3 eye{0, 1, 5};
    Vec3 target{0, 0, 0};
    Vec3 up{0, 1, 0};
    float fovDeg = 45;
    int width = 640;
    int height = 480;
};

class Camera {
  public:
    explicit Camera(const CameraDesc& d) : m_desc(d) {
        m_forward = normalize(d.target - d.eye);
        m_right = normalize(cross(m_forward, d.up));
        m_up = cross(m_right, m_forward);
        m_tanHalf = std::tan(0.5f * radians(d.fovDeg));
        m_aspect = static_cast<float>(d.width) / static_cast<float>(d.height);
    }

    // Ray through the point (px, py) in pixel coordinates (pixel centres at +0.5).
    SDFT_HOST_DEVICE Ray rayThrough(float px, float py) const {
        float sx = (2.0f * px / m_desc.width - 1.0f) * m_tanHalf * m_aspect;
        float sy = (1.0f - 2.0f * py / m_desc.height) * m_tanHalf;
        return {m_desc.eye, normalize(m_forward + m_right * sx + m_up * sy)};
    }
    SDFT_HOST_DEVICE Ray pixelRay(int x, int y) const { return rayThrough(x + 0.5f, y + 0.5f); }

    // Where p lands on the image (pixel coordinates, centres at +0.5); false behind the eye.
    SDFT_HOST_DEVICE bool project(Vec3 p, float& px, float& py) const {
        const Vec3 d = p - m_desc.eye;
        const float z = dot(d, m_forward);
        if (z <= 0) return false;
        const float sx = dot(d, m_right) / z, sy = dot(d, m_up) / z;
        px = (sx / (m_tanHalf * m_aspect) + 1.0f) * 0.5f * m_desc.width;
        py = (1.0f - sy / m_tanHalf) * 0.5f * m_desc.height;
        return true;
    }

    // Radius of half a pixel at distance 1 (Keinert et al. 2014, Listing 2's pixelRadius).
    SDFT_HOST_DEVICE float pixelRadius() const { return m_tanHalf / m_desc.height; }
    SDFT_HOST_DEVICE const CameraDesc& desc() const { return m_desc; }
    // The orthonormal frame (forward towards the target) and tan(fov / 2).
    SDFT_HOST_DEVICE Vec3 forward() const { return m_forward; }
    SDFT_HOST_DEVICE Vec3 right() const { return m_right; }
    SDFT_HOST_DEVICE Vec3 up() const { return m_up; }
    SDFT_HOST_DEVICE float tanHalfFov() const { return m_tanHalf; }

  private:
    CameraDesc m_desc;
    Vec3 m_forward, m_right, m_up;
    float m_tanHalf = 1, m_aspect = 1;
};

}  // namespace sdft
