// Keyframed values (issue 16): a number or a vector given at a few times and interpolated between
// them, the way animation tools store a curve. Linear, step (held until the next key) or smooth:
// a cubic Hermite spline through the keys whose tangents are the centred differences of their
// neighbours over their time span (Catmull-Rom for even spacing), so position and velocity are
// continuous at every key. Before the first and after the last key the curve holds its end value
// (clamp) or repeats the keyed span (loop).
#pragma once

#include <cstddef>
#include <vector>

namespace sdft {

enum class Interpolation { Linear, Step, Smooth };
enum class Extrapolation { Clamp, Loop };

struct Keyframe {
    double time = 0;
    std::vector<double> value;  // one or more components, the same count in every key
};

class KeyframeTrack {
  public:
    // Keys in strictly increasing time, at least one, every value of the same non-zero size
    // (callers validate input; this checks).
    KeyframeTrack(std::vector<Keyframe> keys, Interpolation interpolation,
                  Extrapolation extrapolation);

    // The curve at time t, `components()` values into out. Exact at every key.
    void evaluate(double t, double* out) const;
    std::vector<double> at(double t) const;

    size_t components() const { return m_keys.front().value.size(); }
    double firstTime() const { return m_keys.front().time; }
    double lastTime() const { return m_keys.back().time; }
    const std::vector<Keyframe>& keys() const { return m_keys; }

  private:
    // Velocity (value per unit time) of the smooth curve at key k.
    double tangent(size_t k, size_t c) const;

    std::vector<Keyframe> m_keys;
    Interpolation m_interpolation;
    Extrapolation m_extrapolation;
    bool m_periodic = false;  // loop whose last value equals its first: tangents wrap around
};

}  // namespace sdft
