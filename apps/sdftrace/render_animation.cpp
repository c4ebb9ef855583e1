// sdftrace render --time A:B: the frames of a range, in order on one process or across the ranks
// of an mpirun job (docs/cluster.md): whole frames dealt when they are independent, each frame's
// tiles when they depend on the ones before (TAA, RTSDF histories).
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <optional>

#include "render_args.h"
#include "sdftrace/cluster/distributed_render.h"
#include "sdftrace/cluster/work_farm.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/frame_pattern.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/io/video_writer.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/prepare_scene.h"

namespace sdft::cli {

namespace {

// -o anim.mp4 of a --time range: the frames encoded in order (the writer opened at the first,
// whose size every later one must have), the file renamed into place after the last.
struct VideoSink {
    std::string path;
    double fps;
    std::unique_ptr<VideoWriter> writer;
    int width = 0, height = 0;

    VideoSink(std::string p, double f) : path(std::move(p)), fps(f) {}
    void add(const Film& film, long long number) {
        if (!writer) {
            writer = std::make_unique<VideoWriter>(path, film.width, film.height, fps);
            width = film.width;
            height = film.height;
        } else if (film.width != width || film.height != height) {
            throw InputError("--output " + path + ": frame " + std::to_string(number) + " is " +
                             std::to_string(film.width) + "x" + std::to_string(film.height) +
                             ", the video's frames are " + std::to_string(width) + "x" +
                             std::to_string(height) + " (the image size is keyframed)");
        }
        writer->addFrame(toneMapSrgb(film.color).data());
    }
};

// --taa for a frame's plan: its shadow test (deterministic shadows only: stochastic ones change
// every frame by design), and at the first frame the memory the history needs (its colours,
// objects and depths, and the motion vectors).
void setUpTaa(TemporalAccumulator& taa, const RenderPlan& plan, bool first) {
    const ShadowMethod method = plan.settings.shadowMethod;
    const bool deterministic = method == ShadowMethod::Hard || method == ShadowMethod::Soft;
    taa.rejectShadowChanges(plan.settings.shadows && deterministic ? 0.3f : 0.0f);
    if (!first) return;
    const int w = plan.camera.width, h = plan.camera.height;
    checkMemoryBudget(
        Film::bytesNeeded(w, h) + 37.0 * w * h, "--taa",
        "temporal accumulation of " + std::to_string(w) + "x" + std::to_string(h) + " frames",
        "render a smaller image");
}

// The TAA part of the animation's total line.
std::string taaSummary(const std::optional<TemporalAccumulator>& taa, size_t rejected,
                       long long frames) {
    if (!taa || frames < 2) return "";
    char buf[120];
    std::snprintf(buf, sizeof buf, "; TAA: %.2f%% of pixels without history per frame",
                  100.0 * static_cast<double>(rejected) /
                      (static_cast<double>(frames - 1) * taa->width() * taa->height()));
    return buf;
}

// A frame of a --time range that has been rendered: what rank 0 writes.
struct FinishedFrame {
    long long index = 0;
    Film film{0, 0, 0};
    RenderStats stats;
};

// What rank 0 does with each finished frame of a --time range: its files, the video (in frame
// order: the frames of a distributed render may finish out of order) and its line on stderr.
// Thread-safe: rank 0's own frames and the other ranks' arrive on different threads.
class FrameSink {
  public:
    FrameSink(const RenderArgs& a, const std::vector<std::pair<Aov, std::string>>& aovs,
              const FrameTimes& frames, std::optional<VideoSink>& video)
        : m_a(a), m_aovs(aovs), m_frames(frames), m_video(video) {}

