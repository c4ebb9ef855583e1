#include "sdftrace/io/video_writer.h"

#include <algorithm>
#include <cctype>

#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"

#if SDFT_HAVE_FFMPEG
extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}
#endif

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
std::string avError(int code) {
    char buf[AV_ERROR_MAX_STRING_SIZE] = {};
    av_strerror(code, buf, sizeof buf);
    return buf;
}
}  // namespace

struct VideoWriter::Impl {
    std::string path;
    AtomicOutput out;
    AVFormatContext* format = nullptr;
    AVCodecContext* codec = nullptr;
    AVStream* stream = nullptr;
    AVFrame* frame = nullptr;
    AVPacket* packet = nullptr;
    SwsContext* sws = nullptr;
    int width = 0, height = 0, encodedWidth = 0, encodedHeight = 0, count = 0;
    bool finished = false;

    explicit Impl(const std::string& p) : path(p), out(p) {}
    ~Impl() {
        sws_freeContext(sws);
        av_packet_free(&packet);
        av_frame_free(&frame);
        avcodec_free_context(&codec);
        if (format) {
            if (format->pb) avio_closep(&format->pb);
            avformat_free_context(format);
        }
    }
    [[noreturn]] void fail(const std::string& what, int code) const {
        throw InputError(path + ": cannot write video: " + what +
                         (code < 0 ? " (" + avError(code) + ")" : ""));
    }
    // Sends `f` (null: flush) and writes every packet the encoder gives back.
    void encode(const AVFrame* f) {
        int r = avcodec_send_frame(codec, f);
        if (r < 0) fail("encoding a frame failed", r);
        for (;;) {
            r = avcodec_receive_packet(codec, packet);
            if (r == AVERROR(EAGAIN) || r == AVERROR_EOF) return;
            if (r < 0) fail("encoding a frame failed", r);
            av_packet_rescale_ts(packet, codec->time_base, stream->time_base);
            packet->stream_index = stream->index;
            r = av_interleaved_write_frame(format, packet);
            if (r < 0) fail("writing a frame failed", r);
        }
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
    av_log_set_level(AV_LOG_QUIET);  // errors reach the user as one InputError line
    Impl& s = *m;
    s.width = width;
    s.height = height;
    s.encodedWidth = width & ~1;
    s.encodedHeight = height & ~1;
    const std::string e = lowerExtension(path);
    const char* container = e == "mkv" ? "matroska" : (e == "mov" ? "mov" : "mp4");
    int r = avformat_alloc_output_context2(&s.format, nullptr, container, nullptr);
    if (r < 0 || !s.format) s.fail("no " + std::string(container) + " muxer", r);
    const AVCodec* h264 = avcodec_find_encoder(AV_CODEC_ID_H264);
    if (!h264) s.fail("this FFmpeg has no H.264 encoder", 0);
    s.stream = avformat_new_stream(s.format, nullptr);
    s.codec = avcodec_alloc_context3(h264);
    s.frame = av_frame_alloc();
    s.packet = av_packet_alloc();
    if (!s.stream || !s.codec || !s.frame || !s.packet) s.fail("out of memory", 0);
    const AVRational rate = av_d2q(fps, 100000);
    s.codec->width = s.encodedWidth;
    s.codec->height = s.encodedHeight;
    s.codec->time_base = av_inv_q(rate);
    s.codec->framerate = rate;
    s.codec->pix_fmt = AV_PIX_FMT_YUV420P;
    s.codec->gop_size = 12;
    if (s.format->oformat->flags & AVFMT_GLOBALHEADER)
        s.codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    av_opt_set(s.codec->priv_data, "preset", "medium", 0);
    av_opt_set(s.codec->priv_data, "crf", "18", 0);  // visually lossless for renders
    if ((r = avcodec_open2(s.codec, h264, nullptr)) < 0) s.fail("opening the H.264 encoder", r);
    if ((r = avcodec_parameters_from_context(s.stream->codecpar, s.codec)) < 0)
        s.fail("setting the stream up", r);
    s.stream->time_base = s.codec->time_base;
    s.frame->format = AV_PIX_FMT_YUV420P;
    s.frame->width = s.encodedWidth;
    s.frame->height = s.encodedHeight;
    if ((r = av_frame_get_buffer(s.frame, 0)) < 0) s.fail("allocating a frame", r);
    s.sws =
        sws_getContext(s.encodedWidth, s.encodedHeight, AV_PIX_FMT_RGB24, s.encodedWidth,
                       s.encodedHeight, AV_PIX_FMT_YUV420P, SWS_BICUBIC, nullptr, nullptr, nullptr);
    if (!s.sws) s.fail("setting up the colour conversion", 0);
    if ((r = avio_open(&s.format->pb, s.out.tempPath().c_str(), AVIO_FLAG_WRITE)) < 0)
        s.fail("opening the file", r);
    if ((r = avformat_write_header(s.format, nullptr)) < 0) s.fail("writing the header", r);
}

VideoWriter::~VideoWriter() = default;

void VideoWriter::addFrame(const unsigned char* rgb) {
    Impl& s = *m;
    int r = av_frame_make_writable(s.frame);
    if (r < 0) s.fail("preparing a frame", r);
    // The first encodedWidth x encodedHeight pixels: an odd last column or row is left out.
    const uint8_t* src[1] = {rgb};
    const int stride[1] = {3 * s.width};
    sws_scale(s.sws, src, stride, 0, s.encodedHeight, s.frame->data, s.frame->linesize);
    s.frame->pts = s.count++;
    s.encode(s.frame);
}

void VideoWriter::finish() {
    Impl& s = *m;
    if (s.finished) return;
    s.encode(nullptr);
    int r = av_write_trailer(s.format);
    if (r < 0) s.fail("writing the index", r);
    if ((r = avio_closep(&s.format->pb)) < 0) s.fail("closing the file", r);
    s.out.commit();
    s.finished = true;
}

int VideoWriter::frames() const { return m->count; }

VideoInfo probeVideo(const std::string& path) {
    VideoInfo info;
    AVFormatContext* f = nullptr;
    if (avformat_open_input(&f, path.c_str(), nullptr, nullptr) < 0) return info;
    if (avformat_find_stream_info(f, nullptr) >= 0) {
        const int s = av_find_best_stream(f, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
        if (s >= 0) {
            const AVCodecParameters* p = f->streams[s]->codecpar;
            info.width = p->width;
            info.height = p->height;
            info.codec = avcodec_get_name(p->codec_id);
            info.frames = 0;
            AVPacket* pkt = av_packet_alloc();
            while (pkt && av_read_frame(f, pkt) >= 0) {
                info.frames += pkt->stream_index == s;
                av_packet_unref(pkt);
            }
            av_packet_free(&pkt);
        }
    }
    avformat_close_input(&f);
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
