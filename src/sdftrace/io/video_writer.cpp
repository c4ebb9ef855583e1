#include "sdftrace/io/video_writer.h"

#include <algorithm>
#include <cctype>

#include "sdftrace/core/error.h"
#include "sdftrace/core/plugin_dirs.h"
#include "sdftrace/io/atomic_file.h"
#include "video_plugin.h"

namespace sdft {

namespace {
std::string lowerExtension(const std::string& path) {
    const size_t dot = path.rfind('.');
    if (dot == std::string::npos || path.find('/', dot) != std::string::npos) return "";
    std::string e = path.substr(dot + 1);
    std::transform(e.begin(), e.end(), e.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e;
}
}  // namespace

bool VideoWriter::isVideoPath(const std::string& path) {
    const std::string e = lowerExtension(path);
    return e == "mp4" || e == "mkv" || e == "mov";
}

#if SDFT_HAVE_FFMPEG

namespace {
constexpr const char* kPluginFile = "libsdftrace_video.so";

struct Loaded {
    const VideoPlugin* table = nullptr;
    std::string failure;
};

const Loaded& loaded() {
    static const Loaded once = [] {
        std::string failure;
        const auto* table = static_cast<const VideoPlugin*>(
            loadPluginTable(kPluginFile, "sdftrace_video_plugin", failure));
        if (table && table->version != VideoPlugin::kVersion)
            return Loaded{nullptr, std::string(kPluginFile) +
                                       " is not this build's video plugin (rebuild sdftrace)"};
        return Loaded{table, failure};
    }();
    return once;
}
}  // namespace

const VideoPlugin& videoPlugin(const std::string& purpose) {
    if (!loaded().table)
        throw InputError(purpose + " needs sdftrace's video plugin: " + loaded().failure);
    return *loaded().table;
}

const VideoPlugin* videoPluginIfPresent() { return loaded().table; }

struct VideoWriter::Impl {
    std::string path;
    AtomicOutput out;
    const VideoPlugin* plugin = nullptr;
    void* encoder = nullptr;
    int width = 0, encodedHeight = 0, count = 0;
    bool finished = false;

    explicit Impl(const std::string& p) : path(p), out(p) {}
    ~Impl() {
        if (encoder) plugin->close(encoder);
    }
    [[noreturn]] void fail(const std::string& error) const {
        throw InputError(path + ": cannot write video: " + error);
    }
};

bool VideoWriter::available() { return true; }

VideoWriter::VideoWriter(const std::string& path, int width, int height, double fps)
    : m(std::make_unique<Impl>(path)) {
    if (!isVideoPath(path))
        throw InputError(path + ": not a video file name; accepted: .mp4, .mkv, .mov");
    if (width < 2 || height < 2)
        throw InputError(path + ": a video needs frames of at least 2x2 pixels");
    if (!(fps > 0 && fps <= 1000))
        throw InputError(path + ": frames per second must be in (0, 1000]");
    Impl& s = *m;
    s.plugin = &videoPlugin("writing " + path);
    s.width = width;
    s.encodedHeight = height & ~1;
    const std::string e = lowerExtension(path);
    const char* container = e == "mkv" ? "matroska" : (e == "mov" ? "mov" : "mp4");
    std::string error;
    // H.264 with 4:2:0 chroma takes even sizes: an odd last column or row is left out.
    s.encoder = s.plugin->open(s.out.tempPath().c_str(), container, width & ~1, s.encodedHeight,
                               fps, error);
    if (!s.encoder) s.fail(error);
}

VideoWriter::~VideoWriter() = default;

void VideoWriter::addFrame(const unsigned char* rgb) {
    Impl& s = *m;
    std::string error;
    if (!s.plugin->addFrame(s.encoder, rgb, 3 * s.width, error)) s.fail(error);
    ++s.count;
}

void VideoWriter::finish() {
    Impl& s = *m;
    if (s.finished) return;
    std::string error;
    if (!s.plugin->finish(s.encoder, error)) s.fail(error);
    s.out.commit();
    s.finished = true;
}

int VideoWriter::frames() const { return m->count; }

VideoInfo probeVideo(const std::string& path) {
    VideoInfo info;
    const VideoPlugin* plugin = videoPluginIfPresent();
    if (plugin && !plugin->probe(path.c_str(), info.width, info.height, info.frames, info.codec))
        info = {};
    return info;
}

#else  // no FFmpeg in this build

struct VideoWriter::Impl {};

bool VideoWriter::available() { return false; }

VideoWriter::VideoWriter(const std::string& path, int, int, double) {
    throw InputError(path +
                     ": this build of sdftrace writes no video (FFmpeg's libavcodec, libavformat "
                     "and libswscale were not found when it was built; write frames with "
                     "--frame-pattern)");
}
VideoWriter::~VideoWriter() = default;
void VideoWriter::addFrame(const unsigned char*) {}
void VideoWriter::finish() {}
int VideoWriter::frames() const { return 0; }
VideoInfo probeVideo(const std::string&) { return {}; }

#endif

}  // namespace sdft