    void add(FinishedFrame f) {
        const long long number = m_frames.first + f.index;
        const Film& film = f.film;
        if (!m_a.framePattern.empty())
            writeAov(film, Aov::Color, framePath(m_a.framePattern, number));
        for (const auto& [aov, path] : m_aovs) writeAov(film, aov, framePath(path, number));
        std::lock_guard lock(m_mutex);
        m_renderSeconds += f.stats.seconds;
        if (!m_a.quiet)
            std::fprintf(
                stderr,
                "sdftrace render: frame %lld of %lld (t = %.4g s) -> %s: %dx%d in %.3f "
                "s, %.2f%% hits\n",
                f.index + 1, m_frames.count, m_frames.at(f.index),
                (m_a.framePattern.empty() ? m_a.output : framePath(m_a.framePattern, number))
                    .c_str(),
                film.width, film.height, f.stats.seconds,
                100.0 * static_cast<double>(f.stats.hits) /
                    std::max<double>(1, static_cast<double>(f.stats.primaryRays)));
        if (!m_video) return;
        const long long at = f.index;
        m_pending.emplace(at, std::move(f.film));
        for (auto it = m_pending.find(m_nextVideo); it != m_pending.end();
             it = m_pending.find(m_nextVideo)) {
            m_video->add(it->second, m_frames.first + m_nextVideo);
            m_pending.erase(it);
            ++m_nextVideo;
        }
    }
    double renderSeconds() const { return m_renderSeconds; }
    const std::vector<std::pair<Aov, std::string>>& aovs() const { return m_aovs; }

  private:
    const RenderArgs& m_a;
    const std::vector<std::pair<Aov, std::string>>& m_aovs;
    const FrameTimes& m_frames;
    std::optional<VideoSink>& m_video;
    std::mutex m_mutex;
    std::map<long long, Film> m_pending;  // video frames waiting for an earlier one
    long long m_nextVideo = 0;
    double m_renderSeconds = 0;
};

// The frames of a --time range, shared by every way of rendering them: the scene of frame i at its
// time (its assets from the rank's cache, each distinct one loaded or baked once), its plan, and
// the AOVs to keep.
struct Animation {
    const RenderArgs& a;
    AnimatedScene anim;
    double fps = 30;
    FrameTimes frames;
    unsigned kept = 0;
    bool motion = false;       // motion vectors: the motion AOV or --taa
    bool distributed = false;  // an mpirun job: meshes bake on the CPU

