// Video files (issue 16: `render --time A:B -o anim.mp4`): sRGB frames encoded as H.264 through
// FFmpeg's libraries from Debian (libavcodec, libavformat, libswscale), in an MP4, Matroska or
// QuickTime container by the extension. The file is written to a temporary name and renamed when
// the last frame is in (AtomicOutput): an interrupted or failed render leaves no file. A build
// without FFmpeg has the same API and refuses video paths with one clear error.
#pragma once

#include <memory>
#include <string>

namespace sdft {

class VideoWriter {
  public:
    // Whether this build can write video.
    static bool available();
    // .mp4, .mkv or .mov (case-insensitive).
    static bool isVideoPath(const std::string& path);

    // `fps` frames per second, in (0, 1000]. H.264 with 4:2:0 chroma takes even sizes: an odd
    // width or height loses its last column or row. Throws InputError naming the path.
    VideoWriter(const std::string& path, int width, int height, double fps);
    ~VideoWriter();
    VideoWriter(const VideoWriter&) = delete;
    VideoWriter& operator=(const VideoWriter&) = delete;

    // One frame of the constructor's size: 3 sRGB bytes per pixel, row 0 at the top.
    void addFrame(const unsigned char* rgb);
    // Flushes the encoder, writes the container's index and renames the file into place.
    void finish();
    int frames() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

// What a video file holds (for tests and checks): its first video stream's size, codec and
// frame count (by reading every packet); frames = -1 if the file cannot be read as video.
struct VideoInfo {
    int width = 0, height = 0, frames = -1;
    std::string codec;
};
VideoInfo probeVideo(const std::string& path);

}  // namespace sdft
