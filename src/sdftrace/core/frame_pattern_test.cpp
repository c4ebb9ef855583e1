#include "sdftrace/core/frame_pattern.h"

#include <gtest/gtest.h>

namespace sdft {
namespace {

TEST(FramePattern, OneIntegerFieldAndLiteralPercents) {
    for (const char* ok : {"f_%d.png", "out/%04d.exr", "%%done_%03d.ply", "a%%%d%%.obj", "%123d"})
        EXPECT_TRUE(isFramePattern(ok)) << ok;
    for (const char* bad : {"f.png", "%d_%d.png", "%s.png", "%04x.png", "50%", "%1234d", "%ld"})
        EXPECT_FALSE(isFramePattern(bad)) << bad;
    EXPECT_EQ(framePath("out/%04d.exr", 7), "out/0007.exr");
    EXPECT_EQ(framePath("%%done_%d.ply", 12), "%done_12.ply");
    EXPECT_EQ(framePath("f_%d.png", 5000000000LL), "f_5000000000.png");
}

}  // namespace
}  // namespace sdft
