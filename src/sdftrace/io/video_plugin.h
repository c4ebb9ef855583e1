// FFmpeg's encoder as a plugin (docs/decisions/0020-video-as-a-plugin.md): libsdftrace_video.so
// links libavcodec, libavformat and libswscale and is loaded when a video is first written or
// read, so that the commands that write none (every one but `render` of a video) do not load
// libavformat and the 130-odd libraries behind it, which cost every process more than half of
// its start-up.
//
// The same header declares the plugin's table (built by src/plugins/video/video_plugin.cpp) and
// the loader. Only plain values and std::string cross the boundary, so the plugin needs no
// symbol of this library.
#pragma once

#include <string>

namespace sdft {

struct VideoPlugin {
    static constexpr int kVersion = 1;
    int version = 0;
    // An H.264 encoder writing `file` in `container` ("mp4", "matroska" or "mov"), frames of
    // width x height (even) at `fps`; null with `error` set on failure.
    void* (*open)(const char* file, const char* container, int width, int height, double fps,
                  std::string& error) = nullptr;
    // One frame: 3 sRGB bytes per pixel, rows of `stride` bytes, row 0 at the top.
    bool (*addFrame)(void* encoder, const unsigned char* rgb, int stride,
                     std::string& error) = nullptr;
    // Flushes the encoder, writes the container's index and closes the file.
    bool (*finish)(void* encoder, std::string& error) = nullptr;
    // Frees the encoder (finished or not).
    void (*close)(void* encoder) = nullptr;
    // A video file's first video stream: its size, codec and packet count; false if the file
    // cannot be read as video.
    bool (*probe)(const char* path, int& width, int& height, int& frames,
                  std::string& codec) = nullptr;
};

// The plugin's table, loaded once (thread-safe); throws InputError naming `purpose` and the
// places searched when it is missing or of another version.
const VideoPlugin& videoPlugin(const std::string& purpose);
// The same, or null when it cannot be loaded.
const VideoPlugin* videoPluginIfPresent();

}  // namespace sdft

// The plugin's one exported symbol.
extern "C" const sdft::VideoPlugin* sdftrace_video_plugin();
