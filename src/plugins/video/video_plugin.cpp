// The video plugin (src/sdftrace/io/video_plugin.h): H.264 through FFmpeg's libraries from Debian,
// behind a table of plain functions. Errors come back as one line each; nothing throws across the
// boundary.
#include "sdftrace/io/video_plugin.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include <new>
#include <string>

namespace {

std::string avError(int code) {
    char buf[AV_ERROR_MAX_STRING_SIZE] = {};
    av_strerror(code, buf, sizeof buf);
    return buf;
}

struct Encoder {
    AVFormatContext* format = nullptr;
    AVCodecContext* codec = nullptr;
    AVStream* stream = nullptr;
    AVFrame* frame = nullptr;
    AVPacket* packet = nullptr;
    SwsContext* sws = nullptr;
    int width = 0, height = 0, count = 0;

    ~Encoder() {
        sws_freeContext(sws);
        av_packet_free(&packet);
        av_frame_free(&frame);
        avcodec_free_context(&codec);
        if (format) {
            if (format->pb) avio_closep(&format->pb);
            avformat_free_context(format);
        }
    }
    bool fail(std::string& error, const std::string& what, int code) const {
        error = what + (code < 0 ? " (" + avError(code) + ")" : "");
        return false;
    }
    // Sends `f` (null: flush) and writes every packet the encoder gives back.
    bool encode(const AVFrame* f, std::string& error) {
        int r = avcodec_send_frame(codec, f);
        if (r < 0) return fail(error, "encoding a frame failed", r);
        for (;;) {
            r = avcodec_receive_packet(codec, packet);
            if (r == AVERROR(EAGAIN) || r == AVERROR_EOF) return true;
            if (r < 0) return fail(error, "encoding a frame failed", r);
            av_packet_rescale_ts(packet, codec->time_base, stream->time_base);
            packet->stream_index = stream->index;
            r = av_interleaved_write_frame(format, packet);
            if (r < 0) return fail(error, "writing a frame failed", r);
        }
    }
    bool setUp(const char* file, const char* container, double fps, std::string& error);
};

bool Encoder::setUp(const char* file, const char* container, double fps, std::string& error) {
    int r = avformat_alloc_output_context2(&format, nullptr, container, nullptr);
    if (r < 0 || !format) return fail(error, "no " + std::string(container) + " muxer", r);
    const AVCodec* h264 = avcodec_find_encoder(AV_CODEC_ID_H264);
    if (!h264) return fail(error, "this FFmpeg has no H.264 encoder", 0);
    stream = avformat_new_stream(format, nullptr);
    codec = avcodec_alloc_context3(h264);
    frame = av_frame_alloc();
    packet = av_packet_alloc();
    if (!stream || !codec || !frame || !packet) return fail(error, "out of memory", 0);
    const AVRational rate = av_d2q(fps, 100000);
    codec->width = width;
    codec->height = height;
    codec->time_base = av_inv_q(rate);
    codec->framerate = rate;
    codec->pix_fmt = AV_PIX_FMT_YUV420P;
    codec->gop_size = 12;
    if (format->oformat->flags & AVFMT_GLOBALHEADER) codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    av_opt_set(codec->priv_data, "preset", "medium", 0);
    av_opt_set(codec->priv_data, "crf", "18", 0);  // visually lossless for renders
    if ((r = avcodec_open2(codec, h264, nullptr)) < 0)
        return fail(error, "opening the H.264 encoder", r);
    if ((r = avcodec_parameters_from_context(stream->codecpar, codec)) < 0)
        return fail(error, "setting the stream up", r);
    stream->time_base = codec->time_base;
    frame->format = AV_PIX_FMT_YUV420P;
    frame->width = width;
    frame->height = height;
    if ((r = av_frame_get_buffer(frame, 0)) < 0) return fail(error, "allocating a frame", r);
    sws = sws_getContext(width, height, AV_PIX_FMT_RGB24, width, height, AV_PIX_FMT_YUV420P,
                         SWS_BICUBIC, nullptr, nullptr, nullptr);
    if (!sws) return fail(error, "setting up the colour conversion", 0);
    if ((r = avio_open(&format->pb, file, AVIO_FLAG_WRITE)) < 0)
        return fail(error, "opening the file", r);
    if ((r = avformat_write_header(format, nullptr)) < 0)
        return fail(error, "writing the header", r);
    return true;
}

void* openEncoder(const char* file, const char* container, int width, int height, double fps,
                  std::string& error) {
    av_log_set_level(AV_LOG_QUIET);  // errors reach the user as one line
    auto* e = new (std::nothrow) Encoder;
    if (!e) {
        error = "out of memory";
        return nullptr;
    }
    e->width = width;
    e->height = height;
    if (!e->setUp(file, container, fps, error)) {
        delete e;
        return nullptr;
    }
    return e;
}

bool addFrame(void* encoder, const unsigned char* rgb, int stride, std::string& error) {
    auto& e = *static_cast<Encoder*>(encoder);
    const int r = av_frame_make_writable(e.frame);
    if (r < 0) return e.fail(error, "preparing a frame", r);
    const uint8_t* src[1] = {rgb};
    const int strides[1] = {stride};
    sws_scale(e.sws, src, strides, 0, e.height, e.frame->data, e.frame->linesize);
    e.frame->pts = e.count++;
    return e.encode(e.frame, error);
}

bool finish(void* encoder, std::string& error) {
    auto& e = *static_cast<Encoder*>(encoder);
    if (!e.encode(nullptr, error)) return false;
    int r = av_write_trailer(e.format);
    if (r < 0) return e.fail(error, "writing the index", r);
    if ((r = avio_closep(&e.format->pb)) < 0) return e.fail(error, "closing the file", r);
    return true;
}

void closeEncoder(void* encoder) { delete static_cast<Encoder*>(encoder); }

bool probe(const char* path, int& width, int& height, int& frames, std::string& codec) {
    AVFormatContext* f = nullptr;
    if (avformat_open_input(&f, path, nullptr, nullptr) < 0) return false;
    bool ok = false;
    if (avformat_find_stream_info(f, nullptr) >= 0) {
        const int s = av_find_best_stream(f, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
        if (s >= 0) {
            const AVCodecParameters* p = f->streams[s]->codecpar;
            width = p->width;
            height = p->height;
            codec = avcodec_get_name(p->codec_id);
            frames = 0;
            AVPacket* pkt = av_packet_alloc();
            while (pkt && av_read_frame(f, pkt) >= 0) {
                frames += pkt->stream_index == s;
                av_packet_unref(pkt);
            }
            av_packet_free(&pkt);
            ok = true;
        }
    }
    avformat_close_input(&f);
    return ok;
}

const sdft::VideoPlugin kTable = {
    sdft::VideoPlugin::kVersion, openEncoder, addFrame, finish, closeEncoder, probe};

}  // namespace

extern "C" __attribute__((visibility("default"))) const sdft::VideoPlugin* sdftrace_video_plugin() {
    return &kTable;
}
