#include "sdftrace/scene/keyframes.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/core/macros.h"

namespace sdft {

KeyframeTrack::KeyframeTrack(std::vector<Keyframe> keys, Interpolation interpolation,
                             Extrapolation extrapolation)
    : m_keys(std::move(keys)), m_interpolation(interpolation), m_extrapolation(extrapolation) {
    SDFT_CHECK(!m_keys.empty() && !m_keys.front().value.empty());
    for (size_t k = 0; k < m_keys.size(); ++k) {
        SDFT_CHECK(m_keys[k].value.size() == m_keys.front().value.size());
        SDFT_CHECK(std::isfinite(m_keys[k].time));
        if (k > 0) SDFT_CHECK(m_keys[k].time > m_keys[k - 1].time);
    }
    m_periodic = extrapolation == Extrapolation::Loop && m_keys.size() >= 3 &&
                 m_keys.back().value == m_keys.front().value;
}

double KeyframeTrack::tangent(size_t k, size_t c) const {
    const size_t n = m_keys.size();
    auto v = [&](size_t i) { return m_keys[i].value[c]; };
    auto t = [&](size_t i) { return m_keys[i].time; };
    if (n == 1) return 0;
    if (k > 0 && k + 1 < n) return (v(k + 1) - v(k - 1)) / (t(k + 1) - t(k - 1));
    if (m_periodic) {
        // Key 0 and key n - 1 are the same point of the loop: its neighbours are key n - 2 one
        // period earlier and key 1.
        const double period = t(n - 1) - t(0);
        return (v(1) - v(n - 2)) / (t(1) - (t(n - 2) - period));
    }
    // The ends: the slope of their one segment.
    return k == 0 ? (v(1) - v(0)) / (t(1) - t(0)) : (v(n - 1) - v(n - 2)) / (t(n - 1) - t(n - 2));
}

void KeyframeTrack::evaluate(double t, double* out) const {
    const size_t n = m_keys.size(), m = components();
    const double t0 = m_keys.front().time, t1 = m_keys.back().time;
    if (m_extrapolation == Extrapolation::Loop && n > 1 && (t < t0 || t > t1)) {
        const double period = t1 - t0;
        double u = std::fmod(t - t0, period);
        if (u < 0) u += period;
        t = t0 + u;
    }
    if (n == 1 || t <= t0) {
        std::copy(m_keys.front().value.begin(), m_keys.front().value.end(), out);
        return;
    }
    if (t >= t1) {
        std::copy(m_keys.back().value.begin(), m_keys.back().value.end(), out);
        return;
    }
    // The segment [k, k + 1] holding t (t0 < t < t1): the first key after t, minus one.
    const auto after = std::upper_bound(m_keys.begin(), m_keys.end(), t,
                                        [](double x, const Keyframe& key) { return x < key.time; });
    const size_t k = static_cast<size_t>(after - m_keys.begin()) - 1;
    const Keyframe &a = m_keys[k], &b = m_keys[k + 1];
    if (m_interpolation == Interpolation::Step || t == a.time) {
        std::copy(a.value.begin(), a.value.end(), out);
        return;
    }
    const double h = b.time - a.time, s = (t - a.time) / h;
    if (m_interpolation == Interpolation::Linear) {
        for (size_t c = 0; c < m; ++c) out[c] = a.value[c] + (b.value[c] - a.value[c]) * s;
        return;
    }
    // Cubic Hermite basis on the segment, tangents scaled from per time to per segment.
    const double s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2,
                 h11 = s3 - s2;
    for (size_t c = 0; c < m; ++c)
        out[c] = h00 * a.value[c] + h10 * h * tangent(k, c) + h01 * b.value[c] +
                 h11 * h * tangent(k + 1, c);
}

std::vector<double> KeyframeTrack::at(double t) const {
    std::vector<double> out(components());
    evaluate(t, out.data());
    return out;
}

}  // namespace sdft
