// Video output: frames in, an H.264 file out with as many frames, nothing left behind on failure.
#include "sdftrace/io/video_writer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <vector>

#include "sdftrace/core/error.h"

namespace sdft {
namespace {

namespace fs = std::filesystem;

struct Dir {
    fs::path path = fs::temp_directory_path() / ("sdft_video_" + std::to_string(::getpid()));
    Dir() { fs::create_directories(path); }
    ~Dir() { fs::remove_all(path); }
    size_t count() const {
        return static_cast<size_t>(std::distance(fs::directory_iterator(path), {}));
    }
};

// A moving gradient, so that every frame differs.
std::vector<unsigned char> frame(int w, int h, int k) {
    std::vector<unsigned char> rgb(static_cast<size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            unsigned char* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
            p[0] = static_cast<unsigned char>((x + 4 * k) * 255 / (w + 40));
            p[1] = static_cast<unsigned char>(y * 255 / h);
            p[2] = static_cast<unsigned char>(k * 20);
        }
    return rgb;
}

TEST(VideoWriter, WritesEveryFrameAsH264) {
    if (!VideoWriter::available()) GTEST_SKIP() << "this build has no FFmpeg";
    Dir dir;
    for (const char* name : {"a.mp4", "b.mkv", "c.MOV"}) {
        const std::string path = (dir.path / name).string();
        VideoWriter v(path, 65, 49, 24);  // odd: encoded as 64x48
        for (int k = 0; k < 10; ++k) v.addFrame(frame(65, 49, k).data());
        EXPECT_FALSE(fs::exists(path)) << "the file appears only when finished";
        v.finish();
        const VideoInfo info = probeVideo(path);
        EXPECT_EQ(info.frames, 10) << name;
        EXPECT_EQ(info.width, 64) << name;
        EXPECT_EQ(info.height, 48) << name;
        EXPECT_EQ(info.codec, "h264") << name;
    }
    EXPECT_EQ(dir.count(), 3u);
}

TEST(VideoWriter, AnUnfinishedOrFailedVideoLeavesNoFile) {
    if (!VideoWriter::available()) GTEST_SKIP() << "this build has no FFmpeg";
    Dir dir;
    {
        VideoWriter v((dir.path / "x.mp4").string(), 32, 32, 30);
        v.addFrame(frame(32, 32, 0).data());
    }  // destroyed without finish(): as when a render fails half way
    EXPECT_EQ(dir.count(), 0u);
    EXPECT_THROW(VideoWriter("/nonexistent-dir/x.mp4", 32, 32, 30), InputError);
    EXPECT_THROW(VideoWriter((dir.path / "x.avi").string(), 32, 32, 30), InputError);
    EXPECT_THROW(VideoWriter((dir.path / "x.mp4").string(), 32, 32, 0), InputError);
    EXPECT_EQ(dir.count(), 0u);
}

TEST(VideoWriter, VideoPathsByExtension) {
    EXPECT_TRUE(VideoWriter::isVideoPath("out/anim.mp4"));
    EXPECT_TRUE(VideoWriter::isVideoPath("anim.MKV"));
    EXPECT_TRUE(VideoWriter::isVideoPath("a.b/anim.mov"));
    EXPECT_FALSE(VideoWriter::isVideoPath("anim.png"));
    EXPECT_FALSE(VideoWriter::isVideoPath("mp4"));
    EXPECT_FALSE(VideoWriter::isVideoPath("dir.mp4/anim"));
}

}  // namespace
}  // namespace sdft
