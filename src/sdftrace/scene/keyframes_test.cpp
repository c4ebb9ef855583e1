// Keyframe tracks: exact at their keys, continuous between them (smooth ones with a continuous
// velocity too), held or repeated outside the keyed span.
#include "sdftrace/scene/keyframes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace sdft {
namespace {

// Uneven times and values of three components, drawn from a seed.
std::vector<Keyframe> randomKeys(int n, uint32_t seed) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> gap(0.1, 2.0), value(-5, 5);
    std::vector<Keyframe> keys;
    double t = value(gen);
    for (int k = 0; k < n; ++k) {
        keys.push_back({t, {value(gen), value(gen), value(gen)}});
        t += gap(gen);
    }
    return keys;
}

const Interpolation kAll[] = {Interpolation::Linear, Interpolation::Step, Interpolation::Smooth};

TEST(Keyframes, EveryInterpolationIsExactAtItsKeys) {
    for (int n : {1, 2, 3, 7})
        for (Interpolation in : kAll)
            for (Extrapolation ex : {Extrapolation::Clamp, Extrapolation::Loop}) {
                const auto keys = randomKeys(n, 3 + n);
                KeyframeTrack track(keys, in, ex);
                for (const Keyframe& k : keys) EXPECT_EQ(track.at(k.time), k.value);
            }
}

TEST(Keyframes, LinearAndSmoothAreContinuousAndStepHoldsUntilTheNextKey) {
    const auto keys = randomKeys(6, 11);
    for (Interpolation in : kAll) {
        KeyframeTrack track(keys, in, Extrapolation::Clamp);
        // The largest jump over a tiny time step, anywhere in the keyed span.
        const double dt = 1e-7;
        double worst = 0;
        for (double t = keys.front().time; t < keys.back().time; t += 1e-3) {
            const auto a = track.at(t), b = track.at(t + dt);
            for (size_t c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(a[c] - b[c]));
        }
        if (in == Interpolation::Step) {
            for (size_t k = 0; k + 1 < keys.size(); ++k) {
                EXPECT_EQ(track.at(0.5 * (keys[k].time + keys[k + 1].time)), keys[k].value);
                EXPECT_EQ(track.at(keys[k + 1].time - 1e-9), keys[k].value);  // until the key
            }
        } else {
            EXPECT_LT(worst, 1e-4) << static_cast<int>(in);  // slopes are below ~1e2 per unit
        }
    }
    // Linear: halfway between two keys is their mean.
    KeyframeTrack linear(keys, Interpolation::Linear, Extrapolation::Clamp);
    const auto mid = linear.at(0.5 * (keys[2].time + keys[3].time));
    for (size_t c = 0; c < 3; ++c)
        EXPECT_NEAR(mid[c], 0.5 * (keys[2].value[c] + keys[3].value[c]), 1e-12);
}

TEST(Keyframes, SmoothHasAContinuousVelocityAtTheKeys) {
    const auto keys = randomKeys(6, 17);
    KeyframeTrack track(keys, Interpolation::Smooth, Extrapolation::Clamp);
    const double h = 1e-6;
    for (size_t k = 1; k + 1 < keys.size(); ++k) {
        const double t = keys[k].time;
        const auto before = track.at(t - h), at = track.at(t), after = track.at(t + h);
        const double expected[3] = {
            (keys[k + 1].value[0] - keys[k - 1].value[0]) / (keys[k + 1].time - keys[k - 1].time),
            (keys[k + 1].value[1] - keys[k - 1].value[1]) / (keys[k + 1].time - keys[k - 1].time),
            (keys[k + 1].value[2] - keys[k - 1].value[2]) / (keys[k + 1].time - keys[k - 1].time)};
        for (size_t c = 0; c < 3; ++c) {
            const double left = (at[c] - before[c]) / h, right = (after[c] - at[c]) / h;
            EXPECT_NEAR(left, right, 1e-3 * (1 + std::fabs(left))) << "key " << k;
            EXPECT_NEAR(left, expected[c], 1e-3 * (1 + std::fabs(left))) << "key " << k;
        }
    }
}

TEST(Keyframes, ClampHoldsTheEndsAndLoopRepeatsTheSpan) {
    const auto keys = randomKeys(4, 5);
    const double t0 = keys.front().time, t1 = keys.back().time, period = t1 - t0;
    for (Interpolation in : kAll) {
        KeyframeTrack clamp(keys, in, Extrapolation::Clamp), loop(keys, in, Extrapolation::Loop);
        EXPECT_EQ(clamp.at(t0 - 3), keys.front().value);
        EXPECT_EQ(clamp.at(t1 + 3), keys.back().value);
        for (double u : {0.1, 0.37, 0.8}) {
            const auto inside = loop.at(t0 + u * period);
            for (int turns : {-2, -1, 1, 3}) {
                const auto outside = loop.at(t0 + u * period + turns * period);
                for (size_t c = 0; c < 3; ++c) EXPECT_NEAR(outside[c], inside[c], 1e-9);
            }
        }
    }
}

// A closed loop (last value = first) turns smoothly through its seam: a circle keyed at four
// points and its first point again stays within 12% of the radius (Catmull-Rom: 0.884 at 45
// degrees) and has the same velocity on both sides of the seam.
TEST(Keyframes, ASmoothClosedLoopHasNoCornerAtItsSeam) {
    std::vector<Keyframe> keys;
    for (int k = 0; k <= 4; ++k) {
        const double a = k * M_PI / 2;
        keys.push_back({static_cast<double>(k), {std::cos(a), std::sin(a)}});
    }
    keys.back().value = keys.front().value;  // exactly, despite cos/sin rounding
    KeyframeTrack track(keys, Interpolation::Smooth, Extrapolation::Loop);
    for (double t = 0; t < 8; t += 0.01) {
        const auto p = track.at(t);
        EXPECT_NEAR(std::hypot(p[0], p[1]), 1.0, 0.12) << t;
    }
    const double h = 1e-6;
    const auto before = track.at(4 - h), seam = track.at(4), after = track.at(4 + h);
    for (size_t c = 0; c < 2; ++c)
        EXPECT_NEAR((seam[c] - before[c]) / h, (after[c] - seam[c]) / h, 1e-3);
}

}  // namespace
}  // namespace sdft