    struct Instant {
        Scene scene;
        std::optional<RenderPlan> plan;
    };
    std::unique_ptr<Instant> prepare(long long i, AssetCache& cache, PrepareStats& assets) const {
        auto in = std::make_unique<Instant>();
        AnimatedScene::InstantAssets used;
        in->scene = anim.at(frames.at(i), cache, prepareOptions(a, distributed, motion), &used);
        cache.keepOnly(used.keys);  // what this frame needs stays cached, the rest goes
        assets.add(used.stats);
        applyOverrides(a, in->scene);
        shareMeshAccels(in->scene, cache);  // a rigid mesh's BVH built once for all frames
        in->plan.emplace(planRender(in->scene));
        return in;
    }
    // A frame without TAA: independent of every other frame.
    FinishedFrame renderOne(long long i, AssetCache& cache, PrepareStats& assets) const {
        const std::unique_ptr<Instant> in = prepare(i, cache, assets);
        const RenderPlan& plan = *in->plan;
        FinishedFrame f{i, Film(plan.camera.width, plan.camera.height, kept), {}};
        FrameView view{plan.camera};
        view.frame = static_cast<uint32_t>(frames.first + i);
        // Each rank's own GPU under --device (useGpuOfLocalRank), or its CPU.
        const std::unique_ptr<PlanRenderer> gpu = deviceRenderer(a, plan, i == 0);
        f.stats = renderImage(a, plan, f.film, "", !a.quiet && stderrIsTerminal(),
                              gpu ? gpu->frames() : nullptr);
        if (f.film.has(Aov::Motion)) {
            const double t = frames.at(i);
            f.film.motion =
                frameMotion(a, f.film, view, previousInstant(anim, a, t, fps), in->scene).motion;
        }
        return f;
    }
    // Whether a frame depends on the ones before it: TAA's history, or a mesh regenerated by RTSDF
    // with temporal accumulation (its history lives in the cache).
    bool sequential() const {
        if (a.taa) return true;
        for (const AssetRequest& r : anim.describeAt(frames.at(0)).assets)
            if (r.dynamic == AssetRequest::Dynamic::Rtsdf) return true;
        return false;
    }
};

std::string animationTotal(const Animation& job, double total, double renderSeconds,
                           const PrepareStats& assets, const std::string& taa) {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "sdftrace render: %lld frames (t = %.4g to %.4g s at %.4g fps) in %.3f s, "
                  "render %.3f s per frame; assets: %zu loaded, %zu baked, %zu reused%s\n",
                  job.frames.count, job.frames.at(0), job.frames.at(job.frames.count - 1), job.fps,
                  total, renderSeconds / static_cast<double>(job.frames.count), assets.loaded,
                  assets.baked, assets.cached, taa.c_str());
    return buf;
}

// The frames in order on this process, or (mpirun, sequential frames) on rank 0 with each frame's
// tiles rendered across the ranks by `across`: TAA blends each frame into the history
// reprojected by its motion vectors.
// Returns the TAA part of the total line.
std::string renderFramesInOrder(
    const Animation& job, FrameSink& sink, PrepareStats& assets,
    const std::function<FrameRenderFn(long long, const RenderPlan&)>& across) {
    const RenderArgs& a = job.a;
    AssetCache cache;
    std::optional<TemporalAccumulator> taa;
    if (a.taa) taa.emplace(a.taaAlpha.value_or(0.0f), true);
    size_t rejected = 0;
    for (long long i = 0; i < job.frames.count; ++i) {
        const double t = job.frames.at(i);
        const std::unique_ptr<Animation::Instant> in = job.prepare(i, cache, assets);
        const RenderPlan& plan = *in->plan;
        if (taa) setUpTaa(*taa, plan, i == 0);
        FinishedFrame f{i, Film(plan.camera.width, plan.camera.height, job.kept), {}};
        FrameView view{plan.camera};
        view.frame = static_cast<uint32_t>(job.frames.first + i);
        if (taa) frameJitter(static_cast<uint32_t>(i), view.pixelJitter);
        const bool progress = !a.quiet && stderrIsTerminal();
        const FrameRenderFn fn = across ? across(i, plan) : nullptr;
        f.stats = taa ? (fn ? fn(view, f.film, progress) : render(plan, view, f.film, progress))
                      : renderImage(a, plan, f.film, "", progress, fn);
        if (job.motion) {
            const MotionVectors mv =
                frameMotion(a, f.film, view, previousInstant(job.anim, a, t, job.fps), in->scene);
            if (f.film.has(Aov::Motion)) f.film.motion = mv.motion;
            if (taa) {
                taa->add(f.film, &mv);
                rejected += taa->rejected();
            }
        }
        sink.add(std::move(f));
    }
    return taaSummary(taa, rejected, job.frames.count);
}

// mpirun, frames independent of each other: whole frames dealt to the ranks, each rendering its
// own with all its threads and loading its own assets; rank 0 writes them as they arrive.
void renderFramesDealt(WorkFarm& farm, const Animation& job, FrameSink& sink,
                       PrepareStats& assets) {
    AssetCache cache;
    PrepareStats local;  // rank 0's own frames' (its thread), merged after the round
    Progress bar("frames", static_cast<uint64_t>(job.frames.count), showProgress(job.a));
    RoundPlan round;
    round.items = static_cast<int>(job.frames.count);
    round.local = [&](int first, int last) {
        for (int i = first; i < last; ++i) sink.add(job.renderOne(i, cache, local));
    };
    round.onResult = [&](int, int first, int last, ByteReader& in) {
        for (int i = first; i < last; ++i) {
            FinishedFrame f;
            f.index = i;
            f.stats = in.get<RenderStats>();
            assets.add(in.get<PrepareStats>());
            f.film = unpackFilm(in);
            for (const auto& [aov, path] : sink.aovs())
                if (!f.film.has(aov))
                    throw std::runtime_error("frame " + std::to_string(i) + " came without " +
                                             aovName(aov));
            sink.add(std::move(f));
        }
    };
    round.progress = &bar;
    farm.round(round);
    assets.add(local);
}

// The other ranks' side of renderFramesDealt.
class DealtFrameWorker : public RoundWorker {
  public:
    explicit DealtFrameWorker(const Animation& job) : m_job(job) {}
    void run(int first, int last, ByteWriter& out) override {
        for (int i = first; i < last; ++i) {
            PrepareStats st;
            const FinishedFrame f = m_job.renderOne(i, m_cache, st);
            out.put(f.stats);
            out.put(st);
            packFilm(f.film, out);
        }
    }

