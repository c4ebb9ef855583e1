// Jamriška 2010, §6: acceleration of primary rays by min/max buffers. Every surface block's
// bounding sphere is projected to a conservative square on the image; a low-resolution buffer
// keeps, per buffer pixel, the smallest entry (|c - eye| - r) and largest exit (|c - eye| + r)
// distance of the squares covering it. A primary ray then traverses only [tMin, tMax] of its buffer
// pixel, and a pixel no square covers cannot hit the surface (it lies in surface blocks only).
#pragma once

#include <vector>

#include "sdftrace/field/grid.h"
#include "sdftrace/math/camera.h"

namespace sdft {

class MinMaxBuffer {
  public:
    // `resolution` buffer pixels along the image's longer side (e.g. 64, 128, 256).
    static MinMaxBuffer build(const GridView& grid, const Camera& camera, int resolution);

    // The interval a primary ray through image pixel (x, y) must traverse; empty (t0 > t1) if none.
    void range(int x, int y, float& t0, float& t1) const;

    int width() const { return m_w; }
    int height() const { return m_h; }
    size_t squares() const { return m_squares; }

  private:
    int m_w = 0, m_h = 0;
    float m_scaleX = 1, m_scaleY = 1;  // buffer pixels per image pixel
    bool m_everything = false;         // a block reaches the camera plane: no acceleration
    std::vector<float> m_min, m_max;
    size_t m_squares = 0;
};

}  // namespace sdft
