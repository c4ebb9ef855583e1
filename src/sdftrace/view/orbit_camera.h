// The viewer's camera controller (sdftrace view, docs/viewer.md): orbit about the target, pan, zoom
// and fly, as mouse drags (pixels), wheel clicks and key presses turn into camera moves; the camera
// printed as the CLI flags that reproduce it.
#pragma once
#include <string>

#include "sdftrace/math/camera.h"

namespace sdft {

class OrbitCamera {
  public:
    static constexpr float kDegreesPerPixel = 0.25f;  // orbit
    static constexpr float kZoomPerClick = 0.85f;     // distance factor per wheel click

    explicit OrbitCamera(const CameraDesc& home) : m_home(home), m_camera(home) {}

    // A drag of (dx, dy) pixels (+y down): yaw about the up axis and pitch about the camera's
    // right axis, kept 1 degree away from the poles.
    void orbit(float dx, float dy);
    // The target and the eye move with the drag, so that the point under the cursor at the
    // target's depth follows it.
    void pan(float dx, float dy);
    // `clicks` > 0 moves towards the target (distance times 0.85 per click), within 1e-4 and 1e4
    // times the scene camera's distance.
    void zoom(float clicks);
    // Eye and target move together along the view (forward), right and up axes, in world units.
    void fly(float forward, float right, float up);
    // World units per second of fly(): half the distance to the target.
    float flySpeed() const;
    void reset();
    void setHome(const CameraDesc& home) { m_home = home; }
    // The image size (a window resize); kept by reset().
    void setSize(int width, int height);
    const CameraDesc& camera() const { return m_camera; }
    void setCamera(const CameraDesc& camera) { m_camera = camera; }
    // "--eye x,y,z --target x,y,z --up x,y,z --fov f --width w --height h", with the digits that
    // reproduce the floats exactly.
    std::string cliFlags() const;

  private:
    CameraDesc m_home, m_camera;
};

}  // namespace sdft