  private:
    const Animation& m_job;
    AssetCache m_cache;
};

// The other ranks' side of renderFramesInOrder under mpirun: each round renders tiles of frame i
// (its index leads the round's context). The frames' scenes are prepared here in the same order as
// on rank 0, so that RTSDF histories evolve alike; the next one while rank 0 prepares it too
// (after each round), so that the ranks prepare side by side.
class OrderedFrameWorker {
  public:
    explicit OrderedFrameWorker(const Animation& job) : m_job(job) {}
    std::unique_ptr<RoundWorker> start(const Bytes& context) {
        ByteReader in(context);
        const auto i = in.get<long long>();
        while (m_prepared < i) prepareNext();
        // Instants before i are done with (the --frames of one instant share it).
        m_instants.erase(m_instants.begin(), m_instants.lower_bound(i));
        return tileWorker(*m_instants.at(i)->plan, in);
    }
    void prepareNext() {
        if (m_prepared + 1 >= m_job.frames.count) return;
        PrepareStats unused;
        ++m_prepared;
        m_instants[m_prepared] = m_job.prepare(m_prepared, m_cache, unused);
    }

  private:
    const Animation& m_job;
    AssetCache m_cache;
    long long m_prepared = -1;
    std::map<long long, std::unique_ptr<Animation::Instant>> m_instants;
};

}  // namespace

int renderAnimation(const RenderArgs& a, const TimeSpan& span,
                    const std::vector<std::pair<Aov, std::string>>& aovs, Communicator& comm) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    std::optional<Animation> job;
    together(comm, [&] {
        AnimatedScene anim = loadAnimation(a.scene);
        const double fps = a.fps ? *a.fps : anim.time().fps;
        job.emplace(Animation{a, std::move(anim), fps, frameTimes(span, fps, a.time)});
    });
    unsigned kept = Film::bit(Aov::Color);
    for (const auto& [aov, path] : aovs) kept |= Film::bit(aov);
    job->motion = a.taa || (kept & Film::bit(Aov::Motion));
    if (job->motion) kept |= Film::bit(Aov::Depth);
    if (a.taa) kept |= Film::bit(Aov::Shadow);  // moving shadows reject their history
    job->kept = kept;
    job->distributed = comm.distributed();
    bool ordered = false;
    together(comm, [&] { ordered = job->sequential(); });
    if (comm.distributed() && !comm.root()) {
        if (ordered) {
            OrderedFrameWorker w(*job);
            // Frame 0 before the first round too: the ranks prepare side by side.
            serveRounds(
                comm, [&](const Bytes& c) { return w.start(c); }, [&] { w.prepareNext(); });
        } else {
            serveRounds(comm,
                        [&](const Bytes&) { return std::make_unique<DealtFrameWorker>(*job); });
        }
        return 0;
    }
    std::optional<VideoSink> video;
    if (a.outputFlag && a.outputFlag->count() > 0) video.emplace(a.output, job->fps);
    FrameSink sink(a, aovs, job->frames, video);
    PrepareStats assets;
    std::string taaText;
    if (!comm.distributed()) {
        // --device: each frame's plan uploaded to the GPU (or the CPU renders it).
        std::unique_ptr<PlanRenderer> gpu;
        taaText = renderFramesInOrder(*job, sink, assets,
                                      [&](long long i, const RenderPlan& plan) -> FrameRenderFn {
                                          gpu = deviceRenderer(a, plan, i == 0);
                                          return gpu ? gpu->frames() : nullptr;
                                      });
    } else {
        WorkFarm farm(comm);
        if (ordered) {
            // Frames that depend on the ones before: each on rank 0's GPU, or its tiles across
            // the ranks' CPUs.
            std::unique_ptr<PlanRenderer> gpu;
            taaText = renderFramesInOrder(
                *job, sink, assets, [&](long long i, const RenderPlan& plan) -> FrameRenderFn {
                    gpu = deviceRenderer(a, plan, i == 0);
                    if (gpu) return gpu->frames();
                    return [&farm, &plan, i](const FrameView& view, Film& film, bool progress) {
                        ByteWriter prefix;
                        prefix.put(i);
                        return renderAcross(farm, plan, view, film, progress,
                                            std::move(prefix.bytes()));
                    };
                });
        } else {
            renderFramesDealt(farm, *job, sink, assets);
        }
        farm.end();
    }
    if (video && video->writer) video->writer->finish();
    const double total = std::chrono::duration<double>(Clock::now() - start).count();
    std::fputs(animationTotal(*job, total, sink.renderSeconds(), assets, taaText).c_str(), stderr);
    return 0;
}

}  // namespace sdft::cli
